#include "memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>

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
