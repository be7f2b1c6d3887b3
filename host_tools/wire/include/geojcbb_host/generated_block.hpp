// host_tools/wire: a block of a Markdown file that a program renders (docs/protocol.md's message
// tables, docs/options.md's option table), between two marker lines. One command line for each
// such program: no option prints the block; --check FILE fails (exit 1) when FILE's block differs
// (a CTest keeps the docs current); --update FILE rewrites it.
#pragma once

#include <CLI/CLI.hpp>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

namespace geojcbb::host {

struct GeneratedBlock {
  const char* begin;       ///< the marker line before the block
  const char* end;         ///< the marker line after it
  const char* what;        ///< "message tables", "option table"
  const char* regenerate;  ///< the command that rewrites it, for the stale message
};

/// The block's text in `text`: [b, e) from the begin marker through the end marker's line.
inline bool find_block(const std::string& text, const GeneratedBlock& g, std::size_t& b, std::size_t& e) {
  b = text.find(g.begin);
  const std::size_t end = text.find(g.end);
  if (b == std::string::npos || end == std::string::npos || end < b) return false;
  e = end + std::string(g.end).size();
  if (e < text.size() && text[e] == '\n') ++e;
  return true;
}

/// The program's main: parses --check / --update and prints, checks or rewrites `block`.
inline int generated_block_main(int argc, char** argv, const char* title, const GeneratedBlock& g,
                                const std::string& block) {
  CLI::App app{title};
  std::string check;
  std::string update;
  app.add_option("--check", check, "fail when this file's generated block is stale");
  app.add_option("--update", update, "rewrite this file's generated block");
  CLI11_PARSE(app, argc, argv);
  if (check.empty() && update.empty()) {
    std::cout << block;
    return 0;
  }
  const std::string& path = check.empty() ? update : check;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::cerr << "cannot read " << path << "\n";
    return 2;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::size_t b = 0;
  std::size_t e = 0;
  if (!find_block(text, g, b, e)) {
    std::cerr << path << ": no generated block (marker lines '" << g.begin << "' and '" << g.end << "')\n";
    return 2;
  }
  const std::string current = text.substr(b, e - b);
  if (!check.empty()) {
    if (current == block) {
      std::cout << path << ": " << g.what << " current\n";
      return 0;
    }
    std::size_t i = 0;
    while (i < current.size() && i < block.size() && current[i] == block[i]) ++i;
    const std::size_t line =
        1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(b + i), '\n'));
    std::cerr << path << ": the " << g.what << " are stale (first difference at line " << line << "); regenerate with `"
              << g.regenerate << "`\n"
              << "  file:      " << current.substr(i, current.find('\n', i) - i) << "\n"
              << "  generated: " << block.substr(i, block.find('\n', i) - i) << "\n";
    return 1;
  }
  if (current == block) {
    std::cout << path << ": already current\n";
    return 0;
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text.substr(0, b) << block << text.substr(e);
  if (!out) {
    std::cerr << "cannot write " << path << "\n";
    return 2;
  }
  std::cout << path << ": " << g.what << " rewritten\n";
  return 0;
}

}  // namespace geojcbb::host
