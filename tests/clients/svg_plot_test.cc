// localizer-cli plot's picture (clients/io/svg_plot.h): every estimate is drawn where it is,
// on the same scale in both axes, beside its truth, each layer in its stated colour.
#include "clients/io/svg_plot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <regex>
#include <string>
#include <vector>

namespace localizer::io {
namespace {

struct Dot {
  double x, y;
};

// The red dots (estimates; the legend's dot is the last one).
std::vector<Dot> RedDots(const std::string& svg) {
  std::vector<Dot> dots;
  const std::regex circle(R"re(<circle cx="([-0-9.]+)" cy="([-0-9.]+)" r="3" fill="#d62728"/>)re");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), circle); it != std::sregex_iterator(); ++it) {
    dots.push_back({std::stod((*it)[1]), std::stod((*it)[2])});
  }
  return dots;
}

PlotInput Circle(PlotView view = PlotView::kXy) {
  PlotInput in;
  in.view = view;
  in.width_px = 600;
  in.height_px = 500;
  for (int k = 0; k < 200; ++k) {  // a 5 m circle about (2, -3), at z = -8
    const double a = 2.0 * std::numbers::pi * k / 200.0;
    in.truth_m.push_back(engine::Vec3(2.0 + 5.0 * std::cos(a), -3.0 + 5.0 * std::sin(a), -8.0));
  }
  for (int k = 0; k < 200; k += 10) {  // every tenth, 0.1 m outwards
    const double a = 2.0 * std::numbers::pi * k / 200.0;
    in.estimates_m.push_back(engine::Vec3(2.0 + 5.1 * std::cos(a), -3.0 + 5.1 * std::sin(a), -8.0));
  }
  in.sensors_m = {engine::Vec3(0, 0, -8), engine::Vec3(1, 0, -8), engine::Vec3(0, 1, -8)};
  in.title = "a <circle> & its truth";
  return in;
}

TEST(SvgPlot, EveryEstimateIsDrawnWhereItIsBesideItsTruth) {
  const PlotInput in = Circle();
  const std::string svg = RenderSvgPlot(in);
  EXPECT_NE(svg.find("width=\"600\" height=\"500\""), std::string::npos);
  EXPECT_NE(svg.find("a &lt;circle&gt; &amp; its truth"), std::string::npos) << "the title is escaped";
  EXPECT_NE(svg.find("stroke=\"#7f7f7f\" stroke-width=\"2.0\""), std::string::npos) << "the truth line";
  const std::vector<Dot> dots = RedDots(svg);
  ASSERT_EQ(dots.size(), in.estimates_m.size() + 1);  // + the legend's
  // Equal scale: a metre is as many pixels across as up (y grows downwards in SVG).
  const engine::Vec3 o = SvgPixel(in, engine::Vec3::Zero());
  const double px_per_m = SvgPixel(in, engine::Vec3::UnitX()).x() - o.x();
  EXPECT_GT(px_per_m, 10.0);
  EXPECT_NEAR(o.y() - SvgPixel(in, engine::Vec3::UnitY()).y(), px_per_m, 1e-9);
  for (size_t i = 0; i < in.estimates_m.size(); ++i) {
    const engine::Vec3 at = SvgPixel(in, in.estimates_m[i]);
    EXPECT_NEAR(dots[i].x, at.x(), 0.01);
    EXPECT_NEAR(dots[i].y, at.y(), 0.01);
    EXPECT_GT(dots[i].x, 60.0);  // inside the panel
    EXPECT_LT(dots[i].x, in.width_px - 20.0);
    EXPECT_GT(dots[i].y, 40.0);
    EXPECT_LT(dots[i].y, in.height_px - 50.0);
    // 0.1 m from the truth circle, as drawn: within 0.1 m x the scale plus half a pixel.
    const engine::Vec3 centre = SvgPixel(in, engine::Vec3(2.0, -3.0, -8.0));
    const double r_px = std::hypot(dots[i].x - centre.x(), dots[i].y - centre.y());
    EXPECT_NEAR(r_px, 5.1 * px_per_m, 0.02);
  }
  EXPECT_NE(svg.find("fill=\"#000000\"/>"), std::string::npos) << "sensors";
}

TEST(SvgPlot, SideViewsShowDepthAndSkipNonFinitePoints) {
  PlotInput in = Circle(PlotView::kXz);
  in.estimates_m.push_back(engine::Vec3(NAN, 0.0, 0.0));
  const std::string svg = RenderSvgPlot(in);
  EXPECT_NE(svg.find("z (m)"), std::string::npos);
  EXPECT_EQ(RedDots(svg).size(), in.estimates_m.size());  // the NaN one left out, the legend's in
  // From the side every point of the flat circle sits at one height.
  const double y = SvgPixel(in, in.truth_m[0]).y();
  for (const engine::Vec3& p : in.truth_m) EXPECT_NEAR(SvgPixel(in, p).y(), y, 1e-9);
}

TEST(SvgPlot, NothingToDrawStillGivesAPicture) {
  PlotInput in;
  const std::string svg = RenderSvgPlot(in);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}

}  // namespace
}  // namespace localizer::io
