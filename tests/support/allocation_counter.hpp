// Counts heap allocations, so a test can show that a real-time path never
// allocates. Include it in exactly one file of a test program: it replaces
// the global operator new and delete of that program.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace rigctl::test {
inline std::atomic<long> g_allocations{0};
inline long allocation_count() { return g_allocations.load(std::memory_order_relaxed); }
}  // namespace rigctl::test

// Out of line so that the compiler does not pair an inlined free() with a
// `new` expression and warn about a mismatch: the pair is malloc/free here.
[[gnu::noinline]] void* operator new(std::size_t n) {
  rigctl::test::g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new[](std::size_t n) { return operator new(n); }
// The nothrow forms too (std::stable_sort's buffer uses them), so every
// allocation is counted and pairs with the free() below.
[[gnu::noinline]] void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  rigctl::test::g_allocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(n == 0 ? 1 : n);
}
[[gnu::noinline]] void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
[[gnu::noinline]] void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
