// A thread that takes no signals: SIGINT, SIGTERM and the rest stop the
// run through the main thread's handler, whose blocking calls (poll,
// epoll_wait) they must interrupt; a helper thread that caught one would
// leave the main thread waiting out its timeout.
#ifndef RADIOSITY_QUIET_THREAD_H
#define RADIOSITY_QUIET_THREAD_H

#include <csignal>
#include <thread>
#include <utility>

#include <pthread.h>

template <class F>
std::thread QuietThread(F&& f) {
  sigset_t all, old;
  sigfillset(&all);
  ::pthread_sigmask(SIG_BLOCK, &all, &old);  // inherited by the thread
  std::thread t(std::forward<F>(f));
  ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
  return t;
}

#endif
