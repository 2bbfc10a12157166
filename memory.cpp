#include "memory.h"

#include <malloc.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <new>

namespace {

// The process's virtual size now (what ulimit -v counts): /proc/self/statm.
double VirtualSize() {
  std::ifstream in("/proc/self/statm");
  double pages = 0;
  in >> pages;
  return pages * double(sysconf(_SC_PAGESIZE));
}

}  // namespace

double UsableMemory() {
  double usable = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
  for (int which : {RLIMIT_AS, RLIMIT_DATA}) {
    rlimit r;
    if (getrlimit(which, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
      usable = std::min(usable, double(r.rlim_cur) - VirtualSize());
  }
  // cgroup v2: "max" or a byte count.
  std::ifstream cg("/sys/fs/cgroup/memory.max");
  double limit;
  if (cg >> limit) usable = std::min(usable, limit);
  return std::max(usable, 0.0);
}

void MapLargeArrays() { mallopt(M_MMAP_THRESHOLD, int(kMappedBytes)); }

void ReturnFreeMemory() { malloc_trim(0); }

bool FitsInMemory(double elements, double bytes_per_element, double usable, std::string* err) {
  const double need = elements * bytes_per_element;
  if (need <= usable) return true;
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "about %.3g elements would need about %.2f GB (%.0f bytes each), more than the "
                "%.2f GB this process may use",
                elements, need / 1e9, bytes_per_element, usable / 1e9);
  *err = buf;
  return false;
}

namespace {
constexpr uintptr_t kHuge = uintptr_t(2) << 20;
}  // namespace

void PreferHugePages(const void* p, size_t bytes) {
  const uintptr_t from = (uintptr_t(p) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t to = (uintptr_t(p) + bytes) & ~(kHuge - 1);
  if (from >= to) return;
  constexpr int kCollapse = 25;  // MADV_COLLAPSE: Linux's ABI; glibc 2.36 lacks the name
  // Advised, so that pages faulted in later are huge too; collapsed, so
  // that those already there are now (Linux 6.1 and later; earlier ones
  // leave them to khugepaged). Failures change nothing but speed.
  madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
  madvise(reinterpret_cast<void*>(from), to - from, kCollapse);
}

void* AllocateHuge(size_t bytes) {
  void* p = nullptr;
  if (posix_memalign(&p, bytes < kHuge ? 64 : kHuge, std::max<size_t>(bytes, 1)) != 0)
    throw std::bad_alloc();
  // Before the first touch, so that the whole 2 MB pages are faulted in
  // huge; the tail stays in small pages (no more resident than asked).
  if (bytes >= kHuge) madvise(p, bytes & ~(kHuge - 1), MADV_HUGEPAGE);
  return p;
}
