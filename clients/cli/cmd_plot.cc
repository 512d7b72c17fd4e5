// localizer-cli plot: an estimates CSV drawn against its truth as an SVG picture.
#include <fstream>
#include <iostream>

#include "clients/cli/commands.h"
#include "clients/io/array_json.h"
#include "clients/io/csv_io.h"
#include "clients/io/score.h"
#include "clients/io/svg_plot.h"

namespace localizer::cli {

int RunPlot(const std::vector<std::string>& args) {
  const std::string command = "plot";
  std::string estimates_path, truth_path, array_path, out_path, view_name = "xy";
  int width_px = 800, height_px = 800;
  FlagSet flags("localizer-cli plot --estimates FILE [--truth FILE] [--array FILE] --out FILE.svg [--view xy|xz|yz]",
                "Draws the initialised positions of an estimates CSV (red dots joined by a thin line)\n"
                "against the truth CSV's track (grey) and the array's sensors (black triangles), seen\n"
                "from above (xy) or from a side (xz, yz), with equal scales on both axes, as SVG. With\n"
                "--truth the title carries the score (as `score` prints it). Open the file in a browser;\n"
                "`rsvg-convert -o track.png track.svg` or headless Chromium make a PNG.");
  flags.String("estimates", &estimates_path, "FILE", "estimates CSV written by track or simulate").Required();
  flags.String("truth", &truth_path, "FILE", "truth CSV written by simulate (optional)");
  flags.String("array", &array_path, "FILE", "array.json or the XAV CSV, to draw the sensors (optional)");
  flags.String("out", &out_path, "FILE", "SVG file to write").Required();
  flags.String("view", &view_name, "VIEW", "xy (from above), xz or yz (from a side)");
  flags.Int("width", &width_px, "PX", "px", "picture width, [200, 10000]");
  flags.Int("height", &height_px, "PX", "px", "picture height, [200, 10000]");
  if (auto exit_code = ParseFlagsOrExit(command, flags, args)) return *exit_code;
  io::PlotInput in;
  if (view_name == "xy") {
    in.view = io::PlotView::kXy;
  } else if (view_name == "xz") {
    in.view = io::PlotView::kXz;
  } else if (view_name == "yz") {
    in.view = io::PlotView::kYz;
  } else {
    return UsageError(command, "--view must be xy, xz or yz, got \"" + view_name + "\"");
  }
  if (width_px < 200 || width_px > 10000 || height_px < 200 || height_px > 10000) {
    return UsageError(command, "--width and --height must be in [200, 10000] px");
  }
  in.width_px = width_px;
  in.height_px = height_px;

  auto estimates = io::ReadEstimatesCsv(estimates_path);
  if (!estimates.ok()) return RuntimeError(command, estimates.status());
  for (const io::EstimateRow& row : *estimates) {
    if (row.initialised) in.estimates_m.push_back(row.position_m);
  }
  in.title = estimates_path;
  if (!truth_path.empty()) {
    auto truth = io::ReadTruthCsv(truth_path);
    if (!truth.ok()) return RuntimeError(command, truth.status());
    for (const engine::TruthRow& row : *truth) in.truth_m.push_back(row.position_m);
    auto score = io::Score(*truth, *estimates);
    if (score.ok()) in.title += ": " + io::FormatScore(*score);
  }
  if (!array_path.empty()) {
    auto array = io::ReadArrayFile(array_path, io::ArrayUse::kAuto);
    if (!array.ok()) return RuntimeError(command, array.status());
    in.sensors_m = array->sensors_m;
  }
  if (in.estimates_m.empty()) {
    Warning(command, estimates_path + " has no initialised position; the picture shows the truth and sensors only");
  }
  std::ofstream out(out_path);
  if (!out) return RuntimeError(command, InvalidArgument(out_path + ": cannot open for writing"));
  out << io::RenderSvgPlot(in);
  out.close();
  if (!out) return RuntimeError(command, InvalidArgument(out_path + ": write failed"));
  std::cout << "plot: " << in.estimates_m.size() << " estimates, " << in.truth_m.size() << " truth points -> "
            << out_path << "\n";
  return kExitOk;
}

}  // namespace localizer::cli
