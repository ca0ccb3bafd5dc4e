// What the fuzz targets share: the libFuzzer entry point's declaration and a
// check that aborts (libFuzzer records the input as a crash; the replay
// driver's test fails) when a parser's own promise does not hold.
#ifndef PATHD_TESTS_FUZZ_FUZZ_CHECK_H_
#define PATHD_TESTS_FUZZ_FUZZ_CHECK_H_

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

// Not assert(): the fuzz build is optimised and may define NDEBUG.
#define PATHD_FUZZ_CHECK(cond, what)                                     \
  do {                                                                   \
    if (!(cond)) {                                                       \
      std::fprintf(stderr, "%s:%d: check failed: %s (%s)\n", __FILE__,   \
                   __LINE__, #cond, what);                               \
      std::abort();                                                      \
    }                                                                    \
  } while (false)

#endif  // PATHD_TESTS_FUZZ_FUZZ_CHECK_H_
