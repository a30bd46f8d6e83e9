// Shared helpers of the fuzz harnesses: a front-to-back reader of the input
// (so seeds are easy to write, see make_seeds.py) and a check that aborts,
// which libFuzzer reports as a crash with the input saved.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace fuzz {

// Little-endian reads from the front; zeros once the input is used up.
struct Reader {
  const uint8_t* p;
  std::size_t n;
  std::size_t remaining() const { return n; }
  uint64_t take(std::size_t bytes) {
    uint64_t v = 0;
    for (std::size_t i = 0; i < bytes; ++i) {
      if (n > 0) {
        v |= static_cast<uint64_t>(*p++) << (8 * i);
        --n;
      }
    }
    return v;
  }
  uint8_t u8() { return static_cast<uint8_t>(take(1)); }
  uint16_t u16() { return static_cast<uint16_t>(take(2)); }
  uint32_t u32() { return static_cast<uint32_t>(take(4)); }
  double f64() {
    const uint64_t bits = take(8);
    double d;
    std::memcpy(&d, &bits, sizeof d);
    return d;
  }
  // A time in ns: u16 in 0.1 ms steps, minus 0.1 ms (so -1e5 is reachable).
  int64_t time_ns() { return static_cast<int64_t>(u16()) * 100'000 - 100'000; }
};

inline void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz invariant broken: %s\n", what);
    std::abort();
  }
}

}  // namespace fuzz
