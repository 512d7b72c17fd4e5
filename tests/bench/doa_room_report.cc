// The issue-18 goal scene, measured: two talkers with pauses around a ReSpeaker-style board
// (4 microphones at +-4.05 cm) on a desk in a reverberant room, frame by frame through
// SrpPhat and DirectionTracker. Not a test (no pass/fail); numbers for ACCURACY.md.
//
// Scene: a 6 x 5 x 3 m room, RT60 0.2 / 0.4 / 0.6 s (engine/sim/room.h); the board at
// (2.2, 1.9, 1.0); talkers 1.5-2.5 m away, 0.3-0.5 m above the board, at azimuths 90 degrees
// apart; each talks in bursts (white noise 100-7000 Hz, on 0.4-1.5 s, off 0.2-1.0 s, seeded)
// at equal level; sensor noise 15 dB below a talker's direct sound. 16 kHz, frames of 512,
// hop 256, max_sources 4 (--max-sources), source_side +z. A talker "sounds" in a frame when it is on over the
// whole frame.
// Per RT60 it prints: median and p90 azimuth error of the peaks within 20 degrees of a
// sounding talker; the share of sounding talker-frames with such a peak (detected by a peak);
// the share with a confirmed or coasting track within 20 degrees (detected by a track: what a
// user of the tracks sees) and that track's median azimuth error; seconds
// of confirmed or coasting track per minute further than 20 degrees from both talkers (false;
// two such tracks at once count twice); identity switches (the track nearest a sounding
// talker changes id); seconds of duplicate track per minute (tracks within 20 degrees of a
// talker, nearest to it, beyond the first: one talker reported under two ids).
//
//   build/tests/bench/doa_room_report [--seconds 20] [--seed 1] [--max-sources 4] [--relative 0]
//                                     [--coast-decay 0.2] [--dump peaks_and_tracks.csv]
//                                     (--help: the tracker's options; --coast-decay 0: no decay, as before)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "engine/core/flags.h"
#include "engine/doa/direction_tracker.h"
#include "engine/doa/srp_phat.h"
#include "engine/sim/band_pass_fir.h"
#include "engine/sim/room.h"

