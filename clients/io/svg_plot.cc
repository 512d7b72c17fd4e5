#include "clients/io/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace localizer::io {
namespace {

// Room for the title (top), tick labels and axis names (left, bottom).
constexpr double kLeftPx = 60.0, kRightPx = 20.0, kTopPx = 40.0, kBottomPx = 50.0;
constexpr const char* kTruthColour = "#7f7f7f";
constexpr const char* kEstimateColour = "#d62728";
constexpr const char* kSensorColour = "#000000";

// The (horizontal, vertical) coordinates of a point in the view.
std::pair<double, double> Project(PlotView view, const engine::Vec3& p) {
  switch (view) {
    case PlotView::kXz:
      return {p.x(), p.z()};
    case PlotView::kYz:
      return {p.y(), p.z()};
    case PlotView::kXy:
      break;
  }
  return {p.x(), p.y()};
}

struct Frame {
  double u0 = 0, v0 = 0;  // data at the panel's lower-left corner, m
  double scale = 1;       // px per m
  double left = 0, bottom = 0, panel_w = 0, panel_h = 0;
};

Frame FrameFor(const PlotInput& in) {
  double u_lo = std::numeric_limits<double>::infinity(), u_hi = -u_lo, v_lo = u_lo, v_hi = -u_lo;
  for (const auto* points : {&in.truth_m, &in.estimates_m, &in.sensors_m}) {
    for (const engine::Vec3& p : *points) {
      if (!p.allFinite()) continue;
      const auto [u, v] = Project(in.view, p);
      u_lo = std::min(u_lo, u);
      u_hi = std::max(u_hi, u);
      v_lo = std::min(v_lo, v);
      v_hi = std::max(v_hi, v);
    }
  }
  if (!std::isfinite(u_lo)) u_lo = v_lo = -1.0, u_hi = v_hi = 1.0;  // nothing to draw
  const double span = std::max({u_hi - u_lo, v_hi - v_lo, 1e-3});
  const double pad = 0.05 * span;
  Frame f;
  f.left = kLeftPx;
  f.panel_w = std::max(1.0, in.width_px - kLeftPx - kRightPx);
  f.panel_h = std::max(1.0, in.height_px - kTopPx - kBottomPx);
  f.bottom = kTopPx + f.panel_h;
  f.scale = std::min(f.panel_w / (u_hi - u_lo + 2 * pad), f.panel_h / (v_hi - v_lo + 2 * pad));
  // Centre the data in the panel.
  f.u0 = 0.5 * (u_lo + u_hi) - 0.5 * f.panel_w / f.scale;
  f.v0 = 0.5 * (v_lo + v_hi) - 0.5 * f.panel_h / f.scale;
  return f;
}

std::pair<double, double> Pixel(const Frame& f, PlotView view, const engine::Vec3& p) {
  const auto [u, v] = Project(view, p);
  return {f.left + (u - f.u0) * f.scale, f.bottom - (v - f.v0) * f.scale};
}

// 1, 2 or 5 x 10^k, about `target` ticks over `span`.
double TickStep(double span, double target) {
  const double raw = span / target;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= raw) return m * power;
  }
  return 10.0 * power;
}

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

std::string Fmt(const char* format, double a, double b = 0.0) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, format, a, b);
  return buffer;
}

std::string Polyline(const Frame& f, PlotView view, const std::vector<engine::Vec3>& points, const char* colour,
                     double width_px) {
  std::string d;
  for (const engine::Vec3& p : points) {
    if (!p.allFinite()) continue;
    const auto [x, y] = Pixel(f, view, p);
    d += Fmt("%.2f,%.2f ", x, y);
  }
  if (d.empty()) return "";
  return std::string("<polyline fill=\"none\" stroke=\"") + colour + "\" stroke-width=\"" + Fmt("%.1f", width_px) +
         "\" points=\"" + d + "\"/>\n";
}

}  // namespace

engine::Vec3 SvgPixel(const PlotInput& input, const engine::Vec3& p_m) {
  const Frame f = FrameFor(input);
  const auto [x, y] = Pixel(f, input.view, p_m);
  return {x, y, 0.0};
}

