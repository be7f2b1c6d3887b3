// tests/protocol: CRC-32C (the check value of "123456789", incremental update) and COBS (round trip,
// worst-case size, in place, output one byte short, malformed input).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "protocol/protocol_fixtures.hpp"

using namespace proto_test;

TEST_CASE("protocol: CRC-32C check value and incremental update") {
  const char* s = "123456789";
  const auto* p = reinterpret_cast<const std::uint8_t*>(s);
  CHECK(crc32c(p, 9) == 0xE3069283u);
  CHECK(crc32c_final(crc32c_update(crc32c_update(kCrc32cInit, p, 4), p + 4, 5)) == 0xE3069283u);
  std::uint32_t st = kCrc32cInit;
  for (int i = 0; i < 9; ++i) st = crc32c_update(st, p[i]);
  CHECK(crc32c_final(st) == 0xE3069283u);
  CHECK(crc32c(nullptr, 0) == 0u);
}

TEST_CASE("protocol: COBS round trip, worst-case size and malformed input") {
  for (const std::size_t n : {0u, 1u, 2u, 253u, 254u, 255u, 508u, 509u, 1036u}) {
    for (const int pattern : {0, 1, 2}) {  // all zero, no zero, mixed
      Bytes in(n);
      for (std::size_t i = 0; i < n; ++i) {
        in[i] = pattern == 0   ? 0
                : pattern == 1 ? static_cast<std::uint8_t>(1 + i % 255)
                               : static_cast<std::uint8_t>(i % 7 == 0 ? 0 : i);
      }
      Bytes enc(cobs_max_encoded_size(n));
      std::size_t m = 0;
      REQUIRE(cobs_encode(in.data(), n, enc.data(), enc.size(), m) == Error::kOk);
      CHECK(m <= cobs_max_encoded_size(n));
      if (pattern == 1 && n > 0) CHECK(m == cobs_max_encoded_size(n));  // no zero: the worst case
      for (std::size_t i = 0; i < m; ++i) REQUIRE(enc[i] != 0);
      Bytes dec(n + 1);
      std::size_t k = 0;
      REQUIRE(cobs_decode(enc.data(), m, dec.data(), dec.size(), k) == Error::kOk);
      CHECK(k == n);
      CHECK(std::equal(in.begin(), in.end(), dec.begin()));
      // In place.
      REQUIRE(cobs_decode(enc.data(), m, enc.data(), enc.size(), k) == Error::kOk);
      CHECK(std::equal(in.begin(), in.end(), enc.begin()));
      // Output one byte short.
      Bytes enc2(m - 1 + 1);
      std::size_t w = 12345;
      CHECK(cobs_encode(in.data(), n, enc2.data(), m - 1, w) == Error::kBufferTooSmall);
      CHECK(w == 12345);
    }
  }
  std::size_t k = 0;
  std::uint8_t out[8];
  const std::uint8_t zero_inside[] = {3, 1, 0};
  CHECK(cobs_decode(zero_inside, 3, out, 8, k) == Error::kBadLength);
  const std::uint8_t past_end[] = {5, 1, 2};
  CHECK(cobs_decode(past_end, 3, out, 8, k) == Error::kBadLength);
  const std::uint8_t code_zero[] = {0};
  CHECK(cobs_decode(code_zero, 1, out, 8, k) == Error::kBadLength);
  CHECK(cobs_decode(code_zero, 0, out, 8, k) == Error::kBadLength);
}
