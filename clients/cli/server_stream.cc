#include "clients/cli/server_stream.h"

#include <cstdio>

#include "clients/grpc/latency_summary.h"
#include "clients/io/presence_summary.h"

namespace localizer::cli {

StatusOr<client::RemoteTrackOptions> ParseStreamFlags(const StreamFlags& f) {
  client::RemoteTrackOptions options;
  auto pacing = client::ParsePacing(f.rate);
  if (!pacing.ok()) return InvalidArgument("--rate: " + pacing.status().message());
  options.pacing = *pacing;
  auto encoding = client::ParseEncoding(f.encoding);
  if (!encoding.ok()) return InvalidArgument("--encoding: " + encoding.status().message());
  options.encoding = *encoding;
  if (f.block_samples < 1) {
    return InvalidArgument("--block-samples must be >= 1, got " + std::to_string(f.block_samples));
  }
  options.block_samples = f.block_samples;
  options.label = f.label;
  options.session_key = f.session_key;
  return options;
}

void PrintOpened(const v1::SessionOpened& opened) {
  std::printf("session=%s token=%s backend=%s resumed=%d ttl_s=%g\n", opened.session_id().c_str(),
              opened.resume_token().c_str(), opened.backend().c_str(), opened.resumed() ? 1 : 0,
              opened.session_ttl_s());
  std::fflush(stdout);
}

void PrintStreamTotals(const client::StreamResult& result) {
  const client::LatencySummary latency = client::SummariseLatencies(result.ClientLatencies());
  std::printf("%s rejections=%zu gaps=%zu\n", client::FormatLatencyMs(latency).c_str(), result.rejections.size(),
              result.gaps.size());
  io::PresenceSummary presence;
  for (const client::StreamedEstimate& s : result.estimates) presence.Add(s.estimate);
  if (auto line = presence.NoSourceLine()) std::printf("%s\n", line->c_str());
  if (auto line = presence.FarFieldLine()) std::printf("%s\n", line->c_str());
}

}  // namespace localizer::cli