std::string RenderSvgPlot(const PlotInput& in) {
  const Frame f = FrameFor(in);
  const char* names[3][2] = {{"x (m)", "y (m)"}, {"x (m)", "z (m)"}, {"y (m)", "z (m)"}};
  const int view = static_cast<int>(in.view);
  std::string svg = Fmt("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\"", in.width_px,
                        in.height_px) +
                    " font-family=\"sans-serif\" font-size=\"12\">\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  const double top = f.bottom - f.panel_h;
  svg += Fmt("<rect x=\"%.1f\" y=\"%.1f\"", f.left, top) + Fmt(" width=\"%.1f\" height=\"%.1f\"", f.panel_w, f.panel_h) +
         " fill=\"none\" stroke=\"#cccccc\"/>\n";
  // Ticks and grid.
  const double u_span = f.panel_w / f.scale, v_span = f.panel_h / f.scale;
  const double step = TickStep(std::max(u_span, v_span), 8.0);
  for (double u = std::ceil(f.u0 / step) * step; u <= f.u0 + u_span; u += step) {
    const double x = f.left + (u - f.u0) * f.scale;
    svg += Fmt("<line x1=\"%.1f\" x2=\"%.1f\"", x, x) + Fmt(" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#eeeeee\"/>\n", top, f.bottom);
    svg += Fmt("<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">", x, f.bottom + 16) +
           Fmt("%g</text>\n", std::abs(u) < 1e-9 * step ? 0.0 : u);
  }
  for (double v = std::ceil(f.v0 / step) * step; v <= f.v0 + v_span; v += step) {
    const double y = f.bottom - (v - f.v0) * f.scale;
    svg += Fmt("<line x1=\"%.1f\" x2=\"%.1f\"", f.left, f.left + f.panel_w) +
           Fmt(" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#eeeeee\"/>\n", y, y);
    svg += Fmt("<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">", f.left - 6, y + 4) +
           Fmt("%g</text>\n", std::abs(v) < 1e-9 * step ? 0.0 : v);
  }
  svg += Fmt("<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">", f.left + 0.5 * f.panel_w, f.bottom + 34) +
         names[view][0] + "</text>\n";
  svg += Fmt("<text x=\"14\" y=\"%.1f\" text-anchor=\"middle\"", top + 0.5 * f.panel_h) +
         Fmt(" transform=\"rotate(-90 14 %.1f)\">", top + 0.5 * f.panel_h) + names[view][1] + "</text>\n";
  svg += Fmt("<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\">", f.left, top - 12) + Escape(in.title) + "</text>\n";
  // Layers: truth, the estimates' line and dots, sensors; a legend.
  svg += Polyline(f, in.view, in.truth_m, kTruthColour, 2.0);
  svg += Polyline(f, in.view, in.estimates_m, kEstimateColour, 0.8);
  for (const engine::Vec3& p : in.estimates_m) {
    if (!p.allFinite()) continue;
    const auto [x, y] = Pixel(f, in.view, p);
    svg += Fmt("<circle cx=\"%.2f\" cy=\"%.2f\" r=\"3\" fill=\"", x, y) + kEstimateColour + "\"/>\n";
  }
  for (const engine::Vec3& p : in.sensors_m) {
    if (!p.allFinite()) continue;
    const auto [x, y] = Pixel(f, in.view, p);
    svg += Fmt("<polygon points=\"%.1f,%.1f ", x, y - 6) + Fmt("%.1f,%.1f ", x - 5, y + 4) + Fmt("%.1f,%.1f\"", x + 5, y + 4) +
           " fill=\"" + kSensorColour + "\"/>\n";
  }
  const double lx = f.left + f.panel_w - 150, ly = top + 14;
  svg += Fmt("<rect x=\"%.1f\" y=\"%.1f\" width=\"144\" height=\"52\" fill=\"#ffffff\" stroke=\"#cccccc\"/>\n", lx - 6, ly - 12);
  svg += Fmt("<line x1=\"%.1f\" x2=\"%.1f\"", lx, lx + 24) + Fmt(" y1=\"%.1f\" y2=\"%.1f\" stroke=\"", ly, ly) +
         kTruthColour + "\" stroke-width=\"2\"/>" + Fmt("<text x=\"%.1f\" y=\"%.1f\">truth</text>\n", lx + 30, ly + 4);
  svg += Fmt("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"", lx + 12, ly + 16) + kEstimateColour + "\"/>" +
         Fmt("<text x=\"%.1f\" y=\"%.1f\">estimates</text>\n", lx + 30, ly + 20);
  svg += Fmt("<polygon points=\"%.1f,%.1f ", lx + 12, ly + 26) + Fmt("%.1f,%.1f ", lx + 7, ly + 36) +
         Fmt("%.1f,%.1f\" fill=\"#000000\"/>", lx + 17, ly + 36) + Fmt("<text x=\"%.1f\" y=\"%.1f\">sensors</text>\n", lx + 30, ly + 36);
  svg += "</svg>\n";
  return svg;
}

}  // namespace localizer::io
