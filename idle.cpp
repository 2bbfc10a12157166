// Idle accounting: classes the workers' gaps by what the master did
// meanwhile. It knows times only; not workers, queues or sockets.
#include "idle.h"

#include <algorithm>

// A dry span open meanwhile is cut around the step, so that spans never
// overlap.
void IdleAccount::Busy(Cause cause, double t0, double t1) {
  if (dry_from_ >= 0) {
    if (t0 > dry_from_) spans_.push_back({dry_from_, t0, kDry});
    dry_from_ = t1;
  }
  spans_.push_back({t0, t1, cause});
}

void IdleAccount::Dry(bool dry, double now) {
  if (dry && dry_from_ < 0) dry_from_ = now;
  if (!dry && dry_from_ >= 0) {
    spans_.push_back({dry_from_, now, kDry});
    dry_from_ = -1;
  }
}

// Counted by the spans it overlaps, the latest first; the rest is
// `other`. Spans no gap can reach any more are dropped.
void IdleAccount::Count(double from, double to, double oldest) {
  while (!spans_.empty() && spans_.front().t1 <= oldest) spans_.pop_front();
  if (to <= from) return;
  double rest = to - from;
  auto add = [&](Cause cause, double t0, double t1) {
    const double o = std::min(to, t1) - std::max(from, t0);
    if (o <= 0) return;
    rest -= o;
    (cause == kPicture ? idle_.picture : cause == kPass ? idle_.pass : idle_.dry) += o;
  };
  if (dry_from_ >= 0) add(kDry, dry_from_, to);
  for (auto it = spans_.rbegin(); it != spans_.rend() && it->t1 > from; ++it)
    add(it->cause, it->t0, it->t1);
  idle_.other += std::max(0.0, rest);
}

double DoneAt(double free_at, double out, double compute_s, double polled, double now) {
  return std::clamp(std::max(free_at, out) + compute_s, std::min(polled, now), now);
}
