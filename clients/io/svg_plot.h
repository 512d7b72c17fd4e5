// A track drawn against its truth as an SVG picture, seen from above (x right, y up) or from
// a side: what `localizer-cli plot` writes, so an offline estimates CSV can be looked at
// without other tools (any browser opens it; `rsvg-convert` or Chromium make a PNG).
//
// One panel, equal metres per pixel on both axes (the picture is not stretched), the data's
// box padded by 5 %, ticks at 1, 2 or 5 x 10^k m with labels, and:
//   truth        a grey (#7f7f7f) line, 2 px
//   estimates    red (#d62728) dots, 3 px radius, joined by a thin red line
//   sensors      black (#000000) triangles, when given
//   the title    above (e.g. the file and the score)
// Non-finite points are skipped. Colours are fixed so that a test (and a reader) can find
// each layer by its colour.
#pragma once

#include <string>
#include <vector>

#include "engine/core/types.h"

namespace localizer::io {

enum class PlotView { kXy, kXz, kYz };  // the two axes shown: (x, y) from above, or a side

struct PlotInput {
  std::vector<engine::Vec3> truth_m;      // in time order
  std::vector<engine::Vec3> estimates_m;  // in time order
  std::vector<engine::Vec3> sensors_m;
  std::string title;
  PlotView view = PlotView::kXy;
  int width_px = 800, height_px = 800;  // the whole picture; each in [200, 10000]
};

// The SVG document. Points to pixels: see SvgPixel.
std::string RenderSvgPlot(const PlotInput& input);

// Where a point lands in the picture RenderSvgPlot draws for `input` (pixels from the
// top-left corner), for tests and for overlays.
engine::Vec3 SvgPixel(const PlotInput& input, const engine::Vec3& p_m);

}  // namespace localizer::io
