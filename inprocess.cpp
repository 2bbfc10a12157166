#include "inprocess.h"

#include "check.h"
#include "clock.h"

InProcessTransport::InProcessTransport(const Mesh& mesh, int resolution, bool rotate,
                                       unsigned seed)
    : mesh_(mesh), hemicube_(resolution), rotate_(rotate), seed_(seed) {}

void InProcessTransport::Assign(int w, const proto::Assignment& a) {
  CHECK(w == 0);
  todo_.push_back(a);
}

void InProcessTransport::Poll(double, std::vector<WorkerEvent>* events) {
  if (!joined_) {
    joined_ = true;
    events->push_back({WorkerEvent::kJoined, 0, {}, ""});
    return;
  }
  if (todo_.empty()) return;
  const proto::Assignment a = todo_.front();
  todo_.erase(todo_.begin());
  WorkerEvent ev{WorkerEvent::kColumn, 0, {}, ""};
  ev.column.ff = Spare();
  ev.column.patch = a.patch;
  ev.column.k = a.k;
  const double t0 = MonotonicSeconds();
  ShotColumn(&hemicube_, mesh_, a.patch, a.Group(), a.k, rotate_, seed_, &ev.column.ff);
  ev.column.compute_s = MonotonicSeconds() - t0;
  events->push_back(std::move(ev));
}

double InProcessTransport::Now() { return MonotonicSeconds(); }
