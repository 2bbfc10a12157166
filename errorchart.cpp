#include "errorchart.h"

#include <algorithm>
#include <cmath>

#include "svg.h"

std::vector<double> LogTicks(double lo, double hi) {
  if (!(lo > 0) || !(hi >= lo)) return {0.1, 1};
  int a = int(std::floor(std::log10(lo) + 1e-9)), b = int(std::ceil(std::log10(hi) - 1e-9));
  if (b <= a) b = a + 1;
  std::vector<double> t;
  for (int e = a; e <= b; ++e) t.push_back(std::pow(10.0, e));
  return t;
}

std::vector<double> LinearTicks(double hi) {
  if (!(hi > 0)) hi = 1;
  const double raw = hi / 5, mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) { step = m * mag; break; }
  std::vector<double> t;
  for (int i = 0; t.empty() || t.back() < hi * (1 - 1e-9); ++i) t.push_back(i * step);
  return t;
}

bool WriteErrorChart(const std::string& path, const std::string& title,
                     const std::vector<LogRow>& rows, std::string* err) {
  Series unshot{"unshot fraction", {}, {}}, rms{"RMS error", {}, {}},
      rel{"relative RMS error", {}, {}};
  std::vector<double> waves;
  double lo = HUGE_VAL, hi = 0, tmax = 0;
  auto add = [&](Series* s, double t, double v) {
    const bool ok = std::isfinite(v) && v > 0;
    s->x.push_back(t);
    s->y.push_back(ok ? v : NAN);
    if (ok) lo = std::min(lo, v), hi = std::max(hi, v);
  };
  for (size_t i = 0; i < rows.size(); ++i) {
    const LogRow& r = rows[i];
    if (i > 0 && r.wave != rows[i - 1].wave) waves.push_back(r.seconds);
    tmax = std::max(tmax, r.seconds);
    add(&unshot, r.seconds, r.unshot);
    add(&rms, r.seconds, r.rms);
    add(&rel, r.seconds, r.rel_rms);
  }
  std::vector<Series> series{unshot};
  auto any = [](const Series& s) {
    return std::any_of(s.y.begin(), s.y.end(), [](double v) { return std::isfinite(v); });
  };
  if (any(rms)) series.push_back(rms);
  if (any(rel)) series.push_back(rel);
  // Hundreds of samples: lines only, dots would hide them; a few: dots too.
  for (Series& s : series) s.dots = s.x.size() <= 40;
  const Axis x{"seconds", LinearTicks(tmax), false};
  const Axis y{waves.empty() ? "error" : "error (dashed: a new wave)", LogTicks(lo, hi), true};
  return WriteLineChart(path, title, x, y, series, err, waves);
}
