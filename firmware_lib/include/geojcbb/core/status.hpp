// core: the one list of outcomes every firmware_lib and protocol call returns.
// Errors are values; a function that returns anything but kOk has left its outputs untouched.
#pragma once

#include <cstdint>

namespace geojcbb {

enum class Status : std::uint8_t {
  kOk = 0,
  kNonFinite,            ///< a NaN or Inf in an input
  kInvalidInput,         ///< a value outside its domain (negative range, bad count, bad option)
  kCapacityExceeded,     ///< a count over a compile-time capacity
  kNotSymmetric,         ///< a covariance that is not symmetric (beyond rounding)
  kNotPositiveDefinite,  ///< a covariance that is not positive (semi)definite
  kNoConvergence,        ///< an iterative solver ran out of its iteration bound
};

/// Short stable name of a status, for logs and test messages (no allocation).
constexpr const char* to_string(Status s) {
  switch (s) {
    case Status::kOk: return "ok";
    case Status::kNonFinite: return "non-finite";
    case Status::kInvalidInput: return "invalid-input";
    case Status::kCapacityExceeded: return "capacity-exceeded";
    case Status::kNotSymmetric: return "not-symmetric";
    case Status::kNotPositiveDefinite: return "not-positive-definite";
    case Status::kNoConvergence: return "no-convergence";
  }
  return "unknown";
}

}  // namespace geojcbb
