// netsolve sinter's history.svg: two linear panels (shrinkage per axis against t; mean neck
// against t), written without dependencies (sinter_plot.hpp).
#include "sinter_plot.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace netdem::app::netsolve {

namespace {

struct Series {
  std::vector<double> y;
  const char* colour;
  const char* label;
};

/// Round tick step for a range: 1, 2 or 5 x 10^k, about 5 ticks.
double tick_step(double range) {
  if (!(range > 0.0) || !std::isfinite(range)) return 1.0;
  const double raw = range / 5.0, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

std::string svg_panel(double ox, double W, double H, const std::vector<double>& t, const std::vector<Series>& ser, const char* ylabel) {
  const double L = ox + 70, R = ox + W - 15, T = 40, B = H - 50;
  double y0 = 0.0, y1 = 0.0;
  for (const auto& s : ser)
    for (double v : s.y)
      if (std::isfinite(v)) y0 = std::min(y0, v), y1 = std::max(y1, v);
  if (y1 <= y0) y1 = y0 + 1.0;
  const double t0 = t.empty() ? 0.0 : t.front(), t1 = t.empty() || t.back() <= t0 ? t0 + 1.0 : t.back();
  auto X = [&](double v) { return L + (v - t0) / (t1 - t0) * (R - L); };
  auto Y = [&](double v) { return B - (v - y0) / (y1 - y0) * (B - T); };
  std::string s = fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>\n", L, T, R - L, B - T);
  const double ts = tick_step(t1 - t0), ys = tick_step(y1 - y0);
  for (double v = std::ceil(t0 / ts) * ts; v <= t1 + 1e-9 * ts; v += ts)
    s += fmt::format("<line x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"{1}\" y2=\"{2}\" stroke=\"#ddd\"/><text x=\"{0:.1f}\" y=\"{3}\" "
                     "text-anchor=\"middle\">{4:g}</text>\n",
                     X(v), T, B, B + 16, v);
  for (double v = std::ceil(y0 / ys) * ys; v <= y1 + 1e-9 * ys; v += ys)
    s += fmt::format("<line x1=\"{0}\" x2=\"{1}\" y1=\"{2:.1f}\" y2=\"{2:.1f}\" stroke=\"#ddd\"/><text x=\"{3}\" y=\"{4:.1f}\" "
                     "text-anchor=\"end\">{5:.3g}</text>\n",
                     L, R, Y(v), L - 6, Y(v) + 4, std::fabs(v) < 1e-12 * ys ? 0.0 : v);
  s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">t [s]</text>\n", (L + R) / 2, H - 12);
  s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 {} {})\">{}</text>\n", ox + 16, (T + B) / 2,
                   ox + 16, (T + B) / 2, ylabel);
  int k = 0;
  for (const auto& se : ser) {
    std::string p;
    for (std::size_t i = 0; i < t.size() && i < se.y.size(); ++i)
      if (std::isfinite(se.y[i])) p += fmt::format("{:.1f},{:.1f} ", X(t[i]), Y(se.y[i]));
    s += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\" points=\"{}\"/>\n", se.colour, p);
    s += fmt::format("<line x1=\"{0}\" x2=\"{1}\" y1=\"{2}\" y2=\"{2}\" stroke=\"{3}\" stroke-width=\"2\"/><text x=\"{4}\" y=\"{5}\">{6}</text>\n",
                     L + 10, L + 40, T + 16 + 18 * k, se.colour, L + 46, T + 20 + 18 * k, se.label);
    ++k;
  }
  return s;
}

}  // namespace

std::string history_svg(const std::vector<double>& t, const std::vector<double>& sx, const std::vector<double>& sy,
                        const std::vector<double>& sz, const std::vector<double>& neck, const std::string& title) {
  const double W = 900, H = 420;
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" font-family=\"sans-serif\" font-size=\"12\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" text-anchor=\"middle\">{}</text>\n",
      W, H, W / 2, title);
  if (t.size() < 2) return s + "<text x=\"100\" y=\"200\">fewer than two rows to plot</text>\n</svg>\n";
  s += svg_panel(0, W / 2, H, t, {{sx, "#1f77b4", "shrink_x"}, {sy, "#2ca02c", "shrink_y"}, {sz, "#d62728", "shrink_z"}},
                 "shrinkage -F_ii (homogeneous strain)");
  s += svg_panel(W / 2, W / 2, H, t, {{neck, "#9467bd", "mean neck x / R_min"}}, "neck x / R_min");
  return s + "</svg>\n";
}

}  // namespace netdem::app::netsolve
