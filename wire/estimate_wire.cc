#include "wire/estimate_wire.h"

#include <algorithm>

#include "wire/track_status_wire.h"

namespace localizer::wire {

namespace {

void SetVector(const engine::Vec3& from, v1::Vector3* to) {
  to->set_x(from.x());
  to->set_y(from.y());
  to->set_z(from.z());
}

engine::Vec3 GetVector(const v1::Vector3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

void EstimateToProto(const engine::Estimate& e, int reference_sensor, const std::string& backend, v1::Estimate* out) {
  out->set_sequence(e.sequence);
  out->set_t_s(e.t_s);
  v1::Vector3* p = out->mutable_position_m();
  p->set_x(e.state(0));
  p->set_y(e.state(1));
  p->set_z(e.state(2));
  v1::Vector3* v = out->mutable_velocity_mps();
  v->set_x(e.state(3));
  v->set_y(e.state(4));
  v->set_z(e.state(5));
  auto* cov = out->mutable_covariance();
  cov->Resize(36, 0.0);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) cov->Set(6 * r + c, e.covariance(r, c));
  }
  out->set_frame_index(e.frame_index);
  out->set_initialised(e.initialised);
  out->set_reinitialised(e.reinitialised);
  out->set_ess(e.ess);
  out->set_tdoa_sigma_s(e.tdoa_sigma_s);
  out->set_pairs_used(static_cast<uint32_t>(e.pairs_used));
  out->set_nis(e.nis);
  out->set_source_present(e.source_present);
  out->set_presence_statistic(e.presence_statistic);
  out->set_presence_threshold(e.presence_threshold);
  out->set_ambiguous(e.ambiguous);
  out->set_modes(static_cast<uint32_t>(std::max(0, e.modes)));
  out->set_far_field(e.far_field);
  out->set_range_sd_m(e.range_sd_m);
  out->clear_pairs();
  for (size_t k = 0; k < e.delay_s.size(); ++k) {
    v1::PairTdoa* pair = out->add_pairs();
    const auto pair_index = static_cast<int>(k);
    pair->set_sensor(static_cast<uint32_t>(pair_index < reference_sensor ? pair_index : pair_index + 1));
    pair->set_delay_s(e.delay_s[k]);
    if (k < e.quality.size()) pair->set_quality(e.quality[k]);
  }
  out->mutable_latency()->set_tdoa_s(e.timings.tdoa_s);
  out->mutable_latency()->set_filter_s(e.timings.filter_s);
  out->set_backend(backend);
  out->clear_model_probabilities();
  for (const engine::ModelProbability& m : e.model_probabilities) {
    v1::ModelProbability* model = out->add_model_probabilities();
    model->set_model(m.model);
    model->set_probability(m.probability);
  }
  out->clear_platform();
  if (e.platform) {
    v1::PlatformPose* pose = out->mutable_platform();
    const Eigen::Quaterniond& q = e.platform->body_to_world;
    pose->mutable_body_to_world()->set_w(q.w());
    pose->mutable_body_to_world()->set_x(q.x());
    pose->mutable_body_to_world()->set_y(q.y());
    pose->mutable_body_to_world()->set_z(q.z());
    SetVector(e.platform->euler_rad, pose->mutable_euler_rad());
    SetVector(e.platform->euler_sd_rad, pose->mutable_euler_sd_rad());
    SetVector(e.platform->origin_m, pose->mutable_origin_m());
  }
  out->clear_sources();
  for (const engine::SourceEstimate& s : e.sources) {
    v1::SourceDirection* source = out->add_sources();
    source->set_source_id(s.source_id);
    source->set_status(TrackStatusToProto(s.status));
    SetVector(s.direction, source->mutable_direction());
    source->set_azimuth_rad(s.azimuth_rad);
    source->set_elevation_rad(s.elevation_rad);
    source->set_cone_angle_rad(s.cone_angle_rad);
    source->set_sigma_rad(s.sigma_rad);
    source->set_source_present(s.source_present);
    source->set_power_db(s.power_db);
    if (s.position_m.allFinite()) {
      SetVector(s.position_m, source->mutable_position_m());
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) source->add_position_covariance(s.position_covariance_m2(r, c));
      }
    }
    source->set_range_sd_m(s.range_sd_m);
  }
}

engine::Estimate EstimateFromProto(const v1::Estimate& p) {
  engine::Estimate e;
  e.frame_index = p.frame_index();
  e.sequence = p.sequence();
  e.t_s = p.t_s();
  e.initialised = p.initialised();
  e.reinitialised = p.reinitialised();
  e.state << p.position_m().x(), p.position_m().y(), p.position_m().z(), p.velocity_mps().x(), p.velocity_mps().y(),
      p.velocity_mps().z();
  if (p.covariance_size() == 36) {
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) e.covariance(r, c) = p.covariance(6 * r + c);
    }
  }
  e.ess = p.ess();
  e.tdoa_sigma_s = p.tdoa_sigma_s();
  e.pairs_used = static_cast<int>(p.pairs_used());
  e.nis = p.nis();
  e.source_present = p.source_present();
  e.presence_statistic = p.presence_statistic();
  e.presence_threshold = p.presence_threshold();
  e.ambiguous = p.ambiguous();
  e.modes = static_cast<int>(std::min<uint32_t>(p.modes(), 1u << 30));
  e.far_field = p.far_field();
  e.range_sd_m = p.range_sd_m();
  for (const v1::PairTdoa& pair : p.pairs()) {
    e.delay_s.push_back(pair.delay_s());
    e.quality.push_back(pair.quality());
  }
  e.timings.tdoa_s = p.latency().tdoa_s();
  e.timings.filter_s = p.latency().filter_s();
  for (const v1::ModelProbability& m : p.model_probabilities())
    e.model_probabilities.push_back({m.model(), m.probability()});
  if (p.has_platform()) {
    const v1::PlatformPose& pose = p.platform();
    engine::PlatformAttitude a;
    a.body_to_world = Eigen::Quaterniond(pose.body_to_world().w(), pose.body_to_world().x(), pose.body_to_world().y(),
                                         pose.body_to_world().z());
    a.euler_rad = GetVector(pose.euler_rad());
    a.euler_sd_rad = GetVector(pose.euler_sd_rad());
    a.origin_m = GetVector(pose.origin_m());
    e.platform = a;
  }
  for (const v1::SourceDirection& source : p.sources()) {
    engine::SourceEstimate s;
    s.source_id = source.source_id();
    s.status = TrackStatusFromProto(source.status());
    s.direction = GetVector(source.direction());
    s.azimuth_rad = source.azimuth_rad();
    s.elevation_rad = source.elevation_rad();
    s.cone_angle_rad = source.cone_angle_rad();
    s.sigma_rad = source.sigma_rad();
    s.source_present = source.source_present();
    s.power_db = source.power_db();
    if (source.has_position_m()) s.position_m = GetVector(source.position_m());
    if (source.position_covariance_size() == 9) {
      for (int k = 0; k < 9; ++k) s.position_covariance_m2(k / 3, k % 3) = source.position_covariance(k);
    }
    s.range_sd_m = source.range_sd_m();
    e.sources.push_back(s);
  }
  return e;
}

}  // namespace localizer::wire