namespace localizer::engine {
namespace {

constexpr double kFs = 16000.0;
constexpr int kFrame = 512, kHop = 256;

double Wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

// Departures from the goal scene, for scenes its defaults never drew.
struct SceneVariant {
  double quiet_db = 0.0;         // the second talker this much quieter
  bool random_azimuths = false;  // talkers at seeded azimuths at least 30 degrees apart, not 90 apart
};

int Run(double seconds, uint64_t seed, int max_sources, double relative_floor, bool diffuse_weighting,
        bool signal_weighting, const std::string& dump_path, const DirectionTrackerOptions& tracking_flags,
        const SceneVariant& variant) {
  FILE* dump = dump_path.empty() ? nullptr : std::fopen(dump_path.c_str(), "w");
  if (dump)  // threshold: the peak's (SrpPhat's t, what its rise is held to); 0 on track rows
    std::fprintf(dump, "kind,rt60,frame,on0,on1,energy,onset,rank,id,status,az,el,stat,rise,dist0,dist1,threshold\n");
  const Vec3 centre(2.2, 1.9, 1.0);
  const double a = 0.0405;
  std::vector<Vec3> board, relative{Vec3(a, 0, 0), Vec3(0, a, 0), Vec3(-a, 0, 0), Vec3(0, -a, 0)};
  for (const Vec3& m : relative) board.push_back(centre + m);
  const auto samples = static_cast<int64_t>(seconds * kFs);
  std::printf(
      "RT60 | peak azimuth error median / p90 (deg) | detected by a peak | by a track / its error median (deg) | "
      "false track s/min | id switches | duplicate track s/min\n");
  for (const double rt60_s : {0.2, 0.4, 0.6}) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    ShoeboxRoom room;
    room.rt60_s = rt60_s;
    struct Talker {
      double azimuth_rad = 0.0;
      RoomSource source;
      std::vector<bool> on;  // per sample
    };
    std::vector<Talker> talkers(2);
    std::vector<double> fir = DesignBandPassFir(100.0, 7000.0, kFs).taps;
    double fir_energy = 0.0;
    for (double h : fir) fir_energy += h * h;
    for (double& h : fir) h /= std::sqrt(fir_energy);  // unit power out of unit-power noise
    // Their own generator, so the default scene's draws are unchanged.
    std::mt19937_64 azimuth_rng(seed ^ 0x9e3779b97f4a7c15ULL);
    std::uniform_real_distribution<double> azimuth(-std::numbers::pi, std::numbers::pi);
    const double first_rad = azimuth(azimuth_rng);
    double second_rad = first_rad;
    while (std::abs(Wrap(second_rad - first_rad)) < std::numbers::pi / 6) second_rad = azimuth(azimuth_rng);
    for (int k = 0; k < 2; ++k) {
      Talker& t = talkers[static_cast<size_t>(k)];
      t.azimuth_rad =
          variant.random_azimuths ? (k == 0 ? first_rad : second_rad) : Wrap(0.4 + k * std::numbers::pi / 2);
      double range = 1.5 + uniform(rng);
      const double height = 0.3 + 0.2 * uniform(rng);
      // Seeded azimuths may face a near wall: the talker stays 0.3 m inside it.
      const double along_x = std::cos(t.azimuth_rad), along_y = std::sin(t.azimuth_rad);
      if (std::abs(along_x) > 1e-9)
        range = std::min(range,
                         ((along_x > 0 ? room.size_m.x() : 0.0) - centre.x() - std::copysign(0.3, along_x)) / along_x);
      if (std::abs(along_y) > 1e-9)
        range = std::min(range,
                         ((along_y > 0 ? room.size_m.y() : 0.0) - centre.y() - std::copysign(0.3, along_y)) / along_y);
      t.source.position_m = centre + Vec3(range * std::cos(t.azimuth_rad), range * std::sin(t.azimuth_rad), height);
      t.on.assign(static_cast<size_t>(samples), false);
      for (int64_t i = 0; i < samples;) {
        const auto on = static_cast<int64_t>((0.4 + 1.1 * uniform(rng)) * kFs);
        const auto off = static_cast<int64_t>((0.2 + 0.8 * uniform(rng)) * kFs);
        for (int64_t j = i; j < std::min(samples, i + on); ++j) t.on[static_cast<size_t>(j)] = true;
        i += on + off;
      }
      std::vector<double> white(static_cast<size_t>(samples) + fir.size());
      for (double& v : white) v = normal(rng);
      t.source.signal.assign(static_cast<size_t>(samples), 0.0);
      for (int64_t i = 0; i < samples; ++i) {
        double acc = 0.0;
        for (size_t j = 0; j < fir.size(); ++j) acc += fir[j] * white[static_cast<size_t>(i) + j];
        const double gain = k == 1 ? std::pow(10.0, -variant.quiet_db / 20.0) : 1.0;
        t.source.signal[static_cast<size_t>(i)] = t.on[static_cast<size_t>(i)] ? gain * acc : 0.0;
      }
    }
    std::vector<RoomSource> sources{talkers[0].source, talkers[1].source};
    auto signals = RenderInRoom(room, sources, board, kFs, samples);
    if (!signals.ok()) return std::fprintf(stderr, "%s\n", signals.status().ToString().c_str()), 1;
    const double direct = 1.0 / (4.0 * std::numbers::pi * 2.0);  // a talker at 2 m, unit power
    for (float& v : *signals) v += static_cast<float>(direct * std::pow(10.0, -15.0 / 20.0) * normal(rng));

    SrpOptions options;
    options.band_low_hz = 100.0;
    options.band_high_hz = 7000.0;
    options.source_side = Vec3::UnitZ();
    options.max_sources = max_sources;
    options.hop_samples = kHop;
    options.min_relative_statistic = relative_floor;
    options.diffuse_weighting = diffuse_weighting;
    options.signal_weighting = signal_weighting;
    auto srp = SrpPhat::Create(relative, options);
    DirectionTrackerOptions tracking = tracking_flags;
    tracking.frame_period_s = kHop / kFs;
    if (!srp.ok()) return std::fprintf(stderr, "setup failed\n"), 1;
    auto tracker = DirectionTracker::Create(srp->shape(), tracking);
    if (!tracker.ok()) return std::fprintf(stderr, "setup failed\n"), 1;
    std::vector<double> errors_deg, track_errors_deg;
    int tracked = 0;
    int sounding = 0, detected = 0, false_frames = 0, frames = 0, switches = 0, duplicate_frames = 0;
    std::map<int, uint64_t> last_id;
    std::vector<float> frame(4 * kFrame);
    std::vector<SourceTrack> tracks;
    for (int64_t start = 0; start + kFrame <= samples; start += kHop, ++frames) {
      for (int m = 0; m < 4; ++m)
        std::copy_n(signals->begin() + m * samples + start, kFrame, frame.begin() + m * kFrame);
      auto peaks = srp->Analyse(frame.data());
      if (!peaks.ok() || !tracker->Update(static_cast<double>(start) / kFs, *peaks, srp->band_power(), &tracks).ok())
        return 1;
      std::vector<bool> on(2);
      if (dump) {
        const double energy = srp->band_power();
        auto on_of = [&](int k) {
          const Talker& t = talkers[static_cast<size_t>(k)];
          return int(t.on[static_cast<size_t>(start)]) + 2 * int(t.on[static_cast<size_t>(start + kFrame - 1)]);
        };
        auto dist = [&](double az, int k) {
          return std::abs(Wrap(az - talkers[static_cast<size_t>(k)].azimuth_rad)) * 180 / std::numbers::pi;
        };
        for (size_t r = 0; r < peaks->size(); ++r) {
          const DirectionPeak& p = (*peaks)[r];
          std::fprintf(dump, "p,%.1f,%d,%d,%d,%.6g,%d,%zu,0,0,%.4f,%.4f,%.3f,%.3f,%.2f,%.2f,%.3f\n", rt60_s, frames,
                       on_of(0), on_of(1), energy, int(tracker->last_frame_onset()), r, p.azimuth_rad, p.elevation_rad,
                       p.statistic, p.rise, dist(p.azimuth_rad, 0), dist(p.azimuth_rad, 1), p.threshold);
        }
        for (const SourceTrack& tr : tracks)
          std::fprintf(dump, "t,%.1f,%d,%d,%d,%.6g,%d,0,%llu,%d,%.4f,%.4f,0,0,%.2f,%.2f,0\n", rt60_s, frames, on_of(0),
                       on_of(1), energy, int(tracker->last_frame_onset()), static_cast<unsigned long long>(tr.id),
                       static_cast<int>(tr.status), tr.azimuth_rad, tr.elevation_rad, dist(tr.azimuth_rad, 0),
                       dist(tr.azimuth_rad, 1));
      }
      for (int k = 0; k < 2; ++k) {
        const Talker& t = talkers[static_cast<size_t>(k)];
        on[static_cast<size_t>(k)] = t.on[static_cast<size_t>(start)] && t.on[static_cast<size_t>(start + kFrame - 1)];
        if (!on[static_cast<size_t>(k)]) continue;
        ++sounding;
        double best = 1e9;
        for (const DirectionPeak& p : *peaks) best = std::min(best, std::abs(Wrap(p.azimuth_rad - t.azimuth_rad)));
        if (best < 20.0 * std::numbers::pi / 180) {
          ++detected;
          errors_deg.push_back(best * 180 / std::numbers::pi);
        }
        double track_best = 1e9;
        for (const SourceTrack& tr : tracks)
          track_best = std::min(track_best, std::abs(Wrap(tr.azimuth_rad - t.azimuth_rad)));
        if (track_best < 20.0 * std::numbers::pi / 180) {
          ++tracked;
          track_errors_deg.push_back(track_best * 180 / std::numbers::pi);
        }
        for (const SourceTrack& tr : tracks) {
          if (std::abs(Wrap(tr.azimuth_rad - t.azimuth_rad)) < 20.0 * std::numbers::pi / 180) {
            if (last_id.count(k) && last_id[k] != tr.id) ++switches;
            last_id[k] = tr.id;
            break;
          }
        }
      }
      for (const SourceTrack& tr : tracks) {
        bool near = false;
        for (int k = 0; k < 2; ++k)  // near a talker, sounding or in a pause (a track coasts through one)
          near |= std::abs(Wrap(tr.azimuth_rad - talkers[static_cast<size_t>(k)].azimuth_rad)) <
                  20.0 * std::numbers::pi / 180;
        false_frames += !near;
      }
      for (int k = 0; k < 2; ++k) {  // tracks near a talker beyond its nearest one (two ids for one talker)
        int near = 0;
        for (const SourceTrack& tr : tracks) {
          const double d0 = std::abs(Wrap(tr.azimuth_rad - talkers[0].azimuth_rad));
          const double d1 = std::abs(Wrap(tr.azimuth_rad - talkers[1].azimuth_rad));
          near += (k == 0 ? d0 <= d1 : d1 < d0) && std::min(d0, d1) < 20.0 * std::numbers::pi / 180;
        }
        duplicate_frames += std::max(0, near - 1);
      }
    }
    std::sort(errors_deg.begin(), errors_deg.end());
    const double median = errors_deg.empty() ? NAN : errors_deg[errors_deg.size() / 2];
    const double p90 = errors_deg.empty() ? NAN : errors_deg[errors_deg.size() * 9 / 10];
    std::sort(track_errors_deg.begin(), track_errors_deg.end());
    const double track_median = track_errors_deg.empty() ? NAN : track_errors_deg[track_errors_deg.size() / 2];
    const double minutes = static_cast<double>(frames) * kHop / kFs / 60.0;
    std::printf("%.1f s | %.1f / %.1f | %.1f %% of %d | %.1f %% / %.1f | %.1f | %d | %.1f\n", rt60_s, median, p90,
                100.0 * detected / std::max(1, sounding), sounding, 100.0 * tracked / std::max(1, sounding),
                track_median, false_frames * kHop / kFs / minutes, switches, duplicate_frames * kHop / kFs / minutes);
  }
  return 0;
}

}  // namespace
}  // namespace localizer::engine

