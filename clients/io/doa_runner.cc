#include "clients/io/doa_runner.h"

#include <chrono>
#include <cmath>
#include <fstream>

#include "clients/io/wav_io.h"
#include "engine/doa/array_shape.h"
#include "engine/core/block.h"
#include "engine/core/flags.h"
#include "engine/pipeline/framer.h"

namespace localizer::io {
namespace {

constexpr int64_t kChunkFrames = 1 << 14;  // samples per channel read at once

std::string Cell(double value) { return std::isfinite(value) ? FormatDouble(value) : ""; }

void WriteRow(std::ofstream& out, double t_s, int peak, const engine::DirectionPeak* p) {
  out << FormatDouble(t_s) << ',';
  if (p == nullptr) {
    out << ",0,,,,,,,,\n";
    return;
  }
  double mirror_azimuth = NAN, mirror_elevation = NAN;
  if (p->mirror_ambiguous) {
    mirror_azimuth = engine::AzimuthRad(p->mirror_direction);
    mirror_elevation = engine::ElevationRad(p->mirror_direction);
  }
  out << peak << ",1," << Cell(p->azimuth_rad) << ',' << Cell(p->elevation_rad) << ',' << Cell(p->cone_angle_rad) << ','
      << Cell(mirror_azimuth) << ',' << Cell(mirror_elevation) << ',' << Cell(p->statistic) << ',' << Cell(p->threshold)
      << ',' << Cell(p->power_db) << '\n';
}

}  // namespace

StatusOr<DoaSummary> RunDoa(const DoaJob& job, const std::function<void(const std::string&)>& on_warning) {
  if (job.csv_path.empty()) return InvalidArgument("an output CSV path is required");
  auto stream = WavStream::Open(job.wav_paths);
  if (!stream.ok()) return stream.status();
  if (!stream->warning().empty() && on_warning) on_warning(stream->warning());
  const int channels = stream->channel_count();
  if (channels != static_cast<int>(job.sensors_m.size())) {
    return InvalidArgument(stream->Describe() + " has " + std::to_string(channels) + " channels but " +
                           job.array_source + " has " + std::to_string(job.sensors_m.size()) + " sensors");
  }
  const double fs = stream->sample_rate_hz();
  if (job.array_sample_rate_hz && std::abs(*job.array_sample_rate_hz - fs) > 1e-6 * fs && on_warning) {
    on_warning(job.array_source + " says sample_rate_hz " + FormatDouble(*job.array_sample_rate_hz) + ", " +
               stream->Describe() + " was recorded at " + FormatDouble(fs) + " Hz: using the recording's");
  }
  engine::SrpOptions options = job.srp;
  options.sample_rate_hz = fs;
  options.sound_speed_mps = job.sound_speed_mps;
  if (job.hop_samples < 1 || job.hop_samples > options.frame_samples)
    return InvalidArgument("hop must be in [1, frame] samples, got " + std::to_string(job.hop_samples));
  auto srp = engine::SrpPhat::Create(job.sensors_m, options);
  if (!srp.ok()) return InvalidArgument(job.array_source + ": " + srp.status().message());

  std::ofstream out(job.csv_path);
  if (!out) return InvalidArgument(job.csv_path + ": cannot open for writing");
  out << "t_s,peak,source_present,azimuth_rad,elevation_rad,cone_angle_rad,mirror_azimuth_rad,"
         "mirror_elevation_rad,statistic,threshold,power_db\n";

  DoaSummary summary;
  summary.shape = srp->shape().shape;
  summary.sample_rate_hz = fs;
  const auto start = std::chrono::steady_clock::now();
  engine::Framer framer(channels, options.frame_samples, job.hop_samples);
  std::vector<float> chunk;
  uint64_t sequence = 0;
  for (;;) {
    auto n = stream->Read(kChunkFrames, &chunk);
    if (!n.ok()) return n.status();
    if (*n == 0) break;
    framer.Append(engine::BlockView{++sequence, channels, *n, chunk.data()});
    const float* frame = nullptr;
    int64_t first = 0;
    while (framer.Next(&frame, &first)) {
      auto peaks = srp->Analyse(frame);
      if (!peaks.ok()) {
        return InvalidArgument(stream->Describe() + " at " + FormatDouble(static_cast<double>(first) / fs) +
                               " s: " + peaks.status().message());
      }
      const double t_s = (static_cast<double>(first) + 0.5 * (options.frame_samples - 1)) / fs;
      ++summary.frames;
      if (peaks->empty()) WriteRow(out, t_s, 0, nullptr);
      for (size_t k = 0; k < peaks->size(); ++k) WriteRow(out, t_s, static_cast<int>(k), &(*peaks)[k]);
      summary.frames_with_source += peaks->empty() ? 0 : 1;
      summary.peaks += static_cast<int64_t>(peaks->size());
    }
  }
  out.close();
  if (!out) return InvalidArgument(job.csv_path + ": write failed");
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace localizer::io
