// Time, for the whole program: the monotonic clock for deadlines and the
// master's accounting, the thread's CPU clock for what a column costs, and
// a Clock interface for code that tests must be able to drive (the worker
// pool's heartbeats and deadlines).
#ifndef RADIOSITY_CLOCK_H
#define RADIOSITY_CLOCK_H

// Seconds of the monotonic clock: no system call (tens of ns).
double MonotonicSeconds();

// CPU seconds used by the calling thread: what a column costs, whatever
// else shares the processor. A system call (1-10 us on a virtual
// machine): not for timing work of a few microseconds.
double ThreadCpuSeconds();

// A source of seconds that only moves forward.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual double Now() = 0;
};

// MonotonicSeconds() as a Clock; shared, never deleted.
Clock* MonotonicClock();

#endif
