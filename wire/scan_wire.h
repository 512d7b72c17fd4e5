// Scan <-> engine::Scan and the track list a detection session answers with.
//
// Decoding validates every plot (finite range > 0, bearing in [-pi, pi], elevation in
// [-pi/2, pi/2], finite SNR; finite time and sensor position), so a bad scan is refused
// in-band without touching the session; the time order of scans is the session's to check.
#pragma once

#include <cstdint>

#include "engine/core/detection.h"
#include "engine/core/status.h"
#include "engine/pipeline/scan_session.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::wire {

// INVALID_ARGUMENT naming the field ("scan.detections[4].range_m is -3").
StatusOr<engine::Scan> DecodeScan(const v1::Scan& proto);
// The inverse, for clients.
void EncodeScan(const engine::Scan& scan, uint64_t sequence, v1::Scan* out);

// A scan's result; total_s is the server's to set.
void TrackListToProto(const engine::ScanResult& result, uint64_t sequence, v1::TrackList* out);
// The largest encoded TrackResponse holding `tracks` tracks (every field at its widest), in
// bytes: what a detection session's max_tracks must keep under the send limit.
int64_t MaxTrackListBytes(int tracks);
// The inverse, for clients (summary fields the wire does not carry stay 0; tracks'
// time_s is the list's).
engine::ScanResult TrackListFromProto(const v1::TrackList& proto);

}  // namespace localizer::wire
