// error.svg: the axes' ticks, which series are drawn, the wave marks.
#include "errorchart.h"

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

namespace {

int Count(const std::string& s, const std::string& what) {
  int n = 0;
  for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

std::string Chart(const std::vector<LogRow>& rows) {
  char tmpl[] = "/tmp/errorchart_test.XXXXXX";
  const int fd = mkstemp(tmpl);
  EXPECT_GE(fd, 0);
  close(fd);
  std::string err;
  EXPECT_TRUE(WriteErrorChart(tmpl, "t", rows, &err)) << err;
  std::ifstream f(tmpl);
  std::string s((std::istreambuf_iterator<char>(f)), {});
  unlink(tmpl);
  return s;
}

TEST(ErrorChart, LogTicksCoverTheDecades) {
  EXPECT_EQ(LogTicks(0.003, 0.5), (std::vector<double>{1e-3, 1e-2, 1e-1, 1}));
  EXPECT_EQ(LogTicks(1e-3, 1e-3).size(), 2u);  // one value: still two ends
  EXPECT_EQ(LogTicks(NAN, 1), (std::vector<double>{0.1, 1}));  // nothing to draw
}

TEST(ErrorChart, LinearTicksOneTwoFive) {
  EXPECT_EQ(LinearTicks(12.7), (std::vector<double>{0, 5, 10, 15}));
  EXPECT_EQ(LinearTicks(4), (std::vector<double>{0, 1, 2, 3, 4}));
  EXPECT_EQ(LinearTicks(0).back(), 1);
}

TEST(ErrorChart, UnshotAloneWithoutAReference) {
  const std::vector<LogRow> rows = {{0, 0, 1, 10, 1, NAN, NAN},
                                    {1, 10, 1, 10, 0.1, NAN, NAN},
                                    {2, 20, 2, 40, 1, NAN, NAN},  // a new wave
                                    {3, 30, 2, 40, 0.01, NAN, NAN},
                                    {4, 40, 2, 40, 0, NAN, NAN}};  // 0: not on a log axis
  const std::string svg = Chart(rows);
  EXPECT_EQ(Count(svg, "<polyline"), 1);
  EXPECT_EQ(Count(svg, ">unshot fraction<"), 1);
  EXPECT_EQ(Count(svg, "RMS"), 0);
  EXPECT_EQ(Count(svg, "stroke-dasharray=\"3 3\""), 1);  // one new wave
  EXPECT_EQ(Count(svg, "<circle"), 5);  // few samples: 4 dots (not the 0) and the legend's
  EXPECT_EQ(svg.rfind("</svg>\n"), svg.size() - 7);
}

TEST(ErrorChart, ThreeSeriesWithAReference) {
  std::vector<LogRow> rows;
  for (int i = 0; i < 100; ++i)
    rows.push_back({0.1 * i, 10L * i, 1, 10, std::exp(-0.1 * i), 0.5 * std::exp(-0.1 * i),
                    0.2 * std::exp(-0.1 * i)});
  const std::string svg = Chart(rows);
  EXPECT_EQ(Count(svg, "<polyline"), 3);
  EXPECT_EQ(Count(svg, ">RMS error<"), 1);
  EXPECT_EQ(Count(svg, ">relative RMS error<"), 1);
  EXPECT_EQ(Count(svg, "stroke-dasharray=\"3 3\""), 0);
  EXPECT_EQ(Count(svg, "<circle"), 0);  // many samples: lines only
}

}  // namespace
