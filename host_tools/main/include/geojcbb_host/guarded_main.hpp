// host_tools: every host program's main() runs its body through guarded_main(), so an exception
// that nothing below handled (a file that cannot be read, a bad option value, std::bad_alloc) ends
// the program with "<program>: error: <what>" and exit status 1, not std::terminate's abort.
#pragma once

#include <cstdio>
#include <exception>

namespace geojcbb::host {

/// @return body(argc, argv), or 1 after printing the escaping exception to stderr.
template <class Body>
int guarded_main(Body&& body, int argc, char** argv) noexcept {
  const char* program = argc > 0 && argv[0] != nullptr ? argv[0] : "geojcbb";
  try {
    return body(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
  } catch (...) {
    std::fprintf(stderr, "%s: error: an unknown exception\n", program);
  }
  return 1;
}

}  // namespace geojcbb::host
