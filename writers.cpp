#include "writers.h"

#include <utility>

void Writers::Start(std::function<bool(std::string* err)> write) {
  jobs_.emplace_back();
  Job& job = jobs_.back();
  job.thread = std::thread([&job, write = std::move(write)] {
    if (!write(&job.err) && job.err.empty()) job.err = "cannot write an output";
  });
}

std::string Writers::Wait() { return WaitOlder(0); }

std::string Writers::WaitOlder(size_t keep) {
  std::string first;
  while (jobs_.size() > keep) {
    Job& job = jobs_.front();
    job.thread.join();
    if (first.empty()) first = job.err;
    jobs_.pop_front();
  }
  return first;
}
