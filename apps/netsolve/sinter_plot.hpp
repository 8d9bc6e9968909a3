#pragma once
// netsolve sinter's history.svg (sinter_plot.cpp).
#include <string>
#include <vector>

namespace netdem::app::netsolve {

/// The SVG of the run's history: shrinkage per axis (sx, sy, sz) and the mean neck against t.
std::string history_svg(const std::vector<double>& t, const std::vector<double>& sx, const std::vector<double>& sy,
                        const std::vector<double>& sz, const std::vector<double>& neck, const std::string& title);

}  // namespace netdem::app::netsolve
