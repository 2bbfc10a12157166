#include "progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

double EstimateRemaining(const std::vector<UnshotPoint>& points, double target) {
  if (points.empty()) return NAN;
  if (points.back().unshot < target) return 0;
  double n = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (const UnshotPoint& p : points) {
    if (!(p.unshot > 0)) continue;  // log of 0: the scene is done anyway
    const double y = std::log(p.unshot);
    n += 1;
    st += p.seconds;
    sy += y;
    stt += p.seconds * p.seconds;
    sty += p.seconds * y;
  }
  if (n < 3) return NAN;
  const double var = stt - st * st / n;
  const double span = points.back().seconds - points.front().seconds;
  if (!(span > 0) || !(var > 1e-12 * span * span)) return NAN;
  const double slope = (sty - st * sy / n) / var;
  if (!(slope < 0)) return NAN;
  const double at = (sy - slope * st) / n;  // log(unshot) at t = 0 on the fit
  const double when = (std::log(target) - at) / slope;
  return std::max(0.0, when - points.back().seconds);
}

std::string FormatDuration(double seconds) {
  if (!(seconds >= 0) || !std::isfinite(seconds)) return "?";
  char buf[32];
  const long s = std::lround(seconds);
  if (s < 60) std::snprintf(buf, sizeof buf, "%ld s", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  else std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  return buf;
}

std::string FormatProgress(const ProgressState& s) {
  char buf[256];
  std::string line;
  std::snprintf(buf, sizeof buf, "wave %d | %ld shots", s.wave, s.shots);
  line += buf;
  if (std::isfinite(s.shots_per_s)) {
    std::snprintf(buf, sizeof buf, " | %.0f shots/s", s.shots_per_s);
    line += buf;
  }
  std::snprintf(buf, sizeof buf, " | unshot %.1e", s.unshot);
  line += buf;
  if (s.has_rms) {
    std::snprintf(buf, sizeof buf, " | rms %.2e (%.2f%%)", s.rms, 100 * s.rel_rms);
    line += buf;
  }
  if (s.workers > 0) {
    std::snprintf(buf, sizeof buf, " | %d worker%s", s.workers, s.workers == 1 ? "" : "s");
    line += buf;
  } else {
    line += " | master alone";
  }
  std::snprintf(buf, sizeof buf, " | %s", FormatDuration(s.seconds).c_str());
  line += buf;
  // The estimate is to the target in this wave: a later wave starts again.
  if (s.unshot >= s.target) {
    std::snprintf(buf, sizeof buf, ", ~%s to %.0e", FormatDuration(s.remaining).c_str(),
                  s.target);
    line += buf;
  }
  return line;
}

Progress::Progress(std::function<void(const std::string&)> out, bool terminal, double target,
                   double interval)
    : out_(std::move(out)), terminal_(terminal), target_(target), interval_(interval) {}

void Progress::Update(const Sample& s, const double* rms, const double* rel_rms) {
  if (s.wave != wave_) {  // a new wave starts again from the emitters
    wave_ = s.wave;
    points_.clear();
  }
  points_.push_back({s.seconds, s.unshot});
  // A long run has many samples: keep every other of the older half.
  if (points_.size() > 4096) {
    std::vector<UnshotPoint> kept;
    for (size_t i = 0; i < points_.size(); ++i)
      if (i >= points_.size() / 2 || i % 2 == 0) kept.push_back(points_[i]);
    points_.swap(kept);
  }
  rate_.emplace_back(s.seconds, s.shots);
  while (rate_.size() > 2 && rate_[1].first < s.seconds - 3) rate_.erase(rate_.begin());

  // Nothing to tell before the first shot (workers may not have joined).
  if (s.shots == 0) return;
  if (drawn_at_ >= 0 && s.seconds - drawn_at_ < interval_) return;
  drawn_at_ = s.seconds;

  ProgressState st;
  st.wave = s.wave;
  st.shots = s.shots;
  const double dt = s.seconds - rate_.front().first;
  st.shots_per_s = dt > 0.2 ? double(s.shots - rate_.front().second) / dt
                   : s.seconds > 0.2 ? double(s.shots) / s.seconds
                                     : NAN;
  st.unshot = s.unshot;
  st.has_rms = rms != nullptr;
  if (rms) st.rms = *rms, st.rel_rms = *rel_rms;
  st.workers = s.workers;
  st.seconds = s.seconds;
  st.target = target_;
  // Fit the recent half of the wave: the early shots of the brightest
  // patches fall faster than the rest of the run will.
  const double since = points_.front().seconds;
  const double from = s.seconds - std::max(1.0, 0.5 * (s.seconds - since));
  auto first = std::find_if(points_.begin(), points_.end(),
                            [&](const UnshotPoint& p) { return p.seconds >= from; });
  if (points_.end() - first < 3) first = points_.end() - std::min<long>(8, long(points_.size()));
  st.remaining = EstimateRemaining(std::vector<UnshotPoint>(first, points_.end()), target_);
  Draw(FormatProgress(st));
}

void Progress::Draw(const std::string& line) {
  if (!terminal_) {
    out_("radiosity: " + line + "\n");
    return;
  }
  // Spaces over what is left of a longer line: no terminal escapes needed.
  std::string text = "\r" + line;
  if (line.size() < shown_) text += std::string(shown_ - line.size(), ' ') + "\r" + line;
  out_(text);
  shown_ = line.size();
  last_ = line;
}

void Progress::Clear() {
  if (terminal_ && shown_ > 0) out_("\r" + std::string(shown_, ' ') + "\r");
  shown_ = 0;
}

void Progress::Note(const std::string& line) {
  const std::string keep = last_;
  Clear();
  out_("radiosity: " + line + "\n");
  if (terminal_ && !keep.empty()) Draw(keep);
}

void Progress::Finish() {
  Clear();
  last_.clear();
}
