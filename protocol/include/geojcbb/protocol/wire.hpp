// protocol: little-endian field encode/decode. Every multi-byte field is written byte by byte with
// shifts, so the wire layout does not depend on the host's endianness, alignment or struct padding
// (no struct is ever copied onto the wire). float is IEEE-754 binary32, sent as its bit pattern.
// Writer and Reader are bounds-checked cursors over caller-owned bytes; an access past the end sets
// a sticky failure flag instead of touching memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

namespace geojcbb::proto {

static_assert(std::numeric_limits<float>::is_iec559, "the wire carries IEEE-754 binary32 floats");
static_assert(sizeof(float) == 4 && sizeof(std::uint32_t) == 4, "float32 must be 4 bytes");

constexpr void put_u16_le(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v & 0xFFu);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
constexpr void put_u32_le(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v & 0xFFu);
  p[1] = static_cast<std::uint8_t>((v >> 8) & 0xFFu);
  p[2] = static_cast<std::uint8_t>((v >> 16) & 0xFFu);
  p[3] = static_cast<std::uint8_t>(v >> 24);
}
constexpr std::uint16_t get_u16_le(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
constexpr std::uint32_t get_u32_le(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

/// Bit pattern of a float (memcpy of a scalar, the C++17 spelling of std::bit_cast).
inline std::uint32_t float_bits(float f) {
  std::uint32_t u = 0;
  std::memcpy(&u, &f, sizeof u);
  return u;
}
inline float bits_float(std::uint32_t u) {
  float f = 0.0f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}
/// Finite test on the bit pattern: stays correct under -ffast-math, needs no libm.
inline bool is_finite(float f) { return (float_bits(f) & 0x7F800000u) != 0x7F800000u; }
inline bool is_nan(float f) { return (float_bits(f) & 0x7FFFFFFFu) > 0x7F800000u; }
inline bool is_pos_inf(float f) { return float_bits(f) == 0x7F800000u; }

/// Appends little-endian fields to caller-owned bytes [buf, buf + cap).
class Writer {
 public:
  constexpr Writer(std::uint8_t* buf, std::size_t cap) : buf_(buf), cap_(cap) {}

  void u8(std::uint8_t v) {
    if (!reserve(1)) return;
    buf_[pos_++] = v;
  }
  void u16(std::uint16_t v) {
    if (!reserve(2)) return;
    put_u16_le(buf_ + pos_, v);
    pos_ += 2;
  }
  void u32(std::uint32_t v) {
    if (!reserve(4)) return;
    put_u32_le(buf_ + pos_, v);
    pos_ += 4;
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }  // two's complement, modular
  void f32(float v) { u32(float_bits(v)); }
  void bytes(const std::uint8_t* p, std::size_t n) {
    if (!reserve(n)) return;
    for (std::size_t i = 0; i < n; ++i) buf_[pos_ + i] = p[i];  // <= n
    pos_ += n;
  }

  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] std::size_t size() const { return pos_; }

 private:
  bool reserve(std::size_t n) {
    if (!ok_ || buf_ == nullptr || n > cap_ - pos_) {
      ok_ = false;
      return false;
    }
    return true;
  }
  std::uint8_t* buf_;
  std::size_t cap_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

/// Reads little-endian fields from [p, p + n). Past the end: returns 0 and fails (sticky).
class Reader {
 public:
  constexpr Reader(const std::uint8_t* p, std::size_t n) : p_(p), n_(n) {}

  std::uint8_t u8() {
    if (!take(1)) return 0;
    return p_[pos_++];
  }
  std::uint16_t u16() {
    if (!take(2)) return 0;
    const std::uint16_t v = get_u16_le(p_ + pos_);
    pos_ += 2;
    return v;
  }
  std::uint32_t u32() {
    if (!take(4)) return 0;
    const std::uint32_t v = get_u32_le(p_ + pos_);
    pos_ += 4;
    return v;
  }
  std::int32_t i32() {
    const std::uint32_t u = u32();
    // Two's complement without implementation-defined narrowing.
    return u <= 0x7FFFFFFFu ? static_cast<std::int32_t>(u) : -static_cast<std::int32_t>(~u) - 1;
  }
  float f32() { return bits_float(u32()); }
  void bytes(std::uint8_t* out, std::size_t n) {
    if (!take(n)) return;
    for (std::size_t i = 0; i < n; ++i) out[i] = p_[pos_ + i];  // <= n
    pos_ += n;
  }

  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] std::size_t remaining() const { return n_ - pos_; }

 private:
  bool take(std::size_t n) {
    if (!ok_ || (p_ == nullptr && n > 0) || n > n_ - pos_) {
      ok_ = false;
      return false;
    }
    return true;
  }
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

}  // namespace geojcbb::proto
