// The progress line: its text, the time estimate, and what reaches the
// terminal or the log.
#include "progress.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

namespace {

// unshot = exp(-rate * t), sampled every dt seconds up to t_end.
std::vector<UnshotPoint> Exponential(double rate, double dt, double t_end) {
  std::vector<UnshotPoint> p;
  for (double t = 0; t <= t_end + 1e-9; t += dt) p.push_back({t, std::exp(-rate * t)});
  return p;
}

TEST(EstimateRemaining, ExactOnAnExponentialFall) {
  // exp(-0.5 t) reaches 1e-3 at t = ln(1000) / 0.5 = 13.8155 s; at t = 4: 9.8155 s left.
  const double left = EstimateRemaining(Exponential(0.5, 0.25, 4), 1e-3);
  EXPECT_NEAR(left, std::log(1000.0) / 0.5 - 4, 1e-6);
}

TEST(EstimateRemaining, FollowsTheFitThroughNoise) {
  std::vector<UnshotPoint> p = Exponential(1.0, 0.1, 3);
  for (size_t i = 0; i < p.size(); ++i) p[i].unshot *= i % 2 ? 1.1 : 1 / 1.1;
  const double want = std::log(1000.0) - 3;  // 3.9 s
  EXPECT_NEAR(EstimateRemaining(p, 1e-3), want, 0.1 * want);
}

TEST(EstimateRemaining, ZeroWhenBelowTheTarget) {
  EXPECT_EQ(EstimateRemaining({{0, 1}, {1, 0.1}, {2, 1e-4}}, 1e-3), 0);
}

TEST(EstimateRemaining, UnknownWithoutAFall) {
  EXPECT_TRUE(std::isnan(EstimateRemaining({}, 1e-3)));
  EXPECT_TRUE(std::isnan(EstimateRemaining({{0, 1}, {1, 0.5}}, 1e-3)));        // two points
  EXPECT_TRUE(std::isnan(EstimateRemaining({{1, 1}, {1, 0.5}, {1, 0.2}}, 1e-3)));  // no time
  EXPECT_TRUE(std::isnan(EstimateRemaining({{0, 0.1}, {1, 0.1}, {2, 0.1}}, 1e-3)));  // flat
  EXPECT_TRUE(std::isnan(EstimateRemaining({{0, 0.1}, {1, 0.2}, {2, 0.4}}, 1e-3)));  // rising
}

TEST(FormatDuration, SecondsMinutesHours) {
  EXPECT_EQ(FormatDuration(0), "0 s");
  EXPECT_EQ(FormatDuration(7.4), "7 s");
  EXPECT_EQ(FormatDuration(125), "2:05");
  EXPECT_EQ(FormatDuration(3723), "1:02:03");
  EXPECT_EQ(FormatDuration(NAN), "?");
  EXPECT_EQ(FormatDuration(-1), "?");
}

TEST(FormatProgress, EveryField) {
  ProgressState s;
  s.wave = 2;
  s.shots = 1234;
  s.shots_per_s = 850.4;
  s.unshot = 3.14e-2;
  s.has_rms = true;
  s.rms = 0.0123;
  s.rel_rms = 0.025;
  s.workers = 2;
  s.seconds = 72;
  s.remaining = 5;
  s.target = 1e-3;
  EXPECT_EQ(FormatProgress(s),
            "wave 2 | 1234 shots | 850 shots/s | unshot 3.1e-02 | rms 1.23e-02 (2.50%) | "
            "2 workers | 1:12, ~5 s to 1e-03");
}

TEST(FormatProgress, LeavesOutWhatIsNotKnown) {
  ProgressState s;
  s.shots = 3;
  s.shots_per_s = NAN;
  s.unshot = 0.5;
  s.workers = 1;
  s.remaining = NAN;
  EXPECT_EQ(FormatProgress(s), "wave 1 | 3 shots | unshot 5.0e-01 | 1 worker | 0 s, ~? to 1e-03");
  s.workers = 0;
  s.unshot = 1e-4;  // below the target: no estimate
  EXPECT_EQ(FormatProgress(s), "wave 1 | 3 shots | unshot 1.0e-04 | master alone | 0 s");
}

Sample At(double t, long shots, double unshot, int wave = 1) {
  return Sample{t, shots, wave, 100, unshot, 2};
}

TEST(Progress, PlainLinesEveryInterval) {
  std::string out;
  Progress p([&](const std::string& s) { out += s; }, false, 1e-3, 2.0);
  for (int i = 0; i <= 50; ++i) p.Update(At(i / 10.0, 10 * i + 10, std::exp(-i / 10.0)), nullptr, nullptr);
  p.Finish();
  // Samples at 0, 2 and 4 s: three lines, no carriage return.
  int lines = 0;
  for (char c : out) lines += c == '\n';
  EXPECT_EQ(lines, 3) << out;
  EXPECT_EQ(out.find('\r'), std::string::npos);
  const std::string last =
      "radiosity: wave 1 | 410 shots | 100 shots/s | unshot 1.8e-02 | 2 workers | 4 s, ~3 s to 1e-03\n";
  ASSERT_GE(out.size(), last.size());
  EXPECT_EQ(out.substr(out.size() - last.size()), last) << out;
}

TEST(Progress, NothingBeforeTheFirstShot) {
  std::string out;
  Progress p([&](const std::string& s) { out += s; }, false, 1e-3, 0.0);
  p.Update(At(0, 0, 1), nullptr, nullptr);  // workers may not have joined yet
  EXPECT_EQ(out, "");
  p.Update(At(0.5, 1, 0.9), nullptr, nullptr);
  EXPECT_EQ(out.find("radiosity: wave 1 | 1 shots"), 0u) << out;
}

TEST(Progress, TerminalRedrawsOneLineAndNotesGoAbove) {
  std::string out;
  Progress p([&](const std::string& s) { out += s; }, true, 1e-3, 0.0);
  p.Update(At(0, 1, 1), nullptr, nullptr);
  p.Update(At(1, 10000, 0.5), nullptr, nullptr);
  const std::string before = out;
  EXPECT_EQ(before.find('\n'), std::string::npos);
  EXPECT_EQ(std::count(before.begin(), before.end(), '\r'), 2);
  p.Note("worker 3: joined");
  // The line is blanked, the note printed on its own line, the line redrawn.
  const std::string note = out.substr(before.size());
  EXPECT_EQ(note.find("\r"), 0u);
  EXPECT_NE(note.find("\rradiosity: worker 3: joined\n\rwave 1 | 10000 shots"), std::string::npos)
      << note;
  p.Finish();
  // Finish blanks the line: spaces, then back to the start.
  EXPECT_EQ(out.back(), '\r');
}

TEST(Progress, ShorterLineOverwritesTheLongerOne) {
  std::string out;
  Progress p([&](const std::string& s) { out += s; }, true, 1e-3, 0.0);
  const double rms = 1, rel = 1;
  p.Update(At(0, 1, 1), &rms, &rel);
  const size_t long_line = out.size() - 1;
  out.clear();
  p.Update(At(1, 5, 0.5), nullptr, nullptr);  // no rms: shorter
  // "\r" + short line + padding to the long line's length + "\r" + short line.
  const size_t second_cr = out.find('\r', 1);
  ASSERT_NE(second_cr, std::string::npos);
  EXPECT_EQ(second_cr - 1, long_line);
}

TEST(Progress, NewWaveRestartsTheEstimate) {
  std::string out;
  Progress p([&](const std::string& s) { out += s; }, false, 1e-3, 0.0);
  for (int i = 0; i < 10; ++i) p.Update(At(i, i, std::exp(-double(i))), nullptr, nullptr);
  out.clear();
  // Wave 2 starts again at 1 and has one point: the fit must not mix waves.
  p.Update(At(10, 10, 1, 2), nullptr, nullptr);
  EXPECT_NE(out.find("wave 2 |"), std::string::npos) << out;
  EXPECT_NE(out.find("~? to 1e-03"), std::string::npos) << out;
}

}  // namespace
