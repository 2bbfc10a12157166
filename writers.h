// Files written on threads of their own while the master goes on (the
// pictures of a run, and its outputs at the end, app.cpp): what runs
// there and in what order is the caller's; this only starts, waits and
// keeps the first error.
#ifndef RADIOSITY_WRITERS_H
#define RADIOSITY_WRITERS_H

#include <cstddef>
#include <functional>
#include <list>
#include <string>
#include <thread>

// A wave's picture took 65-80 ms on the room, 45-60 of them encoding the
// PNG, time in which the master's loop fed no worker (bench/defaults.sh).
class Writers {
 public:
  Writers() = default;
  Writers(const Writers&) = delete;
  Writers& operator=(const Writers&) = delete;
  ~Writers() { Wait(); }
  // Runs `write` (false with *err on failure) on a thread of its own.
  void Start(std::function<bool(std::string* err)> write);
  // Waits for every write started; the first error, or "".
  std::string Wait();
  // Waits for the oldest writes until at most `keep` are running; the
  // first error of those, or "".
  std::string WaitOlder(size_t keep);

 private:
  struct Job {
    std::thread thread;
    std::string err;  // written by the job's thread only, read after join
  };
  std::list<Job> jobs_;  // a list: a running job's err stays where it is
};

#endif
