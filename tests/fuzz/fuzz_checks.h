// Invariants the fuzz targets check after each decode (FUZZ_CHECK aborts, so libFuzzer keeps
// the input). Each decoder is run as the server runs it; these are what its header promises.
#pragma once

#include <google/protobuf/util/message_differencer.h>

#include <cmath>
#include <string>
#include <variant>

#include "engine/array/array_geometry.h"
#include "engine/pipeline/session.h"
#include "fuzz_util.h"
#include "wire/block_wire.h"
#include "wire/config_wire.h"
#include "wire/imu_wire.h"
#include "wire/scan_wire.h"

namespace localizer::fuzz {

// A refusal's message goes back to the client and into logs: it names fields and numbers and
// quotes a client string only through EscapedPrefix (string_limits.h), so it is printable ASCII.
inline void CheckRefusal(const Status& status, const char* what) {
  FUZZ_CHECK(!status.ok(), what);
  FUZZ_CHECK(status.code() == StatusCode::kInvalidArgument, std::string(what) + ": " + status.ToString());
  FUZZ_CHECK(!status.message().empty(), what);
  for (const char ch : status.message()) {
    const auto u = static_cast<unsigned char>(ch);
    FUZZ_CHECK(u >= 0x20 && u < 0x7f, std::string(what) + " refusal holds a raw byte " + std::to_string(u) +
                                          " of client input: " + status.ToString());
  }
}

inline bool SameMessage(const google::protobuf::Message& a, const google::protobuf::Message& b) {
  // Field by field (NaN equal to NaN), not byte by byte.
  google::protobuf::util::MessageDifferencer differ;
  differ.set_float_comparison(google::protobuf::util::MessageDifferencer::EXACT);
  google::protobuf::util::DefaultFieldComparator comparator;
  comparator.set_treat_nan_as_equal(true);
  differ.set_field_comparator(&comparator);
  return differ.Compare(a, b);
}

// An accepted config: within the policy, valid for the engine, and its effective config
// (SessionOpened.effective_config, which clients send back to reproduce a session) decodes
// to the same config.
inline void CheckAcceptedConfig(const engine::SessionConfig& config, const wire::ConfigPolicy& policy) {
  if (const auto* audio = std::get_if<engine::AudioSessionConfig>(&config)) {
    FUZZ_CHECK(audio->Validate().ok(), audio->Validate().ToString());
    const int sensors = static_cast<int>(audio->sensors_m.size());
    // Directions take any 2 or more sensors; a position needs 4 (engine/pipeline/session.h).
    const int min_sensors = audio->localization == engine::Localization::kPosition ? 4 : 2;
    FUZZ_CHECK(sensors >= min_sensors && sensors <= policy.max_channels, std::to_string(sensors));
    FUZZ_CHECK(audio->max_sources >= 0 && audio->max_sources <= 16, std::to_string(audio->max_sources));
    FUZZ_CHECK(audio->source_side.allFinite(), "non-finite source_side accepted");
    FUZZ_CHECK(audio->reference_sensor >= 0 && audio->reference_sensor < sensors,
               std::to_string(audio->reference_sensor));
    FUZZ_CHECK(audio->tracker.particle.particles >= 1 && audio->tracker.particle.particles <= policy.max_particles,
               std::to_string(audio->tracker.particle.particles));
    FUZZ_CHECK(audio->max_block_samples >= 1 && audio->max_block_samples <= policy.max_block_samples,
               std::to_string(audio->max_block_samples));
    // What a session builds next from the config: must answer, whatever it answers.
    (void)engine::ArrayGeometry::Create(audio->sensors_m, audio->sound_speed_mps, audio->reference_sensor);
    (void)engine::ResolveLocalization(*audio);
    (void)audio->GccOptionsFor().Validate();
  } else {
    const auto& detection = std::get<engine::DetectionSessionConfig>(config);
    FUZZ_CHECK(detection.Validate().ok(), detection.Validate().ToString());
    FUZZ_CHECK(detection.tws.max_tracks >= 1 && detection.tws.max_tracks <= policy.max_tracks,
               std::to_string(detection.tws.max_tracks));
  }
  const v1::SessionConfig effective = wire::ConfigToProto(config, "label");
  auto again = wire::ConfigFromProto(effective, policy);
  FUZZ_CHECK(again.ok(),
             "the effective config is refused: " + again.status().ToString() + "\n" + effective.ShortDebugString());
  const v1::SessionConfig effective_again = wire::ConfigToProto(*again, "label");
  FUZZ_CHECK(SameMessage(effective, effective_again), "effective config changes on a round trip:\n" +
                                                          effective.ShortDebugString() + "\n" +
                                                          effective_again.ShortDebugString());
}

// A decoded block: the shape the limits allow, every sample finite, in channel-major order,
// and encoding it back gives the same samples in the same encoding.
inline void CheckDecodedBlock(const v1::SampleBlock& block, const wire::BlockLimits& limits,
                              const wire::DecodedBlock& decoded) {
  const engine::BlockView& view = decoded.view;
  FUZZ_CHECK(view.channel_count == limits.channel_count && view.channel_count >= 1, std::to_string(view.channel_count));
  FUZZ_CHECK(view.samples_per_channel >= 1 && view.samples_per_channel <= limits.max_samples_per_channel,
             std::to_string(view.samples_per_channel));
  const int64_t values = view.channel_count * view.samples_per_channel;
  FUZZ_CHECK(static_cast<int64_t>(decoded.samples.size()) == values,
             std::to_string(decoded.samples.size()) + " samples for " + std::to_string(values));
  FUZZ_CHECK(view.samples == decoded.samples.data(), "view does not point into samples");
  FUZZ_CHECK(view.sequence == block.sequence(), "sequence");
  for (int64_t i = 0; i < values; ++i) FUZZ_CHECK(std::isfinite(view.samples[i]), "non-finite sample accepted");
  const bool pcm16 = !block.pcm_s16le().empty();
  v1::SampleBlock encoded;
  wire::EncodeBlock(view, pcm16, &encoded);
  if (pcm16) {
    FUZZ_CHECK(encoded.pcm_s16le() == block.pcm_s16le(), "pcm_s16le does not round-trip");
  } else {
    FUZZ_CHECK(encoded.samples_size() == block.samples_size(), "samples count does not round-trip");
    for (int i = 0; i < block.samples_size(); ++i) {
      FUZZ_CHECK(encoded.samples(i) == block.samples(i), "sample " + std::to_string(i) + " does not round-trip");
    }
  }
}

// A decoded IMU batch: finite, strictly increasing times, and it encodes back to itself.
inline void CheckDecodedImu(const v1::ImuBatch& batch, const wire::DecodedImu& decoded) {
  FUZZ_CHECK(static_cast<int>(decoded.samples.size()) == batch.samples_size(), "sample count");
  FUZZ_CHECK(!decoded.samples.empty() || decoded.origin_m.has_value(), "empty batch without origin accepted");
  for (size_t i = 0; i < decoded.samples.size(); ++i) {
    const engine::ImuSample& s = decoded.samples[i];
    FUZZ_CHECK(std::isfinite(s.t_s) && s.gyro_rps.allFinite() && s.accel_mps2.allFinite(), "non-finite sample");
    FUZZ_CHECK(!s.mag_uT.hasNaN() || s.mag_uT.array().isNaN().all(), "partial magnetometer");
    if (i > 0) FUZZ_CHECK(s.t_s > decoded.samples[i - 1].t_s, "times not increasing");
  }
  if (decoded.origin_m) FUZZ_CHECK(decoded.origin_m->allFinite(), "non-finite origin");
  v1::ImuBatch encoded;
  wire::EncodeImuBatch(decoded.samples, decoded.origin_m ? &*decoded.origin_m : nullptr, batch.sequence(), &encoded);
  auto again = wire::DecodeImuBatch(encoded);
  FUZZ_CHECK(again.ok(), "re-encoded batch refused: " + again.status().ToString());
  FUZZ_CHECK(again->samples.size() == decoded.samples.size(), "re-decoded count");
  for (size_t i = 0; i < decoded.samples.size(); ++i) {
    const engine::ImuSample& a = decoded.samples[i];
    const engine::ImuSample& b = again->samples[i];
    FUZZ_CHECK(a.t_s == b.t_s && a.gyro_rps == b.gyro_rps && a.accel_mps2 == b.accel_mps2, "re-decoded sample");
    FUZZ_CHECK(a.mag_uT.allFinite() ? a.mag_uT == b.mag_uT : b.mag_uT.hasNaN(), "re-decoded magnetometer");
  }
}

// A decoded scan: every plot within the ranges DecodeScan documents, and it encodes back.
inline void CheckDecodedScan(const v1::Scan& scan, const engine::Scan& decoded) {
  FUZZ_CHECK(std::isfinite(decoded.time_s) && decoded.sensor_position_m.allFinite(), "non-finite scan");
  FUZZ_CHECK(static_cast<int>(decoded.detections.size()) == scan.detections_size(), "detection count");
  for (const engine::Detection& d : decoded.detections) {
    FUZZ_CHECK(std::isfinite(d.range_m) && d.range_m > 0.0, "range");
    FUZZ_CHECK(std::abs(d.bearing_rad) <= M_PI, "bearing");
    if (d.elevation_rad) FUZZ_CHECK(std::abs(*d.elevation_rad) <= 0.5 * M_PI, "elevation");
    if (d.snr_db) FUZZ_CHECK(std::isfinite(*d.snr_db), "snr");
  }
  v1::Scan encoded;
  wire::EncodeScan(decoded, scan.sequence(), &encoded);
  auto again = wire::DecodeScan(encoded);
  FUZZ_CHECK(again.ok(), "re-encoded scan refused: " + again.status().ToString());
  FUZZ_CHECK(again->detections.size() == decoded.detections.size(), "re-decoded count");
  for (size_t i = 0; i < decoded.detections.size(); ++i) {
    const engine::Detection& a = decoded.detections[i];
    const engine::Detection& b = again->detections[i];
    FUZZ_CHECK(a.range_m == b.range_m && a.bearing_rad == b.bearing_rad && a.elevation_rad == b.elevation_rad &&
                   a.snr_db == b.snr_db,
               "re-decoded detection " + std::to_string(i));
  }
}

}  // namespace localizer::fuzz
