// protocol: the schema text and how it is rendered. The text states, in one place, the frame layout,
// the flags, the error codes, the session rules, and every message's type number, name, field list
// (name:type{range}, in wire order) and rules. The first lines are written here (kSchemaPrologue);
// every "msg" line is rendered at compile time from the message's fields() (fields.hpp) by
// render_message_line, so a renamed, retyped, reordered or re-ranged field changes the text, and so
// the hash. messages.hpp assembles kSchemaText and kSchemaHash (FNV-1a 32 of the text); HELLO and
// CAPABILITIES carry the hash, and a device refuses a host whose hash differs.
// RULE: a change to the frame, the flags, an error code or the session rules must change the
// prologue below; message layouts change the text by themselves.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "geojcbb/protocol/fields.hpp"

namespace geojcbb::proto {

// Grammar: one item per line. "msg 0xTT NAME field:type{range} ... [repeat field:type ...] [{rule}]".
// Types: u8 u16 u32 i32 f32 (little-endian, IEEE-754 binary32) and cN (N bytes of text).
// "repeat" starts the per-item fields of a counted list; the count is the preceding "count:u8".
// Ranges: >=a, a..b (integers, inclusive), a|b, finite, >a, (a,b), [a,b], (a,b], "|+inf" also +Inf.
// The "session" line states the device's rules that a host relies on (what is served before HELLO,
// what is acknowledged, how retransmitted stream frames are treated, when STATS comes unasked).
inline constexpr char kSchemaPrologue[] =
    "geojcbb serial protocol major=1\n"
    "frame cobs delimiter=0x00 ver:u8 flags:u8 type:u8 reserved:u8{sent-as-0,ignored} seq:u16 len:u16 payload crc32c:u32 "
    "max_payload=1024 crc=castagnoli-reflected-0x82F63B78\n"
    "flags compatible_mask=0x0F ack_requested=0x01 incompatible_mask=0xF0 known_incompatible=none\n"
    "errors 0=ok 1=incomplete 2=bad_length 3=bad_crc 4=overrun 5=bad_version 6=bad_flags 7=unknown_type "
    "8=wrong_type 9=non_finite 10=out_of_range 11=capacity_exceeded 12=not_positive_definite "
    "13=buffer_too_small 14=schema_mismatch 15=not_ready 16=internal 17=busy\n"
    "session before_HELLO=HELLO,PING acked=CONFIG,RESET,SHUTDOWN,SUBMAP_ACK "
    "stream=ODOMETRY,ODOM_DELTA,RELOCALISE,OBS_BATCH,SUBMAP_SEED stream_applied_once_by_seq_since=CONFIG,RESET "
    "retransmit_window=4096 duplicate_last_OBS_BATCH,SUBMAP_SEED=stored_reply "
    "periodic_STATS=after_POSE_every_stats_period_scans\n"
    "handover after_POSE_with_submap_frames>0=SUBMAP,SUBMAP_COV stream_until_SUBMAP_ACK=busy "
    "SUBMAP_ACK_send=same_map_again_or_current_closed RESET,CONFIG=map_dropped "
    "SUBMAP_SEED_answer=ASSOC_RESULT_seeded_or_compatible_or_no_room\n";

/// How old (in frame seq, 16-bit serial arithmetic) a stream frame may be and still be recognised
/// as a retransmission: the device's reference seq follows every frame to at most this far behind
/// (the "session" line's retransmit_window).
inline constexpr std::uint16_t kRetransmitWindow = 4096;

/// FNV-1a, 32 bits (offset basis 2166136261, prime 16777619).
constexpr std::uint32_t fnv1a32(const char* s, std::size_t n) {
  std::uint32_t h = 2166136261u;
  for (std::size_t i = 0; i < n; ++i) {  // <= n
    h ^= static_cast<std::uint8_t>(s[i]);
    h *= 16777619u;
  }
  return h;
}
static_assert(fnv1a32("a", 1) == 0xE40C292Cu, "FNV-1a 32 reference value");

/// Text of at most N - 1 characters, NUL-terminated, built at compile time (or at run time by the
/// docs renderer). Writing past the end sets overflow and writes nothing.
template <std::size_t N>
struct FixedText {
  std::array<char, N> data{};
  std::size_t size = 0;
  bool overflow = false;

