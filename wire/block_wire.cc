#include "wire/block_wire.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace localizer::wire {
namespace {

Status Reject(std::string* reason, const char* key, std::string message) {
  *reason = key;
  return InvalidArgument(std::move(message));
}

}  // namespace

Status DecodeBlock(const v1::SampleBlock& block, const BlockLimits& limits, DecodedBlock* out, std::string* reason) {
  const int64_t channels = block.channel_count();
  // Never divide by a client's zero, whatever the limits say (a session without channels).
  if (channels < 1 || channels != limits.channel_count) {
    return Reject(reason, "channel_count",
                  "channel_count is " + std::to_string(channels) + "; the array has " +
                      std::to_string(limits.channel_count) + " sensors");
  }
  const bool have_float = block.samples_size() > 0;
  const bool have_pcm = !block.pcm_s16le().empty();
  if (!have_float && !have_pcm)
    return Reject(reason, "empty", "block has no samples (samples and pcm_s16le are empty)");
  if (have_float && have_pcm) return Reject(reason, "bad_samples", "block fills both samples and pcm_s16le; send one");
  if (have_pcm && block.pcm_s16le().size() % 2 != 0) {
    return Reject(reason, "bad_samples",
                  "pcm_s16le has " + std::to_string(block.pcm_s16le().size()) + " bytes, not whole 16-bit samples");
  }
  const int64_t values = have_float ? block.samples_size() : static_cast<int64_t>(block.pcm_s16le().size() / 2);
  if (values % channels != 0) {
    return Reject(reason, "bad_samples",
                  std::string(have_float ? "samples" : "pcm_s16le") + " holds " + std::to_string(values) +
                      " values, not a multiple of channel_count " + std::to_string(channels));
  }
  const int64_t per_channel = values / channels;
  if (per_channel > limits.max_samples_per_channel) {
    return Reject(reason, "oversize",
                  "block has " + std::to_string(per_channel) + " samples per channel; the limit is " +
                      std::to_string(limits.max_samples_per_channel));
  }
  if (out->samples.size() != static_cast<size_t>(values)) out->samples.resize(static_cast<size_t>(values));
  float* dst = out->samples.data();
  if (have_float) {
    const float* src = block.samples().data();
    // Finite iff the exponent bits are not all ones: an integer OR-reduction vectorises,
    // unlike a float accumulation or a branch per sample.
    uint32_t non_finite = 0;
    for (int64_t i = 0; i < values; ++i) {
      uint32_t bits;
      std::memcpy(&bits, src + i, sizeof bits);
      non_finite |= static_cast<uint32_t>((bits & 0x7f800000u) == 0x7f800000u);
    }
    if (non_finite != 0) {
      const auto bad = std::find_if(src, src + values, [](float v) { return !std::isfinite(v); });
      const int64_t index = bad - src;
      return Reject(reason, "non_finite",
                    "samples[" + std::to_string(index) + "] (frame " + std::to_string(index / channels) + ", channel " +
                        std::to_string(index % channels) + ") is not finite");
    }
    // De-interleave frame by frame: reads stream through the source once.
    for (int64_t i = 0; i < per_channel; ++i) {
      const float* frame = src + i * channels;
      for (int64_t c = 0; c < channels; ++c) dst[c * per_channel + i] = frame[c];
    }
  } else {
    // Widen to float in one contiguous (vectorised) pass, then de-interleave as above.
    const char* bytes = block.pcm_s16le().data();
    out->interleaved.resize(static_cast<size_t>(values));
    float* wide = out->interleaved.data();
    constexpr float kScale = 1.0f / 32768.0f;
    for (int64_t i = 0; i < values; ++i) {
      const auto lo = static_cast<uint16_t>(static_cast<unsigned char>(bytes[2 * i]));
      const auto hi = static_cast<uint16_t>(static_cast<unsigned char>(bytes[2 * i + 1]));
      wide[i] = static_cast<float>(static_cast<int16_t>(static_cast<uint16_t>(lo | (hi << 8)))) * kScale;
    }
    for (int64_t i = 0; i < per_channel; ++i) {
      const float* frame = wide + i * channels;
      for (int64_t c = 0; c < channels; ++c) dst[c * per_channel + i] = frame[c];
    }
  }
  out->view.sequence = block.sequence();
  out->view.channel_count = static_cast<int>(channels);
  out->view.samples_per_channel = per_channel;
  out->view.samples = dst;
  return Status::Ok();
}

void EncodeBlock(const engine::BlockView& block, bool pcm16, v1::SampleBlock* out) {
  out->set_sequence(block.sequence);
  out->set_channel_count(static_cast<uint32_t>(block.channel_count));
  const int64_t n = block.samples_per_channel;
  const int64_t channels = block.channel_count;
  out->clear_samples();
  out->clear_pcm_s16le();
  if (pcm16) {
    std::string* bytes = out->mutable_pcm_s16le();
    bytes->resize(static_cast<size_t>(2 * n * channels));
    for (int64_t i = 0; i < n; ++i) {
      for (int64_t c = 0; c < channels; ++c) {
        const float x = std::clamp(block.samples[c * n + i], -1.0f, 32767.0f / 32768.0f);
        const auto v = static_cast<int16_t>(std::lrint(x * 32768.0f));
        const auto u = static_cast<uint16_t>(v);
        (*bytes)[static_cast<size_t>(2 * (i * channels + c))] = static_cast<char>(u & 0xff);
        (*bytes)[static_cast<size_t>(2 * (i * channels + c) + 1)] = static_cast<char>(u >> 8);
      }
    }
    return;
  }
  auto* samples = out->mutable_samples();
  samples->Resize(static_cast<int>(n * channels), 0.0f);
  float* dst = samples->mutable_data();
  for (int64_t i = 0; i < n; ++i) {
    for (int64_t c = 0; c < channels; ++c) dst[i * channels + c] = block.samples[c * n + i];
  }
}

}  // namespace localizer::wire
