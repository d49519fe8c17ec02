#pragma once
/// Counts heap allocations to prove hot paths allocate nothing. It replaces the global operator
/// new/delete, so include it in exactly one source file of a test binary:
///   g_allocations = 0; g_counting = true; <hot path>; g_counting = false;
///   EXPECT_EQ(g_allocations.load(), 0);
/// Eigen's heap goes through std::malloc, not operator new: define FORESIGHT_ALLOC_COUNTER_MALLOC
/// before the include to count malloc/calloc/realloc too (glibc lets the executable interpose them;
/// the real allocator stays glibc's). Not under AddressSanitizer, which owns malloc; where it is
/// counted, FORESIGHT_COUNTS_MALLOC is defined.

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
}  // namespace

#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
  if (g_counting) ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
// The nothrow forms too (std::stable_sort's buffer uses them): AddressSanitizer intercepts them
// itself, and its allocation freed by the free() above is an alloc-dealloc mismatch.
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  if (g_counting) ++g_allocations;
  return std::malloc(n ? n : 1);
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

#if defined(FORESIGHT_ALLOC_COUNTER_MALLOC) && defined(__GLIBC__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(FORESIGHT_SANITIZE)
#define FORESIGHT_COUNTS_MALLOC 1
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* malloc(std::size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  if (g_counting) ++g_allocations;
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_realloc(p, n);
}
}
#endif
