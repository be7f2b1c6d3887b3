// geojcbb_uart_check: the host side of the firmware's QEMU smoke test (toolchains/check_firmware.cmake,
// MODE=qemu), with the protocol library's own Decoder and message decoders.
//   --session FILE --write-input OUT [--lead-delimiters N]
//       writes the session's bytes (FILE: hex lines, '#' comments, one "# replies: tt tt ..." line of
//       the expected reply types) to OUT, after N 0x00 delimiters (empty frames; the node ignores them)
//   --session FILE --output UART [--max-stack BYTES]
//       checks what the firmware wrote to its UART: every byte belongs to a frame that passes the
//       Decoder (COBS, length, CRC-32C, version, flags) and decodes as a valid message of a known type;
//       the reply types equal the session's, in order. Prints the last STATS and fails when its stack
//       high-water mark exceeds BYTES.
// Exit status: 0 pass, 1 check failed, 2 usage or file error.
#include <CLI/CLI.hpp>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "geojcbb/protocol/protocol.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {

using namespace geojcbb::proto;

struct Session {
  std::vector<std::uint8_t> bytes;
  std::vector<std::string> replies;  ///< expected reply types, two hex digits each
};

bool read_session(const std::string& path, Session& s) {
  std::ifstream in(path);
  if (!in) {
    std::cerr << "cannot read " << path << "\n";
    return false;
  }
  std::string line;
  const std::string tag = "# replies:";
  while (std::getline(in, line)) {
    if (line.compare(0, tag.size(), tag) == 0) {
      std::istringstream ls(line.substr(tag.size()));
      std::string t;
      while (ls >> t) s.replies.push_back(t);
      continue;
    }
    if (!line.empty() && line[0] == '#') continue;
    std::istringstream ls(line);
    std::string h;
    while (ls >> h) {
      if (h.size() != 2 || h.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos) {
        std::cerr << path << ": not a hex byte: '" << h << "'\n";
        return false;
      }
      s.bytes.push_back(static_cast<std::uint8_t>(std::stoul(h, nullptr, 16)));
    }
  }
  if (s.replies.empty() || s.bytes.empty()) {
    std::cerr << path << ": no '# replies:' line or no bytes\n";
    return false;
  }
  return true;
}

std::string hex2(unsigned v) {
  char b[4];
  std::snprintf(b, sizeof b, "%02x", v & 0xFFu);
  return b;
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& x : v) out += (out.empty() ? "" : " ") + x;
  return out;
}

/// The STATS fields by name, from the message's own description.
void print_stats(const Stats& s) {
  std::array<std::uint8_t, Stats::kMaxPayloadSize> p{};
  std::size_t n = 0;
  if (s.encode(p, n) != Error::kOk) return;
  std::cout << "STATS from the device:\n";
  std::size_t off = 0;
  for (const FieldInfo& f : field_infos<Stats>()) {  // all u32
    std::cout << "  " << f.name << " = " << get_u32_le(p.data() + off) << "\n";
    off += f.bytes();
  }
}

int check_output(const Session& s, const std::string& path, std::optional<std::uint32_t> max_stack) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::cerr << "cannot read " << path << "\n";
    return 2;
  }
  const std::vector<std::uint8_t> out((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Decoder d;
  std::vector<std::string> types;
  std::optional<Stats> stats;
  for (std::size_t i = 0; i < out.size(); ++i) {
    FrameView f;
    const Error e = d.push(out[i], f);
    if (e == Error::kIncomplete) continue;
    if (e != Error::kOk) {
      std::cerr << "a bad frame in the firmware's output (" << to_string(e) << ", ending at byte " << i << ")\n";
      return 1;
    }
    const Error m = dispatch(f, [&](const auto& msg) {
      using M = std::decay_t<decltype(msg)>;
      if constexpr (std::is_same_v<M, Stats>) stats = msg;
    });
    if (m != Error::kOk) {
      std::cerr << "a frame of type 0x" << hex2(f.type) << " in the firmware's output does not decode (" << to_string(m)
                << ")\n";
      return 1;
    }
    types.push_back(hex2(f.type));
  }
  if (d.pending() != 0) {
    std::cerr << "the firmware's output ends inside a frame (" << d.pending() << " bytes after the last delimiter)\n";
    return 1;
  }
  std::cout << out.size() << " bytes out, replies: " << join(types) << "\n";
  if (types != s.replies) {
    std::cerr << "replies differ from the session's\n  expected: " << join(s.replies) << "\n  got:      " << join(types)
              << "\n";
    return 1;
  }
  if (stats) {
    print_stats(*stats);
    if (max_stack && stats->stack_high_water_bytes > *max_stack) {
      std::cerr << "stack high-water mark " << stats->stack_high_water_bytes << " B exceeds " << *max_stack << " B\n";
      return 1;
    }
  }
  return 0;
}

}  // namespace

namespace {

int run(int argc, char** argv) {
  CLI::App app{"The QEMU smoke session: its input bytes, and the check of the firmware's UART output"};
  std::string session_path;
  std::string input_path;
  std::string output_path;
  int lead = 0;
  std::uint32_t max_stack = 0;
  app.add_option("--session", session_path, "session file (hex bytes and a '# replies:' line)")->required();
  auto* write = app.add_option("--write-input", input_path, "write the session's bytes here");
  auto* check = app.add_option("--output", output_path, "check the firmware's UART output in this file");
  app.add_option("--lead-delimiters", lead, "0x00 bytes before the session (--write-input)")
      ->check(CLI::Range(0, 1 << 20));
  auto* stack = app.add_option("--max-stack", max_stack, "largest stack high-water mark in STATS, bytes (--output)");
  write->excludes(check);
  CLI11_PARSE(app, argc, argv);

  Session s;
  if (!read_session(session_path, s)) return 2;
  if (!input_path.empty()) {
    std::ofstream f(input_path, std::ios::binary | std::ios::trunc);
    const std::vector<char> zeros(static_cast<std::size_t>(lead), '\0');
    f.write(zeros.data(), static_cast<std::streamsize>(zeros.size()));
    f.write(reinterpret_cast<const char*>(s.bytes.data()), static_cast<std::streamsize>(s.bytes.size()));
    if (!f) {
      std::cerr << "cannot write " << input_path << "\n";
      return 2;
    }
    std::cout << lead + static_cast<int>(s.bytes.size()) << " bytes to " << input_path << " (" << lead
              << " leading delimiters)\n";
    return 0;
  }
  if (!output_path.empty()) {
    return check_output(s, output_path, *stack ? std::optional<std::uint32_t>(max_stack) : std::nullopt);
  }
  std::cerr << "give --write-input or --output\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
