#include "clock.h"

#include <chrono>
#include <ctime>

double MonotonicSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

namespace {
class Monotonic : public Clock {
 public:
  double Now() override { return MonotonicSeconds(); }
};
}  // namespace

Clock* MonotonicClock() {
  static Monotonic clock;
  return &clock;
}
