#include "svg.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "files.h"

namespace {

constexpr double kWidth = 720, kHeight = 440;
constexpr double kLeft = 70, kRight = 200, kTop = 40, kBottom = 60;  // margins; legend right
constexpr int kColors = 10;
const char* const kPalette[kColors] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                       "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"};

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else out += c;
  }
  return out;
}

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Maps values on an axis to pixels between a and b.
struct Scale {
  const Axis& axis;
  double a, b;
  double operator()(double v) const {
    const double lo = axis.ticks.front(), hi = axis.ticks.back();
    const double u = axis.log ? std::log(v / lo) / std::log(hi / lo) : (v - lo) / (hi - lo);
    return a + (b - a) * u;
  }
};

// The frame: title, axes with ticks, grid and labels.
std::string Frame(const std::string& title, const Scale* x, const Scale& y) {
  std::string s;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%g\" height=\"%g\" "
                "font-family=\"sans-serif\" font-size=\"12\">\n"
                "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n"
                "<text x=\"%g\" y=\"22\" font-size=\"15\" text-anchor=\"middle\">%s</text>\n",
                kWidth, kHeight, (kLeft + kWidth - kRight) / 2, Escape(title).c_str());
  s += buf;
  const double x0 = kLeft, x1 = kWidth - kRight, y0 = kHeight - kBottom, y1 = kTop;
  // Lines that leave the axes' range are cut at the frame.
  std::snprintf(buf, sizeof buf,
                "<clipPath id=\"plot\"><rect x=\"%g\" y=\"%g\" width=\"%g\" height=\"%g\"/>"
                "</clipPath>\n",
                x0, y1, x1 - x0, y0 - y1);
  s += buf;
  for (double t : y.axis.ticks) {
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%g\" y1=\"%.1f\" x2=\"%g\" y2=\"%.1f\" stroke=\"#ddd\"/>"
                  "<text x=\"%g\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n",
                  x0, y(t), x1, y(t), x0 - 6, y(t) + 4, Num(t).c_str());
    s += buf;
  }
  if (x)
    for (double t : x->axis.ticks) {
      std::snprintf(buf, sizeof buf,
                    "<line x1=\"%.1f\" y1=\"%g\" x2=\"%.1f\" y2=\"%g\" stroke=\"#ddd\"/>"
                    "<text x=\"%.1f\" y=\"%g\" text-anchor=\"middle\">%s</text>\n",
                    (*x)(t), y0, (*x)(t), y1, (*x)(t), y0 + 18, Num(t).c_str());
      s += buf;
    }
  std::snprintf(buf, sizeof buf,
                "<rect x=\"%g\" y=\"%g\" width=\"%g\" height=\"%g\" fill=\"none\" stroke=\"black\"/>\n"
                "<text x=\"%g\" y=\"%g\" text-anchor=\"middle\">%s</text>\n"
                "<text transform=\"translate(18 %g) rotate(-90)\" text-anchor=\"middle\">%s</text>\n",
                x0, y1, x1 - x0, y0 - y1, (x0 + x1) / 2, kHeight - 18,
                x ? Escape(x->axis.label).c_str() : "", (y0 + y1) / 2,
                Escape(y.axis.label).c_str());
  s += buf;
  return s;
}

std::string LegendEntry(int i, const std::string& name, const std::string& mark) {
  char buf[512];
  const double x = kWidth - kRight + 12, y = kTop + 10 + 18 * i;
  std::snprintf(buf, sizeof buf, "<g transform=\"translate(%g %g)\">%s</g>"
                "<text x=\"%g\" y=\"%g\">%s</text>\n",
                x, y, mark.c_str(), x + 30, y + 4, Escape(name).c_str());
  return buf;
}

bool Save(const std::string& path, const std::string& svg, std::string* err) {
  return WriteFileAtomic(path, svg, err);
}

}  // namespace

bool WriteLineChart(const std::string& path, const std::string& title, const Axis& x,
                    const Axis& y, const std::vector<Series>& series, std::string* err,
                    const std::vector<double>& x_marks) {
  const Scale sx{x, kLeft, kWidth - kRight}, sy{y, kHeight - kBottom, kTop};
  std::string s = Frame(title, &sx, sy);
  char buf[256];
  for (double m : x_marks) {
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%g\" x2=\"%.1f\" y2=\"%g\" stroke=\"#999\" "
                  "stroke-dasharray=\"3 3\"/>\n",
                  sx(m), kHeight - kBottom, sx(m), kTop);
    s += buf;
  }
  for (size_t i = 0; i < series.size(); ++i) {
    const Series& se = series[i];
    const char* color = kPalette[i % kColors];
    const std::string dash = se.dashed ? " stroke-dasharray=\"6 4\"" : "";
    std::string pts;
    for (size_t k = 0; k < se.x.size(); ++k) {
      if (!std::isfinite(se.y[k])) continue;
      std::snprintf(buf, sizeof buf, "%.1f,%.1f ", sx(se.x[k]), sy(se.y[k]));
      pts += buf;
      if (!se.dots) continue;
      std::snprintf(buf, sizeof buf,
                    "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"%s\" clip-path=\"url(#plot)\"/>\n",
                    sx(se.x[k]), sy(se.y[k]), color);
      s += buf;
    }
    if (se.line)
      s += "<polyline fill=\"none\" stroke=\"" + std::string(color) + "\" stroke-width=\"1.5\"" +
           dash + " clip-path=\"url(#plot)\" points=\"" + pts + "\"/>\n";
    std::string mark =
        se.dots ? "<circle cx=\"12\" cy=\"0\" r=\"3\" fill=\"" + std::string(color) + "\"/>" : "";
    if (se.line)
      mark += "<line x1=\"0\" y1=\"0\" x2=\"24\" y2=\"0\" stroke=\"" + std::string(color) +
              "\" stroke-width=\"1.5\"" + dash + "/>";
    s += LegendEntry(int(i), se.name, mark);
  }
  return Save(path, s + "</svg>\n", err);
}

bool WriteStackedBars(const std::string& path, const std::string& title, const Axis& y,
                      const std::vector<std::string>& groups, const std::vector<std::string>& parts,
                      const std::vector<std::vector<double>>& values, std::string* err) {
  const Scale sy{y, kHeight - kBottom, kTop};
  std::string s = Frame(title, nullptr, sy);
  const double slot = (kWidth - kRight - kLeft) / double(groups.size());
  char buf[512];
  for (size_t g = 0; g < groups.size(); ++g) {
    const double x = kLeft + slot * (double(g) + 0.25);
    double base = 0;
    for (size_t p = 0; p < parts.size(); ++p) {
      const double top = base + values[g][p];
      std::snprintf(buf, sizeof buf,
                    "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"/>\n",
                    x, sy(top), slot / 2, sy(base) - sy(top), kPalette[p % kColors]);
      s += buf;
      base = top;
    }
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%g\" text-anchor=\"middle\">%s</text>\n",
                  x + slot / 4, kHeight - kBottom + 18, Escape(groups[g]).c_str());
    s += buf;
  }
  for (size_t p = 0; p < parts.size(); ++p)
    s += LegendEntry(int(p), parts[p],
                     "<rect x=\"0\" y=\"-6\" width=\"24\" height=\"12\" fill=\"" +
                         std::string(kPalette[p % kColors]) + "\"/>");
  return Save(path, s + "</svg>\n", err);
}
