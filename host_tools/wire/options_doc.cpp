// geojcbb_options_doc: docs/options.md's option table, rendered from the option table itself
// (protocol/include/geojcbb/core/options.h, through core/settings.hpp) and from CONFIG's field
// list (node/wire.hpp, carried_by_config: which options a device receives), and the Python stub's option keywords
// (host_tools/python/geojcbb/_core.pyi, class Options; chosen by a FILE ending in .pyi). Each
// lives between two marker lines.
//   geojcbb_options_doc                 prints the generated block (the Markdown table)
//   geojcbb_options_doc --check FILE    fails (exit 1) when FILE's block differs (CTest options.docs_current,
//                                       options.stub_current)
//   geojcbb_options_doc --update FILE   rewrites FILE's block (CMake target options_docs)
#include <sstream>
#include <string>

#include "geojcbb/core/settings.hpp"
#include "geojcbb/node/node.hpp"
#include "geojcbb_host/generated_block.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {

using namespace geojcbb;

constexpr const char* kBegin =
    "<!-- BEGIN GENERATED: option table (geojcbb_options_doc --update docs/options.md; do not edit) -->";
constexpr const char* kEnd = "<!-- END GENERATED: option table -->";
constexpr const char* kStubBegin =
    "    # BEGIN GENERATED: option keywords (cmake --build build/host-release --target options_docs; do not edit)";
constexpr const char* kStubEnd = "    # END GENERATED: option keywords";

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string range_text(const options::Range& r) {
  const std::string lo = num(r.lo), hi = num(r.hi);
  switch (r.kind) {
    case options::RangeKind::kANY: return "any";
    case options::RangeKind::kGT: return "> " + lo;
    case options::RangeKind::kGE: return ">= " + lo;
    case options::RangeKind::kOPEN: return "(" + lo + ", " + hi + ")";
    case options::RangeKind::kLOPEN: return "(" + lo + ", " + hi + "]";
    case options::RangeKind::kROPEN: return "[" + lo + ", " + hi + ")";
    case options::RangeKind::kCLOSED: return "[" + lo + ", " + hi + "]";
  }
  return "?";
}

std::string render() {
  std::ostringstream os;
  os << kBegin << "\n\n";
  os << "| option | type | default | range | unit | `geojcbb_eval` | CONFIG | meaning |\n";
  os << "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (int i = 0; i < options::kCount; ++i) {
    const options::Info& o = options::kInfo[i];
    const std::string cli = o.cli[0] != '\0' ? std::string("`") + o.cli + "`" : std::string("(host)");
    os << "| `" << o.name << "` | " << o.type << " | " << o.default_text << " | " << range_text(o.range) << " | "
       << o.unit << " | " << cli << " | " << (node::carried_by_config(i) ? "yes" : "**no**") << " | " << o.meaning
       << " |\n";
  }
  os << "\n" << options::kCount << " options. " << kEnd << "\n";
  return os.str();
}

/// The stub's keywords: every option but the strategy (a positional argument), with its Python type.
std::string render_stub() {
  std::ostringstream os;
  os << kStubBegin << "\n";
  for (int i = 0; i < options::kCount; ++i) {
    const options::Info& o = options::kInfo[i];
    const std::string type = o.type;
    if (type == "STRATEGY") continue;
    const char* py = type == "BOOL" ? "bool" : (type == "INT" || type == "U32") ? "int" : "float";
    os << "    " << o.name << ": " << py << "  # default " << o.default_text << "\n";
  }
  os << kStubEnd << "\n";
  return os.str();
}

int run(int argc, char** argv) {
  bool stub = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    stub = stub || (a.size() > 4 && a.compare(a.size() - 4, 4, ".pyi") == 0);
  }
  const char* regenerate = "cmake --build build/host-release --target options_docs";
  if (stub) {
    const host::GeneratedBlock g{kStubBegin, kStubEnd, "option keywords", regenerate};
    return host::generated_block_main(argc, argv, "the Python stub's option keywords from core/options.h", g,
                                      render_stub());
  }
  const host::GeneratedBlock g{kBegin, kEnd, "option table", regenerate};
  return host::generated_block_main(argc, argv, "docs/options.md's option table from core/options.h", g, render());
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
