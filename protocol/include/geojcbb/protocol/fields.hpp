// protocol: the one description of a message, and everything derived from it. A message (or a list
// item) lists its fields once, in wire order, in a constexpr fields(): name, member, valid range, unit
// and a note for the docs. Codec<M> derives from that list the payload sizes, write (encode), read
// (decode), validate, and field_infos<M>(), the flat table from which the schema text (hence the
// schema hash, schema.hpp) and docs/protocol.md's byte tables are rendered. A counted list ("count:u8
// + array of struct") is one List descriptor, last in the list; its items describe themselves the same
// way. Rules that tie fields together (positive definiteness, max > min) are a record's rule(), named
// by its kRule (the name is part of the schema text). Bounds: every loop runs over a field list (a
// compile-time length) or a list's count (<= its capacity). No heap, no recursion at run time.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <tuple>
#include <type_traits>
#include <utility>

#include "geojcbb/protocol/error.hpp"

// The descriptors' texts for people (units, notes) are for the docs and the host's tools only; a
// device build (GEOJCBB_DOC_TEXT=0, set for cross builds by protocol/CMakeLists.txt) keeps them out
// of flash. Neither is part of the schema text, so the schema hash is the same either way.
#ifndef GEOJCBB_DOC_TEXT
#define GEOJCBB_DOC_TEXT 1
#endif
#include "geojcbb/protocol/frame.hpp"
#include "geojcbb/protocol/wire.hpp"

