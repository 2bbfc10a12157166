// Charts as SVG files, for the benchmark's graphs and a run's error.svg:
// lines (with points) on linear or log axes, and stacked bars. No
// dependency beyond the C++ library, so no plotting package is needed.
#ifndef RADIOSITY_SVG_H
#define RADIOSITY_SVG_H

#include <string>
#include <vector>

struct Axis {
  std::string label;
  std::vector<double> ticks;  // increasing; the first and last are the ends
  bool log = false;
};

struct Series {
  std::string name;
  std::vector<double> x, y;  // NaN y: no point there
  bool dashed = false;
  bool line = true;  // false: points only
  bool dots = true;  // a point at every value (false: many values, line only)
};

// Colours go round a fixed palette in series order. x_marks: dashed
// vertical lines at those x (events: a new wave).
bool WriteLineChart(const std::string& path, const std::string& title, const Axis& x,
                    const Axis& y, const std::vector<Series>& series, std::string* err,
                    const std::vector<double>& x_marks = {});

// groups[g] has a bar of parts stacked bottom up: values[g][p].
bool WriteStackedBars(const std::string& path, const std::string& title, const Axis& y,
                      const std::vector<std::string>& groups, const std::vector<std::string>& parts,
                      const std::vector<std::vector<double>>& values, std::string* err);

#endif
