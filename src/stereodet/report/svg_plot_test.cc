#include "stereodet/report/svg_plot.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

namespace stereodet {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// The <polyline points="..."> of the SVG, each as a list of (x, y) pixel pairs.
std::vector<std::vector<std::pair<double, double>>> Polylines(const std::string& svg) {
  std::vector<std::vector<std::pair<double, double>>> lines;
  const std::regex polyline("<polyline[^>]* points=\"([^\"]*)\"");
  for (std::sregex_iterator it(svg.begin(), svg.end(), polyline), end; it != end; ++it) {
    std::vector<std::pair<double, double>> points;
    const std::string text = (*it)[1];
    const std::regex pair("(-?[0-9.]+),(-?[0-9.]+)");
    for (std::sregex_iterator p(text.begin(), text.end(), pair); p != end; ++p) {
      points.emplace_back(std::stod((*p)[1]), std::stod((*p)[2]));
    }
    lines.push_back(points);
  }
  return lines;
}

nlohmann::json Metadata(const std::string& svg) {
  const size_t begin = svg.find("<![CDATA[") + 9;
  const size_t end = svg.find("]]></metadata>");
  return nlohmann::json::parse(svg.substr(begin, end - begin));
}

Plot UnitPlot() {
  Plot p;
  p.id = "unit";
  p.title = "t";
  p.x_min = 0, p.x_max = 1, p.y_min = 0, p.y_max = 1;
  PlotSeries s;
  s.name = "diagonal";
  s.x = {0, 0.5, 1};
  s.y = {0, 0.5, 1};
  p.series.push_back(s);
  return p;
}

TEST(NiceTicksTest, MultiplesOfOneTwoFiveCoveringTheRange) {
  EXPECT_THAT(NiceTicks(0, 1), ElementsAre(0, 0.2, 0.4, ::testing::DoubleNear(0.6, 1e-12), 0.8, 1));
  EXPECT_THAT(NiceTicks(0, 37), ElementsAre(0, 10, 20, 30, 40));
  EXPECT_THAT(NiceTicks(-3, 3, 3), ElementsAre(-4, -2, 0, 2, 4));
  EXPECT_THROW(NiceTicks(1, 1), std::invalid_argument);
}

// A 480 x 340 plot has its area at x 64..464 and y 30..294 px: (0.5, 0.5) lands at (264, 162).
TEST(RenderSvgTest, PointsLandWhereTheFrameSays) {
  const Plot p = UnitPlot();
  const PlotFrame f = LayOutPlot(p);
  EXPECT_EQ(f.left, 64);
  EXPECT_EQ(f.right, 464);
  EXPECT_EQ(f.top, 30);
  EXPECT_EQ(f.bottom, 294);
  const auto lines = Polylines(RenderSvg(p));
  ASSERT_EQ(lines.size(), 1u);
  ASSERT_EQ(lines[0].size(), 3u);
  EXPECT_EQ(lines[0][0], std::make_pair(64.0, 294.0));
  EXPECT_EQ(lines[0][1], std::make_pair(264.0, 162.0));
  EXPECT_EQ(lines[0][2], std::make_pair(464.0, 30.0));
}

TEST(RenderSvgTest, NanBreaksTheLineAndStaysNullInTheData) {
  Plot p = UnitPlot();
  p.series[0].x = {0, 0.25, 0.5, 0.75, 1};
  p.series[0].y = {0, 0.25, NAN, 0.75, 1};
  const std::string svg = RenderSvg(p);
  const auto lines = Polylines(svg);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].size(), 2u);
  EXPECT_EQ(lines[1].size(), 2u);
  const nlohmann::json data = Metadata(svg);
  EXPECT_EQ(data["id"], "unit");
  EXPECT_TRUE(data["series"][0]["y"][2].is_null());
  EXPECT_EQ(data["series"][0]["y"][3], 0.75);
  EXPECT_EQ(data["series"][0]["x"].size(), 5u);
}

// Steps: across at the previous point's height, then up or down; a NaN still breaks the line. The
// data keeps the points as given, with "steps": true. x 0..1 -> 64..464 px, y 0..1 -> 294..30 px.
TEST(RenderSvgTest, StepsGoAcrossThenUpOrDown) {
  Plot p = UnitPlot();
  p.series[0].steps = true;
  p.series[0].x = {0, 0.5, 0.5, 1, NAN, 0, 1};
  p.series[0].y = {1, 1, 0.5, 0.25, 0, 0, 1};
  const std::string svg = RenderSvg(p);
  const auto lines = Polylines(svg);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_THAT(lines[0], ElementsAre(std::make_pair(64.0, 30.0), std::make_pair(264.0, 30.0),
                                    std::make_pair(264.0, 30.0), std::make_pair(264.0, 30.0),
                                    std::make_pair(264.0, 162.0), std::make_pair(464.0, 162.0),
                                    std::make_pair(464.0, 228.0)));
  EXPECT_THAT(lines[1], ElementsAre(std::make_pair(64.0, 294.0), std::make_pair(464.0, 294.0),
                                    std::make_pair(464.0, 30.0)));
  const nlohmann::json data = Metadata(svg);
  EXPECT_EQ(data["series"][0]["steps"], true);
  EXPECT_EQ(data["series"][0]["y"].size(), 7u);
  EXPECT_FALSE(Metadata(RenderSvg(UnitPlot()))["series"][0].contains("steps"));
}

