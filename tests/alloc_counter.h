#pragma once
/// Counts heap allocations to prove hot paths allocate nothing. It replaces the global operator
/// new/delete, so include it in exactly one source file of a test binary:
///   g_allocations = 0; g_counting = true; <hot path>; g_counting = false;
///   EXPECT_EQ(g_allocations.load(), 0);
/// Eigen's heap goes through std::malloc, not operator new: define FORESIGHT_ALLOC_COUNTER_MALLOC
/// before the include to count malloc/calloc/realloc too. With glibc the executable interposes them
/// (the real allocator stays glibc's); under AddressSanitizer, which owns malloc, the counter is
/// its allocation hook (<sanitizer/allocator_interface.h>). Where malloc is counted,
/// FORESIGHT_COUNTS_MALLOC is defined. Either way operator new is counted twice (itself, then the
/// malloc it calls): the tests ask for zero or for a bound measured in the same build.

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

#if defined(FORESIGHT_ALLOC_COUNTER_MALLOC) && \
    (defined(__SANITIZE_ADDRESS__) || defined(FORESIGHT_SANITIZE))
#define FORESIGHT_COUNTS_MALLOC 1
#include <sanitizer/allocator_interface.h>
namespace {
void CountMalloc(const volatile void*, std::size_t) {
  if (g_counting) ++g_allocations;
}
void IgnoreFree(const volatile void*) {}
// Installed before main() (both hooks must be given); ASan calls it on every malloc, calloc,
// realloc and operator new.
[[maybe_unused]] const int g_malloc_hook_installed =
    __sanitizer_install_malloc_and_free_hooks(&CountMalloc, &IgnoreFree);
}  // namespace
#elif defined(FORESIGHT_ALLOC_COUNTER_MALLOC) && defined(__GLIBC__)
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
