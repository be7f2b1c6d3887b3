// tests/support: counts heap allocations (every operator new, and outside AddressSanitizer every
// malloc/calloc/realloc) so tests can assert that a pipeline call allocates nothing. The guard also
// switches off Eigen's run-time allocation permission (EIGEN_RUNTIME_NO_MALLOC), which asserts in
// builds without NDEBUG.
#pragma once

#include <cstdint>

namespace geojcbb::test {

std::uint64_t operator_new_calls();
std::uint64_t malloc_calls();
/// True when malloc-family calls are counted (not under AddressSanitizer, which owns malloc).
bool counts_malloc();

class AllocationGuard {
 public:
  AllocationGuard();
  ~AllocationGuard();
  AllocationGuard(const AllocationGuard&) = delete;
  AllocationGuard& operator=(const AllocationGuard&) = delete;
  /// Allocations (new + malloc) since construction.
  std::uint64_t allocations() const;

 private:
  std::uint64_t new0_;
  std::uint64_t malloc0_;
};

/// Allocations made while f() runs.
template <class F>
std::uint64_t allocations_during(F&& f) {
  AllocationGuard guard;
  f();
  return guard.allocations();
}

}  // namespace geojcbb::test