int main(int argc, char** argv) {
  double seconds = 20.0;
  uint64_t seed = 1;
  int max_sources = 4;
  double relative = 0.0;
  std::string dump;
  localizer::engine::DirectionTrackerOptions tracking;
  bool start_anywhere = false, no_continue = false, diffuse = false, signal = false;
  localizer::engine::SceneVariant variant;
  localizer::FlagSet flags("doa_room_report [flags]",
                           "Two talkers with pauses around a 4-microphone board in rooms of RT60 0.2, 0.4 and\n"
                           "0.6 s, through SrpPhat and DirectionTracker; one line of figures per RT60.");
  flags.Double("seconds", &seconds, "S", "s", "audio per room, in [1, 600]");
  flags.Uint64("seed", &seed, "N", "talkers, their bursts and the noise");
  flags.Int("max-sources", &max_sources, "K", "sources", "SrpOptions::max_sources, in [1, 16]");
  flags.Double("relative", &relative, "R", "", "SrpOptions::min_relative_statistic, in [0, 1) (0: off)");
  flags.Bool("diffuse-weighting", &diffuse,
             "SrpOptions::diffuse_weighting: each pair's bins weighted by 1 - the diffuse field's coherence");
  flags.Bool("signal-weighting", &signal,
             "SrpOptions::signal_weighting: each frame's bins weighted by their share of signal");
  flags.Bool(
      "start-anywhere", &start_anywhere,
      "tracks start from any unexplained peak on any frame (DirectionTrackerOptions::start_at_onsets_only false)");
  flags.Double("onset-rise", &tracking.onset_min_rise_db, "DB", "dB", "DirectionTrackerOptions::onset_min_rise_db");
  flags.Double("resume-after", &tracking.resume_after_s, "S", "s",
               "DirectionTrackerOptions::resume_after_s: a track silent this long resumes only on a rising peak (0: "
               "off)");
  flags.Double("accel", &tracking.angular_accel_noise_radps2, "A", "rad/s^2",
               "DirectionTrackerOptions::angular_accel_noise_radps2");
  flags.Double("rate-sigma", &tracking.initial_rate_sigma_radps, "S", "rad/s",
               "DirectionTrackerOptions::initial_rate_sigma_radps");
  flags.Double("max-coast", &tracking.max_coast_s, "S", "s", "DirectionTrackerOptions::max_coast_s");
  flags.Bool("no-continue", &no_continue,
             "every track keeps its own identity (DirectionTrackerOptions::continue_identities false)");
  flags.Int("steady-hits", &tracking.steady_hits, "N", "", "DirectionTrackerOptions::steady_hits");
  flags.Double("coast-decay", &tracking.coast_rate_decay_s, "S", "s",
               "DirectionTrackerOptions::coast_rate_decay_s: a coasting track's rate decays with this time "
               "constant (0: off, constant rate)");
  flags.Int("min-lead", &tracking.min_lead_frames, "N", "frames",
            "DirectionTrackerOptions::min_lead_frames: a confirmed track is reported once it took its frame's "
            "strongest peak this often (0: off)");
  flags.Double("min-lead-share", &tracking.min_lead_share, "F", "",
               "DirectionTrackerOptions::min_lead_share: ... and in at least this share of the frames it took a "
               "peak in (0: off)");
  flags.Int("persist", &tracking.persistent_leader_frames, "N", "frames",
            "DirectionTrackerOptions::persistent_leader_frames: the strongest peak at one direction this many "
            "frames in a row may start or resume a track (0: off)");
  flags.Double("co-lead-share", &tracking.co_lead_share, "F", "",
               "DirectionTrackerOptions::co_lead_share: a peak of at least this share of the frame's strongest "
               "statistic also leads, and a steady second peak may start a track (0: off)");
  flags.Double("remember", &tracking.remember_identity_s, "S", "s",
               "DirectionTrackerOptions::remember_identity_s: a deleted track's identity is remembered this long "
               "(0: off)");
  flags.Double("quiet-db", &variant.quiet_db, "D", "dB", "the second talker this much quieter, in [0, 30]");
  flags.Bool("random-azimuths", &variant.random_azimuths,
             "talkers at seeded azimuths at least 30 degrees apart (default: 0.4 rad and 90 degrees on)");
  flags.String("dump", &dump, "PATH", "CSV of every frame's peaks and tracks (for analysis)");
  const localizer::Status parsed = flags.Parse(std::vector<std::string>(argv + 1, argv + argc));
  if (flags.help_requested()) return std::printf("%s", flags.Usage().c_str()), 0;
  if (!parsed.ok()) return std::fprintf(stderr, "doa_room_report: %s\n", parsed.message().c_str()), 2;
  if (!(seconds >= 1.0 && seconds <= 600.0))
    return std::fprintf(stderr, "doa_room_report: --seconds must be in [1, 600]\n"), 2;
  if (max_sources < 1 || max_sources > 16)
    return std::fprintf(stderr, "doa_room_report: --max-sources must be in [1, 16]\n"), 2;
  if (!(relative >= 0.0 && relative < 1.0))
    return std::fprintf(stderr, "doa_room_report: --relative must be in [0, 1)\n"), 2;
  if (!(variant.quiet_db >= 0.0 && variant.quiet_db <= 30.0))
    return std::fprintf(stderr, "doa_room_report: --quiet-db must be in [0, 30]\n"), 2;
  tracking.start_at_onsets_only = !start_anywhere;
  tracking.continue_identities = !no_continue;
  return localizer::engine::Run(seconds, seed, max_sources, relative, diffuse, signal, dump, tracking, variant);
}
