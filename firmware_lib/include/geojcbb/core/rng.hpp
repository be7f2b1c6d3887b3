// core: a tiny seeded pseudo-random generator for the randomized stages (RJC): PCG32 (O'Neill,
// "PCG: a family of simple fast space-efficient statistically good algorithms", 2014; the
// pcg32_random_r reference, XSH-RR output). No <random>, no heap, no state outside the object: the
// same seed gives the same sequence on every platform (32/64-bit integer arithmetic only).
#pragma once

#include <cstdint>

namespace geojcbb {

class Pcg32 {
 public:
  /// @param seed    initial state
  /// @param stream  sequence selector (any value; made odd)
  explicit Pcg32(std::uint64_t seed = 0x853c49e6748fea9bULL, std::uint64_t stream = 0xda3e39cb94b95bdbULL)
      : inc_((stream << 1u) | 1u) {
    next();
    state_ += seed;
    next();
  }

  /// The next 32 uniformly distributed bits.
  std::uint32_t next() {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<std::uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }

  /// An integer in [0, n), n >= 1, by Lemire's multiply-shift (bias below n / 2^32; no loop, so the
  /// cost is fixed).
  std::uint32_t below(std::uint32_t n) {
    return static_cast<std::uint32_t>((static_cast<std::uint64_t>(next()) * n) >> 32u);
  }

 private:
  std::uint64_t state_ = 0;
  std::uint64_t inc_;
};

}  // namespace geojcbb
