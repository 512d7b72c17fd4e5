#include "wire/scan_wire.h"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

#include "wire/track_status_wire.h"

namespace localizer::wire {
namespace {

void ToProto(const Eigen::Vector3d& v, v1::Vector3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

}  // namespace

StatusOr<engine::Scan> DecodeScan(const v1::Scan& proto) {
  engine::Scan scan;
  scan.time_s = proto.time_s();
  if (!std::isfinite(scan.time_s)) return InvalidArgument("scan.time_s is not finite");
  scan.sensor_position_m =
      Eigen::Vector3d(proto.sensor_position_m().x(), proto.sensor_position_m().y(), proto.sensor_position_m().z());
  if (!scan.sensor_position_m.allFinite()) return InvalidArgument("scan.sensor_position_m is not finite");
  scan.detections.reserve(static_cast<size_t>(proto.detections_size()));
  for (int i = 0; i < proto.detections_size(); ++i) {
    const v1::Detection& d = proto.detections(i);
    const std::string field = "scan.detections[" + std::to_string(i) + "].";
    if (!(std::isfinite(d.range_m()) && d.range_m() > 0.0)) {
      return InvalidArgument(field + "range_m is " + std::to_string(d.range_m()) + "; must be finite and > 0");
    }
    if (!(std::abs(d.bearing_rad()) <= std::numbers::pi)) {
      return InvalidArgument(field + "bearing_rad is " + std::to_string(d.bearing_rad()) + "; must be in [-pi, pi]");
    }
    engine::Detection detection;
    detection.range_m = d.range_m();
    detection.bearing_rad = d.bearing_rad();
    if (d.has_elevation_rad()) {
      if (!(std::abs(d.elevation_rad()) <= 0.5 * std::numbers::pi)) {
        return InvalidArgument(field + "elevation_rad is " + std::to_string(d.elevation_rad()) +
                               "; must be in [-pi/2, pi/2]");
      }
      detection.elevation_rad = d.elevation_rad();
    }
    if (d.has_snr_db()) {
      if (!std::isfinite(d.snr_db())) return InvalidArgument(field + "snr_db is not finite");
      detection.snr_db = d.snr_db();
    }
    scan.detections.push_back(detection);
  }
  return scan;
}

void EncodeScan(const engine::Scan& scan, uint64_t sequence, v1::Scan* out) {
  out->Clear();
  out->set_sequence(sequence);
  out->set_time_s(scan.time_s);
  ToProto(scan.sensor_position_m, out->mutable_sensor_position_m());
  for (const engine::Detection& d : scan.detections) {
    v1::Detection* p = out->add_detections();
    p->set_range_m(d.range_m);
    p->set_bearing_rad(d.bearing_rad);
    if (d.elevation_rad) p->set_elevation_rad(*d.elevation_rad);
    if (d.snr_db) p->set_snr_db(*d.snr_db);
  }
}

void TrackListToProto(const engine::ScanResult& result, uint64_t sequence, v1::TrackList* out) {
  out->set_sequence(sequence);
  out->set_time_s(result.time_s);
  out->set_scan_index(result.scan_index);
  out->clear_tracks();
  for (const engine::tws::TrackReport& t : result.tracks) {
    v1::TargetTrack* p = out->add_tracks();
    p->set_id(t.id);
    p->set_status(TrackStatusToProto(t.status));
    ToProto(t.position_m, p->mutable_position_m());
    ToProto(t.velocity_mps, p->mutable_velocity_mps());
    auto* cov = p->mutable_covariance();
    cov->Resize(36, 0.0);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) cov->Set(6 * r + c, t.covariance(r, c));
    }
    p->set_hits(static_cast<uint32_t>(t.hits));
    p->set_consecutive_misses(static_cast<uint32_t>(t.consecutive_misses));
  }
  out->set_plots(static_cast<uint32_t>(result.summary.plots));
  out->set_assigned(static_cast<uint32_t>(result.summary.assigned));
  out->set_initiated(static_cast<uint32_t>(result.summary.initiated));
  out->set_deleted(static_cast<uint32_t>(result.summary.deleted));
  out->set_truncated_gates(static_cast<uint32_t>(result.summary.truncated_gates));
  out->set_greedy_clusters(static_cast<uint32_t>(result.summary.greedy_clusters));
  out->set_process_s(result.process_s);
}

int64_t MaxTrackListBytes(int tracks) {
  // Every field at its widest: varints at their maximum, doubles non-zero (so present).
  engine::ScanResult widest;
  widest.scan_index = UINT64_MAX;
  widest.time_s = widest.process_s = 1.5;
  engine::tws::ScanSummary& s = widest.summary;
  s.plots = s.assigned = s.initiated = s.deleted = s.truncated_gates = s.greedy_clusters = INT32_MAX;
  engine::tws::TrackReport track;
  track.id = UINT64_MAX;
  track.status = engine::tws::TrackStatus::kCoasting;
  track.position_m = track.velocity_mps = Eigen::Vector3d::Constant(1.5);
  track.covariance.setConstant(1.5);
  track.hits = track.consecutive_misses = INT32_MAX;
  v1::TrackList empty, one;
  TrackListToProto(widest, UINT64_MAX, &empty);
  empty.set_total_s(1.5);
  widest.tracks.push_back(track);
  TrackListToProto(widest, UINT64_MAX, &one);
  one.set_total_s(1.5);
  const int64_t header = static_cast<int64_t>(empty.ByteSizeLong());
  const int64_t per_track = static_cast<int64_t>(one.ByteSizeLong()) - header;
  // The TrackResponse around it: a tag and a length of at most 5 bytes.
  return header + 6 + per_track * static_cast<int64_t>(tracks);
}

engine::ScanResult TrackListFromProto(const v1::TrackList& proto) {
  engine::ScanResult result;
  result.scan_index = proto.scan_index();
  result.time_s = proto.time_s();
  result.process_s = proto.process_s();
  result.summary.plots = static_cast<int>(proto.plots());
  result.summary.assigned = static_cast<int>(proto.assigned());
  result.summary.initiated = static_cast<int>(proto.initiated());
  result.summary.deleted = static_cast<int>(proto.deleted());
  result.summary.truncated_gates = static_cast<int>(proto.truncated_gates());
  result.summary.greedy_clusters = static_cast<int>(proto.greedy_clusters());
  for (const v1::TargetTrack& t : proto.tracks()) {
    engine::tws::TrackReport r;
    r.id = t.id();
    r.status = TrackStatusFromProto(t.status());
    r.position_m = Eigen::Vector3d(t.position_m().x(), t.position_m().y(), t.position_m().z());
    r.velocity_mps = Eigen::Vector3d(t.velocity_mps().x(), t.velocity_mps().y(), t.velocity_mps().z());
    if (t.covariance_size() == 36) {
      for (int i = 0; i < 36; ++i) r.covariance(i / 6, i % 6) = t.covariance(i);
    }
    r.hits = static_cast<int>(t.hits());
    r.consecutive_misses = static_cast<int>(t.consecutive_misses());
    r.time_s = proto.time_s();
    if (r.status == engine::tws::TrackStatus::kConfirmed || r.status == engine::tws::TrackStatus::kCoasting) {
      ++result.summary.confirmed;
    } else {
      ++result.summary.tentative;
    }
    result.tracks.push_back(r);
  }
  return result;
}

}  // namespace localizer::wire
