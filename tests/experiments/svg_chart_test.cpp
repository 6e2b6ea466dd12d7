#include "planner/experiments/svg_chart.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace corridor::planner {
namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

TEST(SvgChart, NiceTicksCoverTheRangeWithRoundSteps) {
  EXPECT_EQ(nice_ticks(0.0, 10.0), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  EXPECT_EQ(nice_ticks(0.0, 23.3), (std::vector<double>{0, 5, 10, 15, 20, 25}));
  EXPECT_EQ(nice_ticks(0.0, 0.9), (std::vector<double>{0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0}));
  const auto t = nice_ticks(-37.0, 512.0);
  EXPECT_LE(t.front(), -37.0);
  EXPECT_GE(t.back(), 512.0);
  EXPECT_THROW(nice_ticks(1.0, std::nan("")), std::invalid_argument);
}

TEST(SvgChart, LineChartDrawsOneLinePerSeriesWithLegendAndEscapedText) {
  const std::string svg = render_line_chart({"a < b & c", "x", "y"}, {{"static", {0, 1, 2}, {3, 4, 5}},
                                                                     {"dynamic", {0, 1, 2}, {3, 3, 3}}});
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(count(svg, "<polyline"), 2u);
  EXPECT_EQ(count(svg, "<circle"), 6u);
  EXPECT_NE(svg.find("a &lt; b &amp; c"), std::string::npos);
  EXPECT_NE(svg.find(">dynamic<"), std::string::npos);
  EXPECT_THROW(render_line_chart({"t", "x", "y"}, {{"bad", {0, 1}, {1}}}), std::invalid_argument);
  EXPECT_THROW(render_line_chart({"t", "x", "y"}, {{"empty", {}, {}}}), std::invalid_argument);
}

TEST(SvgChart, BarChartDrawsOneBarPerValueAndTheSameDataGivesTheSameText) {
  const std::vector<ChartSeries> series{{"s", {}, {10, 20, 30}}, {"d", {}, {5, 15, std::nan("")}}};
  const std::string svg = render_bar_chart({"t", "pair", "%"}, {"A-B", "C-D", "E-F"}, series);
  EXPECT_EQ(count(svg, "<rect x="), 5u + 1u + 2u);  // bars, plot frame, legend swatches
  EXPECT_EQ(svg, render_bar_chart({"t", "pair", "%"}, {"A-B", "C-D", "E-F"}, series));
  EXPECT_THROW(render_bar_chart({"t", "", ""}, {"A"}, series), std::invalid_argument);
}

}  // namespace
}  // namespace corridor::planner
