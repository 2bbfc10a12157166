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
// there after it is freed. In a process of its own (re-run from main, as
// the program calls MapLargeArrays first): one whose earlier tests freed
// large heap blocks before the call serves the 2 MB from those.
bool MappedAndGivenBack() {
  MapLargeArrays();
  std::free(Touched(8 * kMappedBytes));
  const size_t before = MappedBytes();
  void* p = Touched(2 * kMappedBytes);
  bool ok = MappedBytes() >= before + 2 * kMappedBytes;
  std::free(p);
  ok = ok && MappedBytes() == before;
  // Below the threshold: the heap's.
  void* small = Touched(kMappedBytes / 2);
  ok = ok && MappedBytes() == before;
  std::free(small);
  return ok;
}

TEST(MemoryDeathTest, LargeArraysAreMappedAndGivenBack) {
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "the sanitizer's allocator is not glibc's";
#endif
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(std::_Exit(MappedAndGivenBack() ? 0 : 1), testing::ExitedWithCode(0), "");
}

}  // namespace