  constexpr void put(char c) {
    if (size + 1 >= N) {
      overflow = true;
      return;
    }
    data[size++] = c;
  }
  /// s must not be null (no null test: GCC's sanitizers make `&global != nullptr` non-constant).
  constexpr void put(const char* s) {
    for (std::size_t i = 0; s[i] != '\0'; ++i) put(s[i]);  // <= strlen(s)
  }
  constexpr void put_int(std::int64_t v) {
    if (v < 0) put('-');
    // Magnitude as unsigned (INT64_MIN included), ten digits at most for what schemas hold.
    std::uint64_t u = v < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v);
    char digits[20] = {};
    int n = 0;
    do {
      digits[n++] = static_cast<char>('0' + u % 10);
      u /= 10;
    } while (u != 0 && n < 20);  // <= 20 digits
    while (n > 0) put(digits[--n]);
  }
  constexpr void put_hex2(std::uint8_t v) {
    constexpr char kHex[] = "0123456789ABCDEF";
    put(kHex[v >> 4]);
    put(kHex[v & 0x0F]);
  }
  [[nodiscard]] constexpr const char* c_str() const { return data.data(); }
};

namespace detail {
/// A float bound as the schema writes it: pi, -pi, or an integer (a range with any other bound does
/// not render: the constant expression fails).
inline void range_bound_is_not_pi_or_an_integer() {}
template <std::size_t N>
constexpr void put_bound(FixedText<N>& t, float v) {
  if (v == kPiF) {
    t.put("pi");
  } else if (v == -kPiF) {
    t.put("-pi");
  } else {
    const auto i = static_cast<std::int64_t>(v);
    if (static_cast<float>(i) != v) range_bound_is_not_pi_or_an_integer();
    t.put_int(i);
  }
}
}  // namespace detail

/// The text of a field's range (without braces; empty: any value).
template <std::size_t N>
constexpr void render_range(FixedText<N>& t, const FieldInfo& f) {
  const Range& r = f.range;
  switch (r.kind) {
    case Range::Kind::kAny:
      if (f.type == WireType::kF32) t.put("finite");
      break;
    case Range::Kind::kInt:
      if (r.hi == range::kNoMax) {
        t.put(">=");
        t.put_int(r.lo);
      } else {
        t.put_int(r.lo);
        t.put("..");
        t.put_int(r.hi);
      }
      break;
    case Range::Kind::kOneOf:
      t.put_int(r.lo);
      t.put('|');
      t.put_int(r.hi);
      break;
    case Range::Kind::kFloat:
      if (r.has_lo && r.has_hi) {
        t.put(r.lo_open ? '(' : '[');
        detail::put_bound(t, r.flo);
        t.put(',');
        detail::put_bound(t, r.fhi);
        t.put(r.hi_open ? ')' : ']');
      } else if (r.has_lo) {
        t.put(r.lo_open ? ">" : ">=");
        detail::put_bound(t, r.flo);
      } else if (r.has_hi) {
        t.put(r.hi_open ? "<" : "<=");
        detail::put_bound(t, r.fhi);
      } else {
        t.put("finite");
      }
      if (r.plus_inf) t.put("|+inf");
      break;
    case Range::Kind::kText: t.put("printable,zero-padded"); break;
    case Range::Kind::kCount: t.put("<=capacity"); break;
  }
}

/// The wire type's name: u8 ... f32, and cN for text.
template <std::size_t N>
constexpr void render_type(FixedText<N>& t, const FieldInfo& f) {
  t.put(wire_name(f.type));
  if (f.type == WireType::kText) t.put_int(static_cast<std::int64_t>(f.count));
}

namespace detail {
template <std::size_t N>
constexpr void put_field_token(FixedText<N>& t, const char* name, const FieldInfo& f) {
  t.put(' ');
  t.put(name);
  t.put(':');
  render_type(t, f);
  FixedText<64> r{};
  render_range(r, f);
  if (r.size > 0) {
    t.put('{');
    t.put(r.c_str());
    t.put('}');
  }
}
}  // namespace detail

/// One "msg" line of the schema text (with its newline), from M's description.
template <class M, std::size_t N>
constexpr void render_message_line(FixedText<N>& t) {
  t.put("msg 0x");
  t.put_hex2(static_cast<std::uint8_t>(M::kType));
  t.put(' ');
  t.put(M::kName);
  bool repeated = false;
  for (const FieldInfo& f : field_infos<M>()) {  // <= fields of M and of its items
    if (f.item && !repeated) {
      t.put(" repeat");
      repeated = true;
    }
    if (f.type == WireType::kF32 && f.count > 1) {
      for (std::size_t i = 0; i < f.count; ++i) {        // <= the array's length
        detail::put_field_token(t, f.elem_names[i], f);  // field() requires a name per element
      }
    } else {
      detail::put_field_token(t, f.name, f);
    }
  }
  for (const char* rule : {item_rule_of<M>(), rule_of<M>()}) {  // 2
    if (rule[0] != '\0') {
      t.put(" {");
      t.put(rule);
      t.put('}');
    }
  }
  t.put('\n');
}

