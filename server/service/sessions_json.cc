#include "server/service/sessions_json.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "server/service/version.h"

namespace localizer::server {
namespace {

using nlohmann::json;

// JSON has no NaN or infinity; a reader gets null instead of an unparsable document.
json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json Triple(const double v[3]) { return json::array({Number(v[0]), Number(v[1]), Number(v[2])}); }

json SessionJson(const SessionHost& host, const v1::SessionInfo& info, bool with_track) {
  const engine::AudioSessionConfig& config = host.config();
  const TrackSnapshot track = host.track().Snapshot();
  json s;
  s["id"] = host.id();
  s["label"] = host.label();
  s["backend"] = host.backend();
  s["kind"] = host.runner_info().kind;
  s["filter_type"] = host.runner_info().filter_type;
  s["attached"] = info.attached();
  // A moving array's sensors where its latest pose put them (in the body frame until then).
  json sensors = json::array();
  for (const engine::Vec3& body : config.sensors_m) {
    const engine::Vec3 p =
        track.platform ? engine::Vec3(track.platform->body_to_world * body + track.platform->origin_m) : body;
    const double xyz[3] = {p.x(), p.y(), p.z()};
    sensors.push_back(Triple(xyz));
  }
  s["sensors_m"] = std::move(sensors);
  if (track.platform) {
    const Eigen::Quaterniond& q = track.platform->body_to_world;
    s["platform"] = {{"body_to_world_wxyz", {Number(q.w()), Number(q.x()), Number(q.y()), Number(q.z())}},
                     {"euler_rad", Triple(track.platform->euler_rad.data())},
                     {"origin_m", Triple(track.platform->origin_m.data())}};
  }
  json targets = json::array();
  for (const TargetPoint& t : track.targets) {
    targets.push_back({{"id", t.id}, {"status", t.status}, {"position_m", Triple(t.position_m)}});
  }
  s["targets"] = std::move(targets);
  s["reference_sensor"] = config.reference_sensor;
  s["sample_rate_hz"] = Number(config.sample_rate_hz);
  s["sound_speed_mps"] = Number(config.sound_speed_mps);
  s["blocks"] = info.blocks_processed();
  s["frames"] = info.frames_processed();
  s["initialised_frames"] = track.initialised_frames;
  s["present_frames"] = track.present_frames;
  // The latest frame's source presence, ambiguity and range observability (far_field,
  // range_sd_m: engine::Estimate); null before the first frame and for
  // detection sessions. "state": "present", "silent", or "untested" (the engine ran no
  // presence test: threshold 0).
  if (track.presence && host.runner_info().reports_presence) {
    const PresencePoint& p = *track.presence;
    s["presence"] = {{"state", !p.tested   ? "untested"
                               : p.present ? "present"
                                           : "silent"},
                     {"source_present", p.present},
                     {"statistic", Number(p.statistic)},
                     {"threshold", Number(p.threshold)},
                     {"ambiguous", p.ambiguous},
                     {"modes", p.modes},
                     {"far_field", p.far_field},
                     {"range_sd_m", Number(p.range_sd_m)}};
  } else {
    s["presence"] = nullptr;
  }
  s["age_s"] = Number(info.age_s());
  s["idle_s"] = Number(info.idle_s());
  s["track_capacity"] = track.capacity;
  s["track_included"] = with_track;
  json points = json::array();
  if (with_track) {
    for (const TrackPoint& p : track.points) {
      points.push_back({{"frame", p.frame_index},
                        {"t_s", Number(p.t_s)},
                        {"position_m", Triple(p.position_m)},
                        {"velocity_mps", Triple(p.velocity_mps)},
                        {"position_std_m", Triple(p.position_std_m)},
                        {"reinitialised", p.reinitialised},
                        {"source_present", p.source_present},
                        {"ambiguous", p.ambiguous},
                        {"far_field", p.far_field}});
    }
  }
  s["track"] = std::move(points);
  // Sessions that list sources: what the estimates carry, the latest frame's sources and
  // (with the track) the recent (frame, source) directions, oldest first. NaN angles (what
  // the array cannot observe) and positions (none bounded, or directions only) are null.
  s["localization"] = host.runner_info().localization.empty() ? nullptr : json(host.runner_info().localization);
  s["array_shape"] = host.runner_info().array_shape.empty() ? nullptr : json(host.runner_info().array_shape);
  const auto direction = [](const DirectionPoint& d) {
    return json{{"frame", d.frame_index},
                {"t_s", Number(d.t_s)},
                {"id", d.source_id},
                {"azimuth_rad", Number(d.azimuth_rad)},
                {"elevation_rad", Number(d.elevation_rad)},
                {"cone_angle_rad", Number(d.cone_angle_rad)},
                {"source_present", d.source_present},
                {"position_m", json{Number(d.position_m[0]), Number(d.position_m[1]), Number(d.position_m[2])}}};
  };
  json sources = json::array(), directions = json::array();
  for (const DirectionPoint& d : track.sources) sources.push_back(direction(d));
  if (with_track) {
    for (const DirectionPoint& d : track.directions) directions.push_back(direction(d));
  }
  s["sources"] = std::move(sources);
  s["directions"] = std::move(directions);
  json models = json::array();
  for (const engine::ModelProbability& m : track.model_probabilities) {
    models.push_back({{"model", m.model}, {"probability", Number(m.probability)}});
  }
  s["model_probabilities"] = std::move(models);
  return s;
}

// Labels come from clients: bytes that are not UTF-8 are replaced rather than thrown on.
std::string Dump(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

}  // namespace

std::string FinishedSessionJson(const SessionHost& host, const v1::SessionInfo& info) {
  json s = SessionJson(host, info, /*with_track=*/true);
  s["attached"] = false;  // it ended: no stream holds it any more
  return Dump(s);
}

std::string SessionsJson(const std::vector<std::shared_ptr<SessionHost>>& hosts, Clock::time_point now, double ttl_s,
                         const std::vector<FinishedSession>& finished, size_t max_track_sessions) {
  // Each host's counters taken once (Info takes its lock), then oldest first.
  std::vector<std::pair<v1::SessionInfo, const SessionHost*>> by_age;
  by_age.reserve(hosts.size());
  for (const auto& host : hosts) {
    if (host) by_age.emplace_back(host->Info(now, ttl_s), host.get());
  }
  std::stable_sort(by_age.begin(), by_age.end(),
                   [](const auto& a, const auto& b) { return a.first.age_s() > b.first.age_s(); });
  json doc;
  doc["version"] = kLocalizerVersion;
  doc["sessions_total"] = by_age.size();
  doc["track_sessions_max"] = max_track_sessions;
  json sessions = json::array();
  for (size_t i = 0; i < by_age.size(); ++i) {
    sessions.push_back(SessionJson(*by_age[i].second, by_age[i].first, i < max_track_sessions));
  }
  doc["sessions"] = std::move(sessions);
  std::string text = Dump(doc);
  // The finished sessions were rendered when they ended: appended as they are, without
  // parsing them again (the document is an object: its closing brace moves to the end).
  text.pop_back();
  text += ",\"finished\":[";
  for (size_t i = 0; i < finished.size(); ++i) {
    const FinishedSession& f = finished[i];
    const double ago_s = std::chrono::duration<double>(now - f.finished_at).count();
    if (i > 0) text += ',';
    text += "{\"finished_ago_s\":" + Dump(Number(ago_s)) + ",\"reason\":" + Dump(json(f.reason)) +
            ",\"session\":" + f.session_json + '}';
  }
  text += "]}";
  return text;
}

}  // namespace localizer::server
