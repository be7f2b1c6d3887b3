#include "alloc_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

#include <Eigen/Core>

namespace {
std::atomic<std::uint64_t> g_new{0};
std::atomic<std::uint64_t> g_malloc{0};
}  // namespace

#if defined(__SANITIZE_ADDRESS__)
#define GEOJCBB_TEST_COUNT_MALLOC 0
#else
#define GEOJCBB_TEST_COUNT_MALLOC 1
// glibc's own entry points: interposing malloc in the test executable counts every call made by
// any code in the process (libstdc++, Eigen, ours) and forwards it. An interposer uses glibc's
// reserved names (__libc_*), and its parameters keep <stdlib.h>'s names so that the definitions match
// the declarations they replace.
// NOLINTBEGIN(bugprone-reserved-identifier)
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void __libc_free(void*);
void* malloc(std::size_t __size) {
  g_malloc.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(__size);
}
void* calloc(std::size_t __nmemb, std::size_t __size) {
  g_malloc.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(__nmemb, __size);
}
void* realloc(void* __ptr, std::size_t __size) {
  g_malloc.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(__ptr, __size);
}
void free(void* __ptr) { __libc_free(__ptr); }
}
// NOLINTEND(bugprone-reserved-identifier)
#endif

namespace {
void* counted_new(std::size_t n) {
  g_new.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* counted_new_aligned(std::size_t n, std::align_val_t a) {
  g_new.fetch_add(1, std::memory_order_relaxed);
  const auto al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t n) { return counted_new(n); }
void* operator new[](std::size_t n) { return counted_new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return counted_new(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return counted_new(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t n, std::align_val_t a) { return counted_new_aligned(n, a); }
void* operator new[](std::size_t n, std::align_val_t a) { return counted_new_aligned(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace geojcbb::test {

std::uint64_t operator_new_calls() { return g_new.load(); }
std::uint64_t malloc_calls() { return g_malloc.load(); }
bool counts_malloc() { return GEOJCBB_TEST_COUNT_MALLOC != 0; }

AllocationGuard::AllocationGuard() : new0_(g_new.load()), malloc0_(g_malloc.load()) {
  Eigen::internal::set_is_malloc_allowed(false);
}
AllocationGuard::~AllocationGuard() { Eigen::internal::set_is_malloc_allowed(true); }
std::uint64_t AllocationGuard::allocations() const { return (g_new.load() - new0_) + (g_malloc.load() - malloc0_); }

}  // namespace geojcbb::test
