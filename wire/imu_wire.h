// ImuBatch <-> engine IMU samples (moving-array sessions).
//
// Decoding validates what the engine would (finite time, gyro and accelerometer; times
// increasing within the batch; a finite origin), so a bad batch is answered in-band without
// touching the session. Ordering against the previous batch is the session's to check.
#pragma once

#include <optional>
#include <vector>

#include "engine/core/imu.h"
#include "engine/core/status.h"
#include "engine/core/types.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::wire {

struct DecodedImu {
  std::vector<engine::ImuSample> samples;
  std::optional<engine::Vec3> origin_m;  // set when the batch moves the platform origin
};

// Samples in one batch, at most (a second of a 64 kHz IMU): the attitude filter's work per
// batch stays bounded.
inline constexpr int kMaxImuSamplesPerBatch = 1 << 16;

// INVALID_ARGUMENT naming the field ("imu.samples[3].gyro_rps", "imu.origin_m") for a
// non-finite value, a time not after the previous sample's, an empty batch without an
// origin, or more than kMaxImuSamplesPerBatch samples.
StatusOr<DecodedImu> DecodeImuBatch(const v1::ImuBatch& batch);

// The inverse, for clients: samples (and origin, when given) -> an ImuBatch.
void EncodeImuBatch(const std::vector<engine::ImuSample>& samples, const engine::Vec3* origin_m, uint64_t sequence,
                    v1::ImuBatch* out);

}  // namespace localizer::wire
