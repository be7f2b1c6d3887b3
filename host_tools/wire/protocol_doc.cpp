// geojcbb_protocol_doc: docs/protocol.md's message byte tables, rendered from the messages' own
// descriptions (protocol/include/geojcbb/protocol/messages.hpp, fields()): the same list that the
// encoder, the decoder, the validators and the schema hash come from. The tables live between two
// marker lines in docs/protocol.md.
//   geojcbb_protocol_doc                 prints the generated block
//   geojcbb_protocol_doc --check FILE    fails (exit 1) when FILE's block differs (CTest protocol.docs_current)
//   geojcbb_protocol_doc --update FILE   rewrites FILE's block (CMake target protocol_docs)
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "geojcbb/protocol/protocol.hpp"
#include "geojcbb_host/generated_block.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {

using namespace geojcbb::proto;

constexpr const char* kBegin =
    "<!-- BEGIN GENERATED: message tables (geojcbb_protocol_doc --update docs/protocol.md; do not edit) -->";
constexpr const char* kEnd = "<!-- END GENERATED: message tables -->";

std::string hex2(unsigned v) {
  char b[8];
  std::snprintf(b, sizeof b, "0x%02X", v);
  return b;
}

std::string range_text(const FieldInfo& f) {
  FixedText<64> t{};
  render_range(t, f);
  return std::string(t.data.data(), t.size);
}
std::string type_text(const FieldInfo& f) {
  FixedText<16> t{};
  render_type(t, f);
  return std::string(t.data.data(), t.size);
}

/// "valid" column: the schema's range, then the description's note.
std::string valid_text(const FieldInfo& f) {
  const std::string r = range_text(f);
  std::string out = r.empty() ? "any" : "`" + r + "`";
  if (f.note[0] != '\0') out += "; " + std::string(f.note);
  // A '|' ends a markdown table cell, even inside a code span.
  std::string escaped;
  for (const char c : out) escaped += c == '|' ? std::string("\\|") : std::string(1, c);
  return escaped;
}

template <class M>
void render_message(std::ostream& os) {
  const auto infos = field_infos<M>();
  const bool list = M::kItemSize > 0;
  os << "**" << M::kName << " (" << hex2(static_cast<unsigned>(M::kType)) << "), ";
  if (list) {
    os << M::kFixedSize << " + " << M::kItemSize << "·count bytes**";
  } else {
    os << M::kFixedSize << (M::kFixedSize == 1 ? " byte**" : " bytes**");
  }
  if (infos.empty()) {
    os << ": no fields.\n\n";
    return;
  }
  os << "\n\n| offset | size | type | field | unit | valid |\n| ---: | ---: | --- | --- | --- | --- |\n";
  std::size_t offset = 0;  // fixed part
  std::size_t item_offset = 0;
  for (const FieldInfo& f : infos) {
    const bool floats = f.type == WireType::kF32 && f.count > 1;
    const std::size_t n = floats ? f.count : 1;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t size = floats ? wire_size(f.type) : f.bytes();
      std::string off;
      if (f.item) {
        off = std::to_string(M::kFixedSize + item_offset) + " + " + std::to_string(M::kItemSize) + "i";
        item_offset += size;
      } else {
        off = std::to_string(offset);
        offset += size;
      }
      std::string field = "`" + (f.item ? std::string(f.items_name) + "[i]." : std::string()) + f.name +
                          (floats ? "[" + std::to_string(k) + "]" : std::string()) + "`";
      if (floats && f.elem_names != nullptr) field += " " + std::string(f.elem_names[k]);
      os << "| " << off << " | " << size << " | " << type_text(f) << " | " << field << " | "
         << (f.unit[0] != '\0' ? f.unit : "") << " | " << (k == 0 ? valid_text(f) : "as above") << " |\n";
    }
  }
  const std::string item_rule = item_rule_of<M>();
  const std::string rule = rule_of<M>();
  if (!item_rule.empty()) os << "\nEach item, after its fields: `" << item_rule << "`.\n";
  if (!rule.empty()) os << "\nAfter the fields: `" << rule << "`.\n";
  os << "\n";
}

template <class... M>
std::string render_all(MessageList<M...>) {
  std::ostringstream os;
  os << kBegin << "\n\n";
  os << "| type | name | payload bytes |\n| --- | --- | ---: |\n";
  ((os << "| " << hex2(static_cast<unsigned>(M::kType)) << " | " << M::kName << " | "
       << (M::kItemSize > 0 ? std::to_string(M::kFixedSize) + " + " + std::to_string(M::kItemSize) + "·count"
                            : std::to_string(M::kFixedSize))
       << " |\n"),
   ...);
  os << "\nSchema hash (`kSchemaHash`, FNV-1a 32 of `kSchemaText`): **" << [] {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08X", static_cast<unsigned>(kSchemaHash));
    return std::string(b);
  }() << "**.\n\n";
  (render_message<M>(os), ...);
  os << kEnd << "\n";
  return os.str();
}

/// Splits text around the generated block: [0, b) before, [b, e) the block with its markers and
/// the newline after the end marker, [e, size) after. False when the markers are missing.
}  // namespace

namespace {

int run(int argc, char** argv) {
  const geojcbb::host::GeneratedBlock g{kBegin, kEnd, "message tables",
                                        "cmake --build build/host-release --target protocol_docs"};
  return geojcbb::host::generated_block_main(
      argc, argv, "docs/protocol.md's message tables from the protocol's message descriptions", g,
      render_all(AllMessages<>{}));
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
