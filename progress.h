// Progress on stderr while the master runs: one line redrawn in place
// (\r) on a terminal, a plain line every few seconds otherwise, and the
// workers' comings and goings between them.
#ifndef RADIOSITY_PROGRESS_H
#define RADIOSITY_PROGRESS_H

#include <functional>
#include <string>
#include <vector>

#include "scheduler.h"

// One point of the unshot fraction against run time.
struct UnshotPoint {
  double seconds, unshot;
};

// Seconds from the last point until the unshot fraction falls below
// `target`, by a least-squares fit of log(unshot) against time through the
// points (progressive refinement falls about exponentially); 0 when the
// last point is already below; NaN when the points cannot tell (fewer
// than 3, no time between them, or not falling).
double EstimateRemaining(const std::vector<UnshotPoint>& points, double target);

// "7 s", "2:05", "1:02:03"; "?" for NaN or negative.
std::string FormatDuration(double seconds);

// What one progress line shows.
struct ProgressState {
  int wave = 1;
  long shots = 0;
  double shots_per_s = 0;   // NaN: not known yet
  double unshot = 1;
  bool has_rms = false;
  double rms = 0, rel_rms = 0;
  int workers = 0;          // alive; 0 with -j 0 (the master computes)
  double seconds = 0;
  double remaining = 0;     // NaN: not known
  double target = 1e-3;
};

// "wave 2 | 1234 shots | 850 shots/s | unshot 3.1e-03 | rms 1.2e-02 (2.5%)
//  | 2 workers | 0:12, ~5 s to 1e-03"
std::string FormatProgress(const ProgressState& s);

class Progress {
 public:
  // terminal: redraw one line in place; else a line every `interval`
  // seconds of run time. `out` receives the text (stderr in the program).
  Progress(std::function<void(const std::string&)> out, bool terminal, double target,
           double interval);

  // A progress sample (rms and rel_rms null without a reference).
  void Update(const Sample& s, const double* rms, const double* rel_rms);
  // A message line ("radiosity: " is added), printed above the progress line.
  void Note(const std::string& line);
  // Clears the line (the final summary follows).
  void Finish();

 private:
  void Draw(const std::string& line);
  void Clear();

  std::function<void(const std::string&)> out_;
  bool terminal_;
  double target_, interval_;
  double drawn_at_ = -1;            // run time of the last line; < 0: none yet
  size_t shown_ = 0;                // characters of the line on screen
  std::string last_;                // the line on screen, to redraw after a note
  int wave_ = 0;
  std::vector<UnshotPoint> points_;  // this wave's samples
  std::vector<std::pair<double, long>> rate_;  // (seconds, shots), recent
};

#endif
