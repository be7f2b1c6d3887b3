// protocol: CRC-32C (Castagnoli), the frame check. Reflected polynomial 0x82F63B78, initial value
// and final XOR 0xFFFFFFFF; check value of "123456789" is 0xE3069283 (static_assert below). It
// detects every 1-, 2- and 3-bit error and every burst up to 32 bits in frames of our size.
// Table-driven, one byte per step; the 256-entry table (1 KiB) is generated at compile time.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace geojcbb::proto {

constexpr std::uint32_t kCrc32cPoly = 0x82F63B78u;  ///< reflected 0x1EDC6F41
constexpr std::uint32_t kCrc32cInit = 0xFFFFFFFFu;
constexpr std::uint32_t kCrc32cCheck = 0xE3069283u;  ///< CRC-32C of the ASCII bytes "123456789"

namespace detail {
constexpr std::array<std::uint32_t, 256> make_crc32c_table() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {  // <= 256
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (c >> 1) ^ kCrc32cPoly : c >> 1;  // <= 8
    t[i] = c;
  }
  return t;
}
inline constexpr std::array<std::uint32_t, 256> kCrc32cTable = make_crc32c_table();
}  // namespace detail

/// Running state: start with kCrc32cInit, feed bytes, finish with crc32c_final.
constexpr std::uint32_t crc32c_update(std::uint32_t state, const std::uint8_t* p, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {  // <= n
    state = detail::kCrc32cTable[(state ^ p[i]) & 0xFFu] ^ (state >> 8);
  }
  return state;
}
constexpr std::uint32_t crc32c_update(std::uint32_t state, std::uint8_t byte) {
  return detail::kCrc32cTable[(state ^ byte) & 0xFFu] ^ (state >> 8);
}
constexpr std::uint32_t crc32c_final(std::uint32_t state) { return state ^ 0xFFFFFFFFu; }

/// CRC-32C of [p, p + n).
constexpr std::uint32_t crc32c(const std::uint8_t* p, std::size_t n) {
  return crc32c_final(crc32c_update(kCrc32cInit, p, n));
}

namespace detail {
constexpr std::uint32_t crc32c_of_check_string() {
  const std::uint8_t s[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  return crc32c(s, 9);
}
}  // namespace detail
static_assert(detail::crc32c_of_check_string() == kCrc32cCheck, "CRC-32C check value");

}  // namespace geojcbb::proto