/// One message's line, and its FNV-1a hash (a test builds it for two orders of the same fields).
template <class M>
constexpr FixedText<2048> message_line() {
  FixedText<2048> t{};
  render_message_line<M>(t);
  return t;
}
template <class M>
constexpr std::uint32_t message_hash() {
  constexpr FixedText<2048> t = message_line<M>();
  static_assert(!t.overflow, "a message line over 2047 characters");
  return fnv1a32(t.data.data(), t.size);
}

/// Payload layout of one message as a schema text states it.
struct SchemaLayout {
  bool found = false;
  std::size_t fixed_bytes = 0;  ///< fields before "repeat" (all of them when there is none)
  std::size_t item_bytes = 0;   ///< fields after "repeat" (0: no counted list)
};

namespace detail {
constexpr bool is_space(char c) { return c == ' ' || c == '\n'; }
constexpr int hex_digit(char c) {
  return (c >= '0' && c <= '9') ? c - '0' : (c >= 'A' && c <= 'F') ? c - 'A' + 10 : -1;
}
/// Size of the type in the token [b, e) ("name:u16{...}"); 0 when the token is not a field.
constexpr std::size_t token_field_size(const char* b, const char* e) {
  const char* c = b;
  while (c < e && *c != ':') ++c;  // <= token length
  if (c == e) return 0;
  ++c;
  const char* t = c;
  while (t < e && *t != '{') ++t;  // <= token length
  const std::size_t n = static_cast<std::size_t>(t - c);
  if (n == 2 && c[0] == 'u' && c[1] == '8') return 1;
  if (n == 3 && c[0] == 'u' && c[1] == '1' && c[2] == '6') return 2;
  if (n == 3 && c[1] == '3' && c[2] == '2' && (c[0] == 'u' || c[0] == 'i' || c[0] == 'f')) return 4;
  if (n >= 2 && c[0] == 'c') {  // cN: N bytes of text
    std::size_t k = 0;
    for (std::size_t i = 1; i < n; ++i) {  // <= token length
      if (c[i] < '0' || c[i] > '9') return 0;
      k = k * 10 + static_cast<std::size_t>(c[i] - '0');
    }
    return k;
  }
  return 0;
}
constexpr bool token_is(const char* b, const char* e, const char* word) {
  const char* w = word;
  while (b < e && *w != '\0') {  // <= token length
    if (*b++ != *w++) return false;
  }
  return b == e && *w == '\0';
}
}  // namespace detail

/// Parses a schema text for message `type` (a cross-check of the rendered text against the codec's
/// sizes). Bound: one pass over the text.
constexpr SchemaLayout schema_layout(const char* text, std::size_t length, std::uint8_t type) {
  SchemaLayout out{};
  const char* p = text;
  const char* const end = text + length;
  while (p < end) {  // one line per pass, <= length
    const char* eol = p;
    while (eol < end && *eol != '\n') ++eol;  // <= line length
    const bool is_msg = eol - p > 9 && p[0] == 'm' && p[1] == 's' && p[2] == 'g' && p[3] == ' ' && p[4] == '0' &&
                        p[5] == 'x' && detail::hex_digit(p[6]) >= 0 && detail::hex_digit(p[7]) >= 0;
    if (is_msg && detail::hex_digit(p[6]) * 16 + detail::hex_digit(p[7]) == type) {
      out.found = true;
      bool repeated = false;
      const char* t = p + 9;
      while (t < eol) {  // one token per pass, <= line length
        while (t < eol && detail::is_space(*t)) ++t;
        const char* te = t;
        while (te < eol && !detail::is_space(*te)) ++te;
        if (detail::token_is(t, te, "repeat")) {
          repeated = true;
        } else {
          (repeated ? out.item_bytes : out.fixed_bytes) += detail::token_field_size(t, te);
        }
        t = te;
      }
      return out;
    }
    p = eol + 1;
  }
  return out;
}

}  // namespace geojcbb::proto
