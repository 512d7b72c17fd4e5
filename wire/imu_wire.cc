#include "wire/imu_wire.h"

#include <cmath>
#include <limits>
#include <string>

namespace localizer::wire {
namespace {

engine::Vec3 FromProto(const v1::Vector3& v) { return {v.x(), v.y(), v.z()}; }

void ToProto(const engine::Vec3& v, v1::Vector3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

}  // namespace

StatusOr<DecodedImu> DecodeImuBatch(const v1::ImuBatch& batch) {
  DecodedImu out;
  if (batch.samples_size() == 0 && !batch.has_origin_m()) {
    return InvalidArgument("imu batch has no samples and no origin_m");
  }
  if (batch.samples_size() > kMaxImuSamplesPerBatch) {
    return InvalidArgument("imu.samples has " + std::to_string(batch.samples_size()) + " samples; at most " +
                           std::to_string(kMaxImuSamplesPerBatch) + " per batch");
  }
  out.samples.reserve(static_cast<size_t>(batch.samples_size()));
  double previous_t_s = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < batch.samples_size(); ++i) {
    const v1::ImuSample& p = batch.samples(i);
    const std::string field = "imu.samples[" + std::to_string(i) + "]";
    engine::ImuSample s;
    s.t_s = p.t_s();
    s.gyro_rps = FromProto(p.gyro_rps());
    s.accel_mps2 = FromProto(p.accel_mps2());
    if (p.has_mag_ut()) s.mag_uT = FromProto(p.mag_ut());
    if (!std::isfinite(s.t_s)) return InvalidArgument(field + ".t_s is not finite");
    if (!(s.t_s > previous_t_s)) {
      return InvalidArgument(field + ".t_s " + std::to_string(s.t_s) + " is not after the previous sample's " +
                             std::to_string(previous_t_s));
    }
    if (!p.has_gyro_rps() || !s.gyro_rps.allFinite())
      return InvalidArgument(field + ".gyro_rps is missing or not finite");
    if (!p.has_accel_mps2() || !s.accel_mps2.allFinite()) {
      return InvalidArgument(field + ".accel_mps2 is missing or not finite");
    }
    if (p.has_mag_ut() && !s.mag_uT.allFinite()) return InvalidArgument(field + ".mag_uT is not finite");
    previous_t_s = s.t_s;
    out.samples.push_back(s);
  }
  if (batch.has_origin_m()) {
    out.origin_m = FromProto(batch.origin_m());
    if (!out.origin_m->allFinite()) return InvalidArgument("imu.origin_m is not finite");
  }
  return out;
}

void EncodeImuBatch(const std::vector<engine::ImuSample>& samples, const engine::Vec3* origin_m, uint64_t sequence,
                    v1::ImuBatch* out) {
  out->Clear();
  out->set_sequence(sequence);
  for (const engine::ImuSample& s : samples) {
    v1::ImuSample* p = out->add_samples();
    p->set_t_s(s.t_s);
    ToProto(s.gyro_rps, p->mutable_gyro_rps());
    ToProto(s.accel_mps2, p->mutable_accel_mps2());
    if (s.mag_uT.allFinite()) ToProto(s.mag_uT, p->mutable_mag_ut());
  }
  if (origin_m != nullptr) ToProto(*origin_m, out->mutable_origin_m());
}

}  // namespace localizer::wire