namespace geojcbb::proto {

/// pi rounded to float (3.14159274f, a little above pi): the bound of bearings and fields of view.
constexpr float kPiF = 3.14159265358979323846f;

/// Wire types: little-endian integers, IEEE-754 binary32, and text (cN: N bytes, printable ASCII then
/// zero padding).
enum class WireType : std::uint8_t { kU8, kU16, kU32, kI32, kF32, kText };

constexpr std::size_t wire_size(WireType t) {
  switch (t) {
    case WireType::kU8: return 1;
    case WireType::kU16: return 2;
    case WireType::kU32:
    case WireType::kI32:
    case WireType::kF32: return 4;
    case WireType::kText: return 1;  // per character
  }
  return 0;
}
constexpr const char* wire_name(WireType t) {
  switch (t) {
    case WireType::kU8: return "u8";
    case WireType::kU16: return "u16";
    case WireType::kU32: return "u32";
    case WireType::kI32: return "i32";
    case WireType::kF32: return "f32";
    case WireType::kText: return "c";  // followed by the length: c16
  }
  return "?";
}

/// A field's valid range. Integers (enums and bool by their value): kInt [lo, hi], kOneOf lo or hi.
/// Floats: always finite (+Inf too when plus_inf), then the optional bounds. kText: printable ASCII
/// (0x20-0x7E), then zero padding only. kCount: a list's count, at most the receiver's capacity.
/// The same value gives the check (in_range) and its text (render_range): one source.
/// The small members first: 32 bytes, not 40 (every field's descriptor is in the device's flash).
struct Range {
  enum class Kind : std::uint8_t { kAny, kInt, kOneOf, kFloat, kText, kCount };
  Kind kind = Kind::kAny;
  bool has_lo = false;
  bool has_hi = false;
  bool lo_open = false;
  bool hi_open = false;
  bool plus_inf = false;
  float flo = 0.0f;
  float fhi = 0.0f;
  std::int64_t lo = 0;
  std::int64_t hi = 0;
};

namespace range {
constexpr std::int64_t kNoMax = std::numeric_limits<std::int64_t>::max();
constexpr Range any() { return Range{}; }
constexpr Range integers(Range::Kind kind, std::int64_t lo, std::int64_t hi) {
  Range r{kind};
  r.lo = lo;
  r.hi = hi;
  return r;
}
constexpr Range at_least(std::int64_t lo) { return integers(Range::Kind::kInt, lo, kNoMax); }
constexpr Range between(std::int64_t lo, std::int64_t hi) { return integers(Range::Kind::kInt, lo, hi); }
constexpr Range one_of(std::int64_t a, std::int64_t b) { return integers(Range::Kind::kOneOf, a, b); }
constexpr Range text() { return Range{Range::Kind::kText}; }
constexpr Range count() { return Range{Range::Kind::kCount}; }
/// f32: finite.
constexpr Range finite() { return Range{Range::Kind::kFloat}; }
/// f32: finite, >= lo (or > lo when open).
constexpr Range lower_bound(float lo, bool open) {
  Range r{Range::Kind::kFloat};
  r.flo = lo;
  r.has_lo = true;
  r.lo_open = open;
  return r;
}
/// f32: finite, >= lo.
constexpr Range not_below(float lo) { return lower_bound(lo, false); }
/// f32: finite, > lo.
constexpr Range above(float lo) { return lower_bound(lo, true); }
/// f32: finite, in [lo, hi], '(' / ']' by lo_open / hi_open.
constexpr Range interval(float lo, float hi, bool lo_open, bool hi_open) {
  Range r = lower_bound(lo, lo_open);
  r.fhi = hi;
  r.has_hi = true;
  r.hi_open = hi_open;
  return r;
}
/// The same range, also accepting +Inf.
constexpr Range or_plus_inf(Range r) {
  r.plus_inf = true;
  return r;
}
}  // namespace range

/// Float check: kNonFinite for NaN, -Inf, and +Inf unless allowed; then kOutOfRange or kOk.
inline Error check_float(const Range& r, float v) {
  if (is_nan(v) || (!is_finite(v) && !(r.plus_inf && is_pos_inf(v)))) return Error::kNonFinite;
  if (!is_finite(v)) return Error::kOk;  // +Inf, allowed: above every lower bound, no upper bound
  if (r.has_lo && (r.lo_open ? !(v > r.flo) : !(v >= r.flo))) return Error::kOutOfRange;
  if (r.has_hi && (r.hi_open ? !(v < r.fhi) : !(v <= r.fhi))) return Error::kOutOfRange;
  return Error::kOk;
}
/// Integer check (kInt, kOneOf; anything else passes).
constexpr bool int_in_range(const Range& r, std::int64_t v) {
  if (r.kind == Range::Kind::kInt) return v >= r.lo && v <= r.hi;
  if (r.kind == Range::Kind::kOneOf) return v == r.lo || v == r.hi;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Field descriptors.

/// One field of record R: a scalar (integer, enum, bool, float), std::array<float, N> (N f32 on the
/// wire, each named by elem_names) or std::array<char, N> (text cN).
/// A device build (GEOJCBB_DOC_TEXT=0) keeps no unit and note: they would be "" anyway, and every
/// descriptor is in its flash.
template <class R, class T>
struct Field {
  const char* name;
  T R::*member;
  Range range;
  const char* const* elem_names;  ///< std::array<float, N>: the wire name of each element
#if GEOJCBB_DOC_TEXT
  const char* unit;  ///< for the docs ("" when none; names carry units too: x_m)
  const char* note;  ///< for the docs (not part of the schema text)
#endif
  constexpr const char* unit_text() const {
#if GEOJCBB_DOC_TEXT
    return unit;
#else
    return "";
#endif
  }
  constexpr const char* note_text() const {
#if GEOJCBB_DOC_TEXT
    return note;
#else
    return "";
#endif
  }
};

/// A counted list: count (u8) on the wire, then `count` items (struct Item with its own fields()).
template <class R, class C, class Item, std::size_t N>
struct List {
  const char* name;  ///< of the count field
  C R::*count;
  std::array<Item, N> R::*items;
  const char* items_name;  ///< for the docs: obs -> obs[i].range_m
  const char* note;
};

namespace detail {
template <class T>
struct IsFloatArray : std::false_type {};
template <std::size_t N>
struct IsFloatArray<std::array<float, N>> : std::true_type {};
}  // namespace detail

/// A text for people, or "" in a device build (the literal is then never emitted).
constexpr const char* doc_text(const char* text) { return GEOJCBB_DOC_TEXT ? text : ""; }

namespace detail {
template <class R, class T>
constexpr Field<R, T> make_field(const char* name, T R::*member, Range r, const char* unit, const char* note,
                                 const char* const* elem_names) {
#if GEOJCBB_DOC_TEXT
  return Field<R, T>{name, member, r, elem_names, unit, note};
#else
  (void)unit;
  (void)note;
  return Field<R, T>{name, member, r, elem_names};
#endif
}
}  // namespace detail
using detail::make_field;

template <class R, class T>
constexpr Field<R, T> field(const char* name, T R::*member, Range r = range::any(), const char* unit = "",
                            const char* note = "") {
  static_assert(!detail::IsFloatArray<T>::value,
                "an array of floats names its elements: field(name, member, range, unit, note, names)");
  return make_field<R, T>(name, member, r, unit, note, nullptr);
}
/// An array of floats: N f32 on the wire, each with its own name (p00 ... p22).
template <class R, std::size_t N>
constexpr Field<R, std::array<float, N>> field(const char* name, std::array<float, N> R::*member, Range r,
                                               const char* unit, const char* note, const char* const (&elem_names)[N]) {
  return make_field<R, std::array<float, N>>(name, member, r, unit, note, elem_names);
}
template <class R, class C, class Item, std::size_t N>
constexpr List<R, C, Item, N> list(const char* name, C R::*count, std::array<Item, N> R::*items, const char* items_name,
                                   const char* note = "") {
  static_assert(std::is_same_v<C, std::uint8_t>, "a list's count is a u8");
  static_assert(N >= 1 && N <= 255, "count is a u8");
  return List<R, C, Item, N>{name, count, items, items_name, doc_text(note)};
}

namespace detail {

template <class T>
struct IsList : std::false_type {};
template <class R, class C, class Item, std::size_t N>
struct IsList<List<R, C, Item, N>> : std::true_type {};

template <class T, bool = std::is_enum_v<T>>
struct Underlying {
  using type = T;
};
template <class T>
struct Underlying<T, true> {
  using type = std::underlying_type_t<T>;
};

/// How a member type goes on the wire: its wire type and how many of it.
template <class T>
struct WireOf {
  using U = typename Underlying<T>::type;
  static_assert(std::is_same_v<U, bool> || std::is_same_v<U, std::uint8_t> || std::is_same_v<U, std::uint16_t> ||
                    std::is_same_v<U, std::uint32_t> || std::is_same_v<U, std::int32_t> || std::is_same_v<U, float>,
                "no wire type for this member type");
  static constexpr WireType kType = std::is_same_v<U, float>           ? WireType::kF32
                                    : std::is_same_v<U, std::int32_t>  ? WireType::kI32
                                    : std::is_same_v<U, std::uint32_t> ? WireType::kU32
                                    : std::is_same_v<U, std::uint16_t> ? WireType::kU16
                                                                       : WireType::kU8;
  static constexpr std::size_t kCount = 1;
};
template <std::size_t N>
struct WireOf<std::array<float, N>> {
  static constexpr WireType kType = WireType::kF32;
  static constexpr std::size_t kCount = N;
};
template <std::size_t N>
struct WireOf<std::array<char, N>> {
  static constexpr WireType kType = WireType::kText;
  static constexpr std::size_t kCount = N;
};

template <class R, class T>
constexpr std::size_t wire_bytes(const Field<R, T>&) {
  return wire_size(WireOf<T>::kType) * WireOf<T>::kCount;
}
template <class R, class C, class Item, std::size_t N>
constexpr std::size_t wire_bytes(const List<R, C, Item, N>&) {
  return 1;  // the count; the items are counted by item_size
}

/// A record's optional rule: `static constexpr const char* kRule` and `Error rule() const`.
template <class R, class = void>
struct HasRule : std::false_type {};
template <class R>
struct HasRule<R, std::void_t<decltype(R::kRule), decltype(std::declval<const R&>().rule())>> : std::true_type {};

/// A record's field list as one constant object (static storage): the codec walks it at run time
/// without building the descriptors on the stack (a STATS list is about 1.1 KB).
template <class R>
inline constexpr auto kFieldsOf = R::fields();

template <class R>
constexpr std::size_t field_count() {
  return std::tuple_size_v<decltype(R::fields())>;
}

/// Fields before the list (all of them without one), in bytes, the list's count included.
template <class R>
constexpr std::size_t fixed_size() {
  return std::apply([](const auto&... f) { return (std::size_t{0} + ... + wire_bytes(f)); }, R::fields());
}

template <class R>
constexpr bool has_list() {
  return std::apply([](const auto&... f) { return (false || ... || IsList<std::decay_t<decltype(f)>>::value); },
                    R::fields());
}

/// The list descriptor's type (void without one). It must come last.
template <class R, bool = has_list<R>()>
struct ListOf {
  using type = void;
  using Item = void;
  static constexpr std::size_t kCapacity = 0;
  static constexpr std::size_t kItemSize = 0;
};
template <class R>
struct ListOf<R, true> {
  using Tuple = decltype(R::fields());
  using type = std::decay_t<std::tuple_element_t<std::tuple_size_v<Tuple> - 1, Tuple>>;
  static_assert(IsList<type>::value, "a list must be the last field");
  template <class L>
  struct Parts;
  template <class R2, class C, class I, std::size_t N>
  struct Parts<List<R2, C, I, N>> {
    using Item = I;
    static constexpr std::size_t kN = N;
  };
  using Item = typename Parts<type>::Item;
  static constexpr std::size_t kCapacity = Parts<type>::kN;
  static_assert(!has_list<Item>(), "list items hold no lists");
  static constexpr std::size_t kItemSize = fixed_size<Item>();
};

// --- write ---------------------------------------------------------------------------------------

template <class T>
void write_scalar(Writer& w, T v) {
  using U = typename Underlying<T>::type;
  const U u = static_cast<U>(v);
  if constexpr (std::is_same_v<U, bool>) {
    w.u8(u ? 1 : 0);
  } else if constexpr (std::is_same_v<U, float>) {
    w.f32(u);
  } else if constexpr (std::is_same_v<U, std::int32_t>) {
    w.i32(u);
  } else if constexpr (std::is_same_v<U, std::uint32_t>) {
    w.u32(u);
  } else if constexpr (std::is_same_v<U, std::uint16_t>) {
    w.u16(u);
  } else {
    w.u8(u);
  }
}

template <class R>
void write_record(Writer& w, const R& rec);

template <class R, class T>
void write_one(Writer& w, const R& rec, const Field<R, T>& f) {
  const T& v = rec.*(f.member);
  if constexpr (WireOf<T>::kCount > 1 || WireOf<T>::kType == WireType::kText) {
    for (const auto x : v) {  // <= N
      if constexpr (WireOf<T>::kType == WireType::kText) {
        w.u8(static_cast<std::uint8_t>(x));
      } else {
        w.f32(x);
      }
    }
  } else {
    write_scalar(w, v);
  }
}
template <class R, class C, class Item, std::size_t N>
void write_one(Writer& w, const R& rec, const List<R, C, Item, N>& f) {
  const std::uint8_t n = rec.*(f.count);
  w.u8(n);
  for (std::size_t i = 0; i < n && i < N; ++i) write_record(w, (rec.*(f.items))[i]);  // <= N
}

template <class R>
void write_record(Writer& w, const R& rec) {
  std::apply([&](const auto&... f) { (write_one(w, rec, f), ...); }, kFieldsOf<R>);
}

// --- read ----------------------------------------------------------------------------------------

template <class T>
Error read_scalar(Reader& r, T& out) {
  using U = typename Underlying<T>::type;
  if constexpr (std::is_same_v<U, bool>) {
    const std::uint8_t b = r.u8();
    if (b > 1) return Error::kOutOfRange;  // a bool holds 0 or 1 only
    out = b == 1;
  } else if constexpr (std::is_same_v<U, float>) {
    out = r.f32();
  } else if constexpr (std::is_same_v<U, std::int32_t>) {
    out = r.i32();
  } else if constexpr (std::is_same_v<U, std::uint32_t>) {
    out = static_cast<T>(r.u32());
  } else if constexpr (std::is_same_v<U, std::uint16_t>) {
    out = static_cast<T>(r.u16());
  } else {
    out = static_cast<T>(r.u8());  // a fixed underlying type holds any u8; validate() checks enums
  }
  return Error::kOk;
}

template <class R>
Error read_record(Reader& r, std::size_t n, R& rec);

template <class R, class T>
Error read_one(Reader& r, std::size_t, R& rec, const Field<R, T>& f) {
  T& v = rec.*(f.member);
  if constexpr (WireOf<T>::kCount > 1 || WireOf<T>::kType == WireType::kText) {
    for (auto& x : v) {  // <= N
      if constexpr (WireOf<T>::kType == WireType::kText) {
        x = static_cast<char>(r.u8());
      } else {
        x = r.f32();
      }
    }
    return Error::kOk;
  } else {
    return read_scalar(r, v);
  }
}
/// The list: count over capacity is kCapacityExceeded; a payload length other than what count
/// implies is kBadLength (n is the whole payload's length).
template <class R, class C, class Item, std::size_t N>
Error read_one(Reader& r, std::size_t n, R& rec, const List<R, C, Item, N>& f) {
  const std::uint8_t count = r.u8();
  if (count > N) return Error::kCapacityExceeded;
  if (n != fixed_size<R>() + count * fixed_size<Item>()) return Error::kBadLength;
  rec.*(f.count) = count;
  for (std::size_t i = 0; i < count; ++i) {  // <= N
    const Error e = read_record(r, 0, (rec.*(f.items))[i]);
    if (e != Error::kOk) return e;
  }
  return Error::kOk;
}

template <class R>
Error read_record(Reader& r, std::size_t n, R& rec) {
  Error e = Error::kOk;
  std::apply([&](const auto&... f) { (void)(((e = read_one(r, n, rec, f)) == Error::kOk) && ...); }, kFieldsOf<R>);
  return e;
}

// --- validate ------------------------------------------------------------------------------------

template <class R, class T>
Error finite_one(const R& rec, const Field<R, T>& f) {
  if constexpr (WireOf<T>::kType == WireType::kF32) {
    if constexpr (WireOf<T>::kCount > 1) {
      for (const float x : rec.*(f.member)) {  // <= N
        if (check_float(f.range, x) == Error::kNonFinite) return Error::kNonFinite;
      }
      return Error::kOk;
    } else {
      return check_float(f.range, rec.*(f.member)) == Error::kNonFinite ? Error::kNonFinite : Error::kOk;
    }
  } else {
    return Error::kOk;
  }
}
template <class R, class C, class Item, std::size_t N>
Error finite_one(const R&, const List<R, C, Item, N>&) {
  return Error::kOk;
}

template <class R, class T>
Error range_one(const R& rec, const Field<R, T>& f) {
  const T& v = rec.*(f.member);
  if constexpr (WireOf<T>::kType == WireType::kF32) {
    if constexpr (WireOf<T>::kCount > 1) {
      for (const float x : v) {  // <= N
        const Error e = check_float(f.range, x);
        if (e != Error::kOk) return e;
      }
      return Error::kOk;
    } else {
      return check_float(f.range, v);
    }
  } else if constexpr (WireOf<T>::kType == WireType::kText) {
    bool padding = false;
    for (const char c : v) {  // <= N
      if (c == '\0') {
        padding = true;
      } else if (padding || c < 0x20 || c > 0x7E) {
        return Error::kOutOfRange;
      }
    }
    return Error::kOk;
  } else {
    using U = typename Underlying<T>::type;
    return int_in_range(f.range, static_cast<std::int64_t>(static_cast<U>(v))) ? Error::kOk : Error::kOutOfRange;
  }
}
template <class R>
Error validate_record(const R& rec);

template <class R, class C, class Item, std::size_t N>
Error range_one(const R& rec, const List<R, C, Item, N>& f) {
  const std::uint8_t count = rec.*(f.count);
  if (count > N) return Error::kCapacityExceeded;
  for (std::size_t i = 0; i < count; ++i) {  // <= N
    const Error e = validate_record((rec.*(f.items))[i]);
    if (e != Error::kOk) return e;
  }
  return Error::kOk;
}

/// A record's checks, in this order: every float finite (kNonFinite), then every field's range in
/// wire order (kOutOfRange; a list: kCapacityExceeded, then each item the same way), then the rule.
template <class R>
Error validate_record(const R& rec) {
  Error e = Error::kOk;
  std::apply([&](const auto&... f) { (void)(((e = finite_one(rec, f)) == Error::kOk) && ...); }, kFieldsOf<R>);
  if (e != Error::kOk) return e;
  std::apply([&](const auto&... f) { (void)(((e = range_one(rec, f)) == Error::kOk) && ...); }, kFieldsOf<R>);
  if (e != Error::kOk) return e;
  if constexpr (HasRule<R>::value) e = rec.rule();
  return e;
}

/// Items the payload carries (0 without a list).
template <class R>
std::size_t item_count(const R& rec) {
  if constexpr (has_list<R>()) {
    return rec.*(std::get<field_count<R>() - 1>(kFieldsOf<R>).count);
  } else {
    (void)rec;
    return 0;
  }
}

template <class R>
constexpr std::size_t max_payload_size() {
  constexpr std::size_t n = fixed_size<R>() + ListOf<R>::kCapacity * ListOf<R>::kItemSize;
  static_assert(n <= kMaxPayload, "a full message must fit one frame");
  return n;
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// The flat table of a message's fields (type-erased), for the schema text and the docs.

struct FieldInfo {
  const char* name = "";
  WireType type = WireType::kU8;
  std::size_t count = 1;  ///< elements (std::array<float, N>) or characters (text)
  const char* const* elem_names = nullptr;
  Range range{};
  const char* unit = "";
  const char* note = "";
  bool item = false;            ///< a field of the list's items
  const char* items_name = "";  ///< item fields: the list member (obs, pairs)
  [[nodiscard]] constexpr std::size_t bytes() const {
    return type == WireType::kText ? count : wire_size(type) * count;
  }
};

namespace detail {
template <class R, class T>
constexpr FieldInfo info_of(const Field<R, T>& f, bool item, const char* items_name) {
  return FieldInfo{f.name, WireOf<T>::kType, WireOf<T>::kCount, f.elem_names, f.range, f.unit_text(), f.note_text(),
                   item,   items_name};
}
template <class R, class C, class Item, std::size_t N>
constexpr FieldInfo info_of(const List<R, C, Item, N>& f, bool, const char*) {
  return FieldInfo{f.name, WireType::kU8, 1, nullptr, range::count(), "", f.note, false, ""};
}
template <class R, std::size_t K>
constexpr void append_infos(std::array<FieldInfo, K>& out, std::size_t& k, bool item, const char* items_name) {
  std::apply([&](const auto&... f) { ((out[k++] = info_of(f, item, items_name)), ...); }, R::fields());
}
}  // namespace detail

/// Fields of M (and then of its list's items), in wire order.
template <class M>
constexpr std::size_t info_count() {
  if constexpr (detail::has_list<M>()) {
    return detail::field_count<M>() + detail::field_count<typename detail::ListOf<M>::Item>();
  } else {
    return detail::field_count<M>();
  }
}
template <class M>
constexpr std::array<FieldInfo, info_count<M>()> field_infos() {
  std::array<FieldInfo, info_count<M>()> out{};
  std::size_t k = 0;
  detail::append_infos<M>(out, k, false, "");
  if constexpr (detail::has_list<M>()) {
    using L = detail::ListOf<M>;
    detail::append_infos<typename L::Item>(out, k, true,
                                           std::get<detail::field_count<M>() - 1>(M::fields()).items_name);
  }
  return out;
}
/// The rule names of M and of its items ("" when none).
template <class R>
constexpr const char* rule_of() {
  if constexpr (detail::HasRule<R>::value) {
    return R::kRule;
  } else {
    return "";
  }
}
template <class M>
constexpr const char* item_rule_of() {
  if constexpr (detail::has_list<M>()) {
    return rule_of<typename detail::ListOf<M>::Item>();
  } else {
    return "";
  }
}

// ---------------------------------------------------------------------------------------------

/// Encode, decode, validate and sizes of every message, from M::fields() (CRTP; the messages stay
/// aggregates). A value-initialised message of every type is valid (the fuzz target relies on it).
template <class M>
struct Codec {
  /// Bytes of the fields before the list (all of them without one), the count included.
  static constexpr std::size_t kFixedSize = detail::fixed_size<M>();
  /// Bytes of one list item (0 without a list), and the list's capacity.
  static constexpr std::size_t kItemSize = detail::ListOf<M>::kItemSize;
  static constexpr std::size_t kCapacity = detail::ListOf<M>::kCapacity;
  /// The largest payload (a full list).
  static constexpr std::size_t kMaxPayloadSize = detail::max_payload_size<M>();
  /// The payload of a fixed-size message (a list's: its largest).
  static constexpr std::size_t kPayloadSize = kMaxPayloadSize;

  /// @return kOk; kNonFinite; kOutOfRange; kCapacityExceeded; kNotPositiveDefinite (a rule's).
  [[nodiscard]] Error validate() const { return detail::validate_record(self()); }
  [[nodiscard]] std::size_t payload_size() const { return kFixedSize + detail::item_count(self()) * kItemSize; }
  void write(Writer& w) const { detail::write_record(w, self()); }
  /// Reads the fields (no validation; a failed read leaves *this partly written).
  /// @return kOk; kBadLength (payload length); kCapacityExceeded (count); kOutOfRange (a bool not 0/1)
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if constexpr (detail::has_list<M>()) {
      if (n < kFixedSize) return Error::kBadLength;
    } else {
      if (n != kFixedSize) return Error::kBadLength;
    }
    Reader r(p, n);
    return detail::read_record(r, n, static_cast<M&>(*this));
  }

  /// Validates and writes the payload into [out, out + cap).
  /// @return kOk with len set; the validation error; kBufferTooSmall. len is untouched on error.
  [[nodiscard]] Error encode(std::uint8_t* out, std::size_t cap, std::size_t& len) const {
    const Error e = validate();
    if (e != Error::kOk) return e;
    const std::size_t n = payload_size();
    if (n > cap || (out == nullptr && n > 0)) return Error::kBufferTooSmall;
    Writer w(out, cap);
    write(w);
    if (!w.ok() || w.size() != n) return Error::kInternal;  // write() disagrees with payload_size()
    len = n;
    return Error::kOk;
  }
  template <std::size_t N>
  [[nodiscard]] Error encode(std::array<std::uint8_t, N>& out, std::size_t& len) const {
    return encode(out.data(), N, len);
  }
  /// Reads and validates a payload in place, with no copy (a receiver's scratch: on error *this
  /// holds part of the payload and must not be used).
  /// @return kOk; kBadLength; kCapacityExceeded; kNonFinite; kOutOfRange; kNotPositiveDefinite.
  [[nodiscard]] Error decode_in_place(const std::uint8_t* p, std::size_t n) {
    if (p == nullptr && n > 0) return Error::kBadLength;
    const Error e = read(p, n);
    return e != Error::kOk ? e : validate();
  }
  /// Reads and validates a payload; *this is assigned only when everything passed.
  /// @return as decode_in_place.
  [[nodiscard]] Error decode(const std::uint8_t* p, std::size_t n) {
    M tmp{};
    const Error e = tmp.decode_in_place(p, n);
    if (e == Error::kOk) static_cast<M&>(*this) = tmp;
    return e;
  }

 private:
  const M& self() const { return static_cast<const M&>(*this); }
};

}  // namespace geojcbb::proto
