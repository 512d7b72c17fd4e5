#include "wire/locate_wire.h"

#include <string>

namespace localizer::wire {

Status DecodeLocateRequest(const v1::LocateRequest& request, const ConfigPolicy& policy, DecodedLocate* out) {
  if (request.config().has_detections()) {
    return InvalidArgument(
        "config.detections: Locate measures one block of samples; detection configs open Track sessions");
  }
  auto config = AudioConfigFromProto(request.config(), policy);
  if (!config.ok()) return config.status();
  out->config = std::move(config).value();
  std::string reason;
  return DecodeBlock(request.block(), {static_cast<int>(out->config.sensors_m.size()), out->config.max_block_samples},
                     &out->block, &reason);
}

void LocateResultToProto(const engine::LocateResult& result, const engine::ArrayGeometry& array,
                         v1::LocateResponse* out) {
  for (size_t p = 0; p < result.measurement.pairs.size(); ++p) {
    const engine::PairMeasurement& m = result.measurement.pairs[p];
    v1::PairTdoa* pair = out->add_pairs();
    pair->set_sensor(static_cast<uint32_t>(array.sensor_of_pair(static_cast<int>(p))));
    pair->set_delay_s(m.delay_s);
    pair->set_quality(m.quality);
    pair->set_peak_snr(m.peak_snr);
  }
  out->set_fix_found(result.fix_found);
  if (result.fix_found) {
    out->mutable_position_m()->set_x(result.fix.position_m.x());
    out->mutable_position_m()->set_y(result.fix.position_m.y());
    out->mutable_position_m()->set_z(result.fix.position_m.z());
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) out->add_covariance(result.fix.covariance_m2(r, c));
    }
    out->set_residual_rms_s(result.fix.rms_residual_s);
  }
  out->set_tdoa_s(result.tdoa_s);
}

}  // namespace localizer::wire
