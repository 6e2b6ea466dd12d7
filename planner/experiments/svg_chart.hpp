// Line and grouped-bar charts as standalone SVG text: experiment plots that a reader opens in any
// browser, with no plotting toolchain to install. Output is deterministic for the same data.
#pragma once

#include <string>
#include <vector>

namespace corridor::planner {

struct ChartSeries {
  std::string label;
  std::vector<double> x;  // line charts only
  std::vector<double> y;
};

struct ChartText {
  std::string title;
  std::string x_label;
  std::string y_label;
};

// Throws std::invalid_argument when a series' x and y differ in length or hold no finite point.
std::string render_line_chart(const ChartText& text, const std::vector<ChartSeries>& series, bool y_from_zero = true);

// One group of bars per category, one bar per series; series[i].y[k] is its value in category k.
std::string render_bar_chart(const ChartText& text, const std::vector<std::string>& categories,
                             const std::vector<ChartSeries>& series);

// "Nice" axis ticks (1, 2, 2.5 or 5 times a power of ten) covering [lo, hi].
std::vector<double> nice_ticks(double lo, double hi, int target_count = 6);

}  // namespace corridor::planner
