// error.svg: how a run's error fell against run time, from the rows of
// its log.csv (design.md, outputs).
#ifndef RADIOSITY_ERRORCHART_H
#define RADIOSITY_ERRORCHART_H

#include <string>
#include <vector>

#include "results.h"

// Unshot fraction, and RMS and relative RMS error where the rows have them,
// against seconds on a log y axis; a dashed vertical line where a wave
// starts. Values <= 0 cannot be drawn on a log axis and are left out.
bool WriteErrorChart(const std::string& path, const std::string& title,
                     const std::vector<LogRow>& rows, std::string* err);

// Tick values of a log axis: the powers of ten from below lo to above hi.
std::vector<double> LogTicks(double lo, double hi);
// Tick values of a linear axis from 0 to at least hi: 1, 2 or 5 × 10^k apart.
std::vector<double> LinearTicks(double hi);

#endif