TEST(RenderSvgTest, DashArraysForDashedAndDottedLines) {
  Plot p = UnitPlot();
  p.series.push_back(p.series[0]);
  p.series.push_back(p.series[0]);
  p.series[1].dashed = true;
  p.series[2].dash_array = "1.5,2.5";
  const std::string svg = RenderSvg(p);
  // Each series' polyline and its legend line.
  const std::regex dashed("stroke-dasharray=\"5,3\""), dotted("stroke-dasharray=\"1.5,2.5\"");
  EXPECT_EQ(
      std::distance(std::sregex_iterator(svg.begin(), svg.end(), dashed), std::sregex_iterator()),
      2);
  EXPECT_EQ(
      std::distance(std::sregex_iterator(svg.begin(), svg.end(), dotted), std::sregex_iterator()),
      2);
}

TEST(RenderSvgTest, RangesFromTheDataWidenToNiceTicks) {
  Plot p;
  p.id = "auto";
  PlotSeries s;
  s.x = {3, 37};
  s.y = {0.12, 0.31};
  p.series.push_back(s);
  const PlotFrame f = LayOutPlot(p);
  EXPECT_EQ(f.x_min, 0);
  EXPECT_EQ(f.x_max, 40);
  EXPECT_DOUBLE_EQ(f.y_min, 0.1);
  EXPECT_DOUBLE_EQ(f.y_max, 0.35);
}

TEST(RenderSvgTest, BarsStartAtZeroAndCategoriesLabelTheAxis) {
  Plot p;
  p.id = "bars";
  p.categories = {"Easy", "Hard"};
  PlotSeries s;
  s.style = SeriesStyle::kBars;
  s.name = "a";
  s.x = {0, 1};
  s.y = {0.5, 0.25};
  p.series.push_back(s);
  const PlotFrame f = LayOutPlot(p);
  EXPECT_EQ(f.y_min, 0);
  EXPECT_EQ(f.x_min, -0.5);
  EXPECT_EQ(f.x_max, 1.5);
  const std::string svg = RenderSvg(p);
  EXPECT_THAT(svg, HasSubstr(">Easy</text>"));
  EXPECT_THAT(svg, HasSubstr(">Hard</text>"));
  // The axis ends at the tallest bar (0.5 is a tick), so the first bar's top is the area's top.
  EXPECT_DOUBLE_EQ(f.y_max, 0.5);
  EXPECT_THAT(svg, HasSubstr(" y=\"30.00\" width="));
}

// A legend entry longer than the figure is wide wraps at spaces: (480 - 44) / 7 = 62 characters a
// line, one 17 px row each, and the SVG grows by the rows.
TEST(RenderSvgTest, LongLegendEntriesWrapAndTheFigureGrows) {
  Plot p = UnitPlot();
  p.series[0].name = std::string(40, 'a') + " " + std::string(40, 'b') + " c";
  const std::string svg = RenderSvg(p);
  EXPECT_THAT(svg, HasSubstr(">" + std::string(40, 'a') + "</text>"));
  EXPECT_THAT(svg, HasSubstr(">" + std::string(40, 'b') + " c</text>"));
  EXPECT_THAT(svg, HasSubstr("height=\"380.00\""));  // 340 + 2 x 17 + 6
  p.series[0].name = "short";
  EXPECT_THAT(RenderSvg(p), HasSubstr("height=\"363.00\""));  // 340 + 17 + 6
}

TEST(RenderSvgTest, EscapesTextAndChecksItsInput) {
  Plot p = UnitPlot();
  p.series[0].name = "A<B & \"C\"";
  EXPECT_THAT(RenderSvg(p), HasSubstr("A&lt;B &amp; &quot;C&quot;"));
  Plot bad_id = UnitPlot();
  bad_id.id = "a b";
  EXPECT_THROW(RenderSvg(bad_id), std::invalid_argument);
  Plot bad_length = UnitPlot();
  bad_length.series[0].y.pop_back();
  EXPECT_THROW(RenderSvg(bad_length), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
