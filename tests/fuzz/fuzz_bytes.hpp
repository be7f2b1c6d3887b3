// The fuzz targets' byte reader: past the end it yields zeros, so every program terminates. Each
// target derives its own Input from it and adds how it turns bytes into numbers (f()).
#pragma once

#include <cstddef>
#include <cstdint>

namespace geojcbb::fuzz {

/// Stops the fuzzer on a broken invariant (a crash it reports with the input).
inline void require(bool ok) {
  if (!ok) __builtin_trap();
}

struct Bytes {
  const std::uint8_t* p;
  std::size_t n, i = 0;
  Bytes(const std::uint8_t* data, std::size_t size) : p(data), n(size) {}
  bool more() const { return i < n; }
  std::uint8_t u8() { return i < n ? p[i++] : 0; }
  std::uint16_t u16() {  // one read per statement: the same order under every compiler
    const std::uint8_t lo = u8();
    return static_cast<std::uint16_t>(lo | (u8() << 8));
  }
  std::uint32_t u32() {
    const std::uint32_t lo = u16();
    return lo | (std::uint32_t{u16()} << 16);
  }
  std::uint64_t u64() {
    std::uint64_t v = 0;
    for (int k = 0; k < 8; ++k) v |= std::uint64_t{u8()} << (8 * k);  // <= 8
    return v;
  }
};

}  // namespace geojcbb::fuzz
