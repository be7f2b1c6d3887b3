// core: the settings of one SLAM step (association and filter) as one plain struct, generated from
// the option table (core/options.h): each member, its default, its range check and its description
// come from the option's one line there. SlamStep::configure, make_strategy, the wire's CONFIG, the C
// API, Python and the command-line tools all take this struct; nothing copies its fields one by one.
// No heap; the struct is a literal type, so defaults can be compared at compile time.
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>

#include "geojcbb/core/options.h"

namespace geojcbb {

enum class Strategy : std::uint8_t { kIcnn, kJcbb, kKjcbb, kDfjcbb, kGemjcbb, kGeojcbb, kPcjcbb };
constexpr int kStrategyCount = 7;
/// The papers' six (ICNN .. GEOJCBB); PCJCBB is this project's preset (docs/consistency.md).
constexpr int kPaperStrategyCount = 6;

constexpr const char* to_string(Strategy s) {
  switch (s) {
    case Strategy::kIcnn: return "ICNN";
    case Strategy::kJcbb: return "JCBB";
    case Strategy::kKjcbb: return "KJCBB";
    case Strategy::kDfjcbb: return "DFJCBB";
    case Strategy::kGemjcbb: return "GEMJCBB";
    case Strategy::kGeojcbb: return "GEOJCBB";
    case Strategy::kPcjcbb: return "PCJCBB";
  }
  return "?";
}

/// Reads a strategy's name, case-insensitive, with an optional "+V" that switches the pairwise
/// verification into the preset ("JCBB+V"; PCJCBB has it always): the one parser of the
/// command-line tools, the link, the QEMU harness and Python. Bounds: 7 names of <= 8 characters.
/// @return true and s, verify set; false (nothing written) for any other text.
inline bool parse_strategy(const char* text, Strategy& s, bool& verify) {
  auto upper = [](char c) { return c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c; };
  for (int k = 0; k < kStrategyCount; ++k) {  // <= kStrategyCount
    const char* name = to_string(static_cast<Strategy>(k));
    int i = 0;
    while (name[i] != '\0' && upper(text[i]) == name[i]) ++i;  // <= 8 characters
    if (name[i] != '\0') continue;
    const bool plain = text[i] == '\0';
    const bool plus_v = text[i] == '+' && upper(text[i + 1]) == 'V' && text[i + 2] == '\0';
    if (!plain && !plus_v) continue;
    s = static_cast<Strategy>(k);
    verify = plus_v;
    return true;
  }
  return false;
}

namespace options {

/// The C++ type of each TYPE token of the table; REAL is the pipeline's scalar.
template <typename T>
struct Types {
  using STRATEGY = Strategy;
  using F64 = double;
  using REAL = T;
  using F32 = float;
  using INT = int;
  using U32 = std::uint32_t;
  using BOOL = bool;
};

enum class RangeKind : std::uint8_t { kANY, kGT, kGE, kOPEN, kLOPEN, kROPEN, kCLOSED };

/// An option's domain, as the table's (kind, lo, hi).
struct Range {
  RangeKind kind = RangeKind::kANY;
  double lo = 0, hi = 0;
  /// x lies in the domain (a bounded kind also needs x finite; NaN is in no bounded domain).
  [[nodiscard]] bool contains(double x) const {
    if (kind == RangeKind::kANY) return true;
    if (!std::isfinite(x)) return false;
    switch (kind) {
      case RangeKind::kGT: return x > lo;
      case RangeKind::kGE: return x >= lo;
      case RangeKind::kOPEN: return x > lo && x < hi;
      case RangeKind::kLOPEN: return x > lo && x <= hi;
      case RangeKind::kROPEN: return x >= lo && x < hi;
      case RangeKind::kCLOSED: return x >= lo && x <= hi;
      case RangeKind::kANY: break;
    }
    return true;
  }
};

constexpr double as_double(Strategy s) { return static_cast<int>(s); }
template <typename V>
constexpr double as_double(V v) {
  return static_cast<double>(v);
}

/// One line of the table, as text and range (the docs table, the CLI, Python's keywords).
struct Info {
  const char* type;          ///< the TYPE token: STRATEGY, F64, REAL, F32, INT, U32, BOOL
  const char* name;          ///< the member's name (C, C++, Python keyword)
  const char* default_text;  ///< the default as written in the table
  Range range;
  const char* unit;
  const char* cli;  ///< geojcbb_eval's option ("": set by the host)
  const char* meaning;
};

// The texts for people (unit, option, meaning) only where something reads them: a device build
// (GEOJCBB_DOC_TEXT=0, protocol/CMakeLists.txt) keeps them out of flash.
#ifndef GEOJCBB_DOC_TEXT
#define GEOJCBB_DOC_TEXT 1
#endif
#define GEOJCBB_OPT_RANGE(kind, lo, hi) \
  Range { RangeKind::k##kind, static_cast<double>(lo), static_cast<double>(hi) }
/// A text for people, or "" in a device build (the literal is then never emitted).
constexpr const char* doc_text(const char* text) { return GEOJCBB_DOC_TEXT ? text : ""; }
#define GEOJCBB_OPT_INFO(TYPE, name, def, range, unit, cli, doc) \
  Info{#TYPE, #name, #def, GEOJCBB_OPT_RANGE range, doc_text(unit), doc_text(cli), doc_text(doc)},
/// Every option, in the table's order.
inline constexpr Info kInfo[] = {GEOJCBB_OPTIONS(GEOJCBB_OPT_INFO)};
#undef GEOJCBB_OPT_INFO

#define GEOJCBB_OPT_INDEX(TYPE, name, def, range, unit, cli, doc) k_##name,
/// An option's index into kInfo.
enum Index : int { GEOJCBB_OPTIONS(GEOJCBB_OPT_INDEX) kCount };
#undef GEOJCBB_OPT_INDEX

constexpr bool same_name(const char* a, const char* b) {
  while (*a != '\0' && *a == *b) {  // <= the shorter name's length
    ++a;
    ++b;
  }
  return *a == *b;
}
/// The index of the option called `name`, or -1 (compile-time lookups: the wire's CONFIG fields).
constexpr int index_of(const char* name) {
  for (int i = 0; i < kCount; ++i) {  // <= kCount
    if (same_name(kInfo[i].name, name)) return i;
  }
  return -1;
}

/// A value of one option between its C++ type and another representation (the wire's, C's): enums
/// through their integer, bool as != 0, numbers by static_cast.
template <class To, class From>
constexpr To convert(From v) {
  if constexpr (std::is_enum<To>::value || std::is_enum<From>::value) {
    return static_cast<To>(static_cast<int>(v));
  } else if constexpr (std::is_same<To, bool>::value) {
    return v != From(0);
  } else {
    return static_cast<To>(v);
  }
}

/// Member I of a settings struct (I an options::Index): Member<I>::get(s).
template <int I>
struct Member;
#define GEOJCBB_OPT_MEMBER_AT(TYPE, name, def, range, unit, cli, doc) \
  template <>                                                         \
  struct Member<k_##name> {                                           \
    template <class S>                                                \
    static constexpr auto& get(S& s) {                                \
      return s.name;                                                  \
    }                                                                 \
  };
GEOJCBB_OPTIONS(GEOJCBB_OPT_MEMBER_AT)
#undef GEOJCBB_OPT_MEMBER_AT

}  // namespace options

/// The settings of one SLAM step: every option of core/options.h, with its default.
template <typename T>
struct StepSettings {
#define GEOJCBB_OPT_MEMBER(TYPE, name, def, range, unit, cli, doc) \
  typename options::Types<T>::TYPE name = static_cast<typename options::Types<T>::TYPE>(def);
  GEOJCBB_OPTIONS(GEOJCBB_OPT_MEMBER)
#undef GEOJCBB_OPT_MEMBER
};

/// Calls f(info, member) for every option of s, in the table's order (the CLI, Python's keywords,
/// the tests' comparisons). Bound: options::kCount calls.
template <typename S, typename F>
void for_each_option(S& s, F&& f) {
#define GEOJCBB_OPT_VISIT(TYPE, name, def, range, unit, cli, doc) f(options::kInfo[options::k_##name], s.name);
  GEOJCBB_OPTIONS(GEOJCBB_OPT_VISIT)
#undef GEOJCBB_OPT_VISIT
}

/// Calls f(info, a_member, b_member) for every option, the same option of two settings.
template <typename S, typename R, typename F>
void for_each_option_pair(S& a, R& b, F&& f) {
#define GEOJCBB_OPT_VISIT2(TYPE, name, def, range, unit, cli, doc) f(options::kInfo[options::k_##name], a.name, b.name);
  GEOJCBB_OPTIONS(GEOJCBB_OPT_VISIT2)
#undef GEOJCBB_OPT_VISIT2
}

/// A stage's own option struct (ekf::LandmarkPolicy, reloc::AlignOptions, ...) takes the table's
/// options through one list next to the struct, NAME_OPTIONS(F) with F(member, option) per member,
/// and bind_options expands it: every member is assigned its option by generated code, never by a
/// hand-written copy. An option the table does not have, or a member whose type is not the option's
/// (a silent conversion), fails to compile. Used inside a function with `in` (the settings, or a
/// struct that inherits them) and `out` (the stage's struct).
#define GEOJCBB_BIND_OPTION(member, option)                                                                 \
  static_assert(std::is_same<std::decay_t<decltype(out.member)>, std::decay_t<decltype(in.option)>>::value, \
                #member " has the type of the option " #option);                                            \
  out.member = in.option;

/// Every option within its range, and max_range_m > min_range_m. Capacity limits are make_strategy's.
template <typename T>
[[nodiscard]] bool in_range(const StepSettings<T>& s) {
  bool ok = true;
  for_each_option(
      s, [&ok](const options::Info& info, const auto& v) { ok = ok && info.range.contains(options::as_double(v)); });
  return ok && s.max_range_m > s.min_range_m;
}

/// Member-wise equality (Python reuses a configuration while its settings stay the same).
template <typename T>
bool same_settings(const StepSettings<T>& a, const StepSettings<T>& b) {
#define GEOJCBB_OPT_SAME(TYPE, name, def, range, unit, cli, doc) &&a.name == b.name
  return true GEOJCBB_OPTIONS(GEOJCBB_OPT_SAME);
#undef GEOJCBB_OPT_SAME
}

}  // namespace geojcbb
