// memory.h: how large arrays are allocated.
#include "memory.h"

#include <malloc.h>

#include <cstdlib>
#include <cstring>

#include <gtest/gtest.h>

namespace {

// Where the blocks go, so that the compiler keeps each malloc and free.
void* volatile g_sink;

void* Touched(size_t bytes) {
  void* p = std::malloc(bytes);
  std::memset(p, 1, bytes);
  g_sink = p;
  return p;
}

// Bytes in mappings of their own now.
size_t MappedBytes() { return mallinfo2().hblkhd; }

// glibc alone would take the 2 MB block from the heap once an 8 MB one
// had been freed (its threshold rises to 8 MB), and keep it resident
// there after it is freed.
TEST(Memory, LargeArraysAreMappedAndGivenBack) {
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "the sanitizer's allocator is not glibc's";
#endif
  MapLargeArrays();
  std::free(Touched(8 * kMappedBytes));
  const size_t before = MappedBytes();
  void* p = Touched(2 * kMappedBytes);
  EXPECT_GE(MappedBytes(), before + 2 * kMappedBytes);
  std::free(p);
  EXPECT_EQ(MappedBytes(), before);
  // Below the threshold: the heap's.
  void* small = Touched(kMappedBytes / 2);
  EXPECT_EQ(MappedBytes(), before);
  std::free(small);
}

}  // namespace
