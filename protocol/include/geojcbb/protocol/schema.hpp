// protocol: the schema text and its hash. kSchemaText describes, in one place, the frame layout, the
// flags, the error codes and every message's type number, field list (name:type, in wire order) and
// valid ranges. kSchemaHash is its FNV-1a 32-bit hash, computed at compile time; HELLO and
// CAPABILITIES carry it, and a device refuses a host whose hash differs.
// RULE: any change to a frame or message layout, a type number, a flag, an error code or a valid
// range must change this text (hence the hash). messages.hpp static_asserts that every message's
// payload size equals the size this text implies, so a layout change that forgets the text fails to
// compile.
#pragma once

#include <cstddef>
#include <cstdint>

namespace geojcbb::proto {

// Grammar: one item per line. "msg 0xTT NAME field:type{range} ... [repeat field:type ...]".
// Types: u8 u16 u32 i32 f32 (little-endian, IEEE-754 binary32) and c16 (16 bytes of text).
// "repeat" starts the per-item fields of a counted list; the count is the preceding "count:u8".
// The "session" line states the device's rules that a host relies on (what is served before HELLO,
// what is acknowledged, how retransmitted stream frames are treated, when STATS comes unasked).
inline constexpr char kSchemaText[] =
    "geojcbb serial protocol major=1\n"
    "frame cobs delimiter=0x00 ver:u8 flags:u8 type:u8 reserved:u8{sent-as-0,ignored} seq:u16 len:u16 payload crc32c:u32 "
    "max_payload=1024 crc=castagnoli-reflected-0x82F63B78\n"
    "flags compatible_mask=0x0F ack_requested=0x01 incompatible_mask=0xF0 known_incompatible=none\n"
    "errors 0=ok 1=incomplete 2=bad_length 3=bad_crc 4=overrun 5=bad_version 6=bad_flags 7=unknown_type "
    "8=wrong_type 9=non_finite 10=out_of_range 11=capacity_exceeded 12=not_positive_definite "
    "13=buffer_too_small 14=schema_mismatch 15=not_ready 16=internal\n"
    "session before_HELLO=HELLO,PING acked=CONFIG,RESET,SHUTDOWN stream=ODOMETRY,OBS_BATCH "
    "stream_applied_once_by_seq_since=CONFIG,RESET retransmit_window=4096 duplicate_last_OBS_BATCH=stored_reply "
    "periodic_STATS=after_POSE_every_stats_period_scans\n"
    "msg 0x01 HELLO protocol_version:u8 schema_hash:u32\n"
    "msg 0x02 CAPABILITIES protocol_version:u8 schema_hash:u32 max_observations:u16{>=1} "
    "max_candidates:u16{>=1} max_groups:u8{>=1} max_landmarks:u16{>=1} max_jcbb_nodes:u32{>=1} "
    "scalar_bytes:u8{4|8} boot_id:u32 firmware_id:c16{printable,zero-padded}\n"
    "msg 0x03 CONFIG strategy:u8{0..5} confidence:f32{(0,1)} new_landmark_level:f32{(0,1)} "
    "local_radius_m:f32{>0} groups:u8 condition_groups:u8{0|1} dbscan_eps_m:f32{>0} "
    "dbscan_min_points:u8{>=1} node_budget:u32{>=1} min_range_m:f32{>=0} max_range_m:f32{>min} "
    "half_fov_rad:f32{(0,pi]} confirm_hits:u8{>=1} max_misses:u8{>=1} max_tentative_reviews:u8{>=1} "
    "stats_period_scans:u16{0=off}\n"
    "msg 0x04 ACK acked_type:u8 acked_seq:u16\n"
    "msg 0x05 NACK nacked_type:u8 nacked_seq:u16 error:u8{2..16}\n"
    "msg 0x06 PING nonce:u32\n"
    "msg 0x07 PONG nonce:u32\n"
    "msg 0x08 RESET x_m:f32 y_m:f32 theta_rad:f32 p00:f32 p01:f32 p02:f32 p11:f32 p12:f32 p22:f32 "
    "{finite,positive-definite}\n"
    "msg 0x09 SHUTDOWN exit_code:u8\n"
    "msg 0x10 ODOMETRY v_mps:f32 w_radps:f32 dt_s:f32{>=0} sigma_v_mps:f32{>=0} sigma_w_radps:f32{>=0} "
    "{finite}\n"
    "msg 0x11 OBS_BATCH batch_id:u32 count:u8{<=capacity} repeat range_m:f32{>=0} bearing_rad:f32{[-pi,pi]} "
    "r00:f32 r01:f32 r11:f32 {finite,positive-definite}\n"
    "msg 0x20 ASSOC_RESULT batch_id:u32 count:u8{<=capacity} repeat outcome:u8{0..4} feature_id:i32{>=0|-1=new|-2=unmatched} "
    "d2:f32{>=0|+inf}\n"
    "msg 0x21 POSE batch_id:u32 x_m:f32 y_m:f32 theta_rad:f32 p00:f32 p01:f32 p02:f32 p11:f32 p12:f32 "
    "p22:f32 landmark_count:u16 {finite,diagonal>=0}\n"
    "msg 0x30 STATS_REQUEST\n"
    "msg 0x31 STATS frames_ok:u32 bad_crc:u32 bad_length:u32 overrun:u32 unknown_type:u32 bad_version:u32 "
    "bad_flags:u32 invalid_field:u32 budget_hits:u32 scans:u32 instr_predict:u32 instr_predict_local:u32 "
    "instr_associate:u32 instr_update:u32 instr_augment_review:u32 instr_step:u32 "
    "stack_high_water_bytes:u32\n"
    "msg 0x7F ERROR error:u8{2..16} offending_type:u8 offending_seq:u16\n";

/// How old (in frame seq, 16-bit serial arithmetic) a stream frame may be and still be recognised
/// as a retransmission: the device's reference seq follows every frame to at most this far behind
/// (the "session" line's retransmit_window).
inline constexpr std::uint16_t kRetransmitWindow = 4096;

inline constexpr std::size_t kSchemaTextLength = sizeof(kSchemaText) - 1;  ///< without the NUL

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

inline constexpr std::uint32_t kSchemaHash = fnv1a32(kSchemaText, kSchemaTextLength);

/// Payload layout of one message as the schema text states it.
struct SchemaLayout {
  bool found = false;
  std::size_t fixed_bytes = 0;     ///< fields before "repeat" (all of them when there is none)
  std::size_t item_bytes = 0;      ///< fields after "repeat" (0: no counted list)
};

namespace detail {
constexpr bool is_space(char c) { return c == ' ' || c == '\n'; }
constexpr int hex_digit(char c) {
  return (c >= '0' && c <= '9') ? c - '0' : (c >= 'A' && c <= 'F') ? c - 'A' + 10 : -1;
}
/// Size of the type in the token [b, e) ("name:u16{...}"); 0 when the token is not a field.
constexpr std::size_t field_size(const char* b, const char* e) {
  const char* c = b;
  while (c < e && *c != ':') ++c;  // <= token length
  if (c == e) return 0;
  ++c;
  const char* t = c;
  while (t < e && *t != '{') ++t;  // <= token length
  const std::size_t n = static_cast<std::size_t>(t - c);
  if (n == 2 && c[0] == 'u' && c[1] == '8') return 1;
  if (n == 3 && c[1] == '1' && c[2] == '6') return c[0] == 'u' ? 2 : c[0] == 'c' ? 16 : 0;
  if (n == 3 && c[1] == '3' && c[2] == '2' && (c[0] == 'u' || c[0] == 'i' || c[0] == 'f')) return 4;
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

/// Parses kSchemaText for message `type`. Bound: one pass over the text (kSchemaTextLength).
constexpr SchemaLayout schema_layout(std::uint8_t type) {
  SchemaLayout out{};
  const char* p = kSchemaText;
  const char* const end = kSchemaText + kSchemaTextLength;
  while (p < end) {  // one line per pass, <= kSchemaTextLength
    const char* eol = p;
    while (eol < end && *eol != '\n') ++eol;  // <= line length
    const bool is_msg = eol - p > 9 && p[0] == 'm' && p[1] == 's' && p[2] == 'g' && p[3] == ' ' &&
                        p[4] == '0' && p[5] == 'x' && detail::hex_digit(p[6]) >= 0 &&
                        detail::hex_digit(p[7]) >= 0;
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
          (repeated ? out.item_bytes : out.fixed_bytes) += detail::field_size(t, te);
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
