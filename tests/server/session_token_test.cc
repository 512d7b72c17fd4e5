// Session ids and resume tokens must be unguessable: an attacker who opens sessions and
// reads their ids and tokens must not be able to compute another session's. The attack
// here is the one that worked on the registry's former std::mt19937_64 (whose hex digits
// were raw outputs): untemper 312 consecutive outputs, run the recurrence forward and
// predict the next session's id and token. It is shown to work on an mt19937_64 stream
// (so the test can fail), then run against the registry.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "server/metrics/registry.h"
#include "server/service/secure_random.h"
#include "server/service/session_registry.h"
#include "wire/config_wire.h"

namespace localizer::server {
namespace {

constexpr int kStateWords = 312;  // mt19937_64's n

// The former encoding: 16 hex digits per 64-bit output, least significant nibble first.
std::string HexOfOutput(uint64_t bits) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string s;
  for (int i = 0; i < 16; ++i, bits >>= 4) s.push_back(kHex[bits & 15]);
  return s;
}
uint64_t OutputOfHex(const std::string& hex16) {
  uint64_t bits = 0;
  for (int i = 15; i >= 0; --i) {
    const char c = hex16[static_cast<size_t>(i)];
    bits = (bits << 4) | static_cast<uint64_t>(c <= '9' ? c - '0' : c - 'a' + 10);
  }
  return bits;
}

// Inverse of y ^= (y >> shift) (& mask) for right shifts, and of y ^= (y << shift) & mask.
uint64_t UndoRightShiftXor(uint64_t y, int shift, uint64_t mask) {
  uint64_t x = y;
  for (int i = 0; i < 64 / shift + 1; ++i) x = y ^ ((x >> shift) & mask);
  return x;
}
uint64_t UndoLeftShiftXor(uint64_t y, int shift, uint64_t mask) {
  uint64_t x = y;
  for (int i = 0; i < 64 / shift + 1; ++i) x = y ^ ((x << shift) & mask);
  return x;
}
uint64_t Untemper(uint64_t y) {
  y = UndoRightShiftXor(y, 43, ~0ULL);
  y = UndoLeftShiftXor(y, 37, 0xfff7eee000000000ULL);
  y = UndoLeftShiftXor(y, 17, 0x71d67fffeda60000ULL);
  return UndoRightShiftXor(y, 29, 0x5555555555555555ULL);
}
uint64_t Temper(uint64_t x) {
  x ^= (x >> 29) & 0x5555555555555555ULL;
  x ^= (x << 17) & 0x71d67fffeda60000ULL;
  x ^= (x << 37) & 0xfff7eee000000000ULL;
  return x ^ (x >> 43);
}

// From 312 consecutive outputs, the next `count` outputs (the MT19937-64 recurrence).
std::vector<uint64_t> PredictNext(const std::vector<uint64_t>& outputs, int count) {
  std::vector<uint64_t> x;
  for (size_t i = outputs.size() - kStateWords; i < outputs.size(); ++i) x.push_back(Untemper(outputs[i]));
  std::vector<uint64_t> next;
  for (int k = 0; k < count; ++k) {
    const size_t n = x.size();
    const uint64_t y = (x[n - kStateWords] & 0xffffffff80000000ULL) | (x[n - kStateWords + 1] & 0x7fffffffULL);
    const uint64_t v = x[n - kStateWords + 156] ^ (y >> 1) ^ ((y & 1) ? 0xb5026f5aa96619e9ULL : 0);
    x.push_back(v);
    next.push_back(Temper(v));
  }
  return next;
}

TEST(SessionTokenAttack, PredictsAnMt19937StreamSoTheTestCanFail) {
  std::mt19937_64 engine(20261201);
  engine.discard(1234);  // the attacker does not know where the stream started
  std::vector<uint64_t> seen;
  for (int i = 0; i < kStateWords; ++i) seen.push_back(OutputOfHex(HexOfOutput(engine())));
  const std::vector<uint64_t> predicted = PredictNext(seen, 3);
  for (uint64_t p : predicted) EXPECT_EQ(p, engine());
}

engine::DetectionSessionConfig DetectionConfig() { return {}; }  // cheapest session to open

TEST(SessionTokenAttack, RegistryIdsAndTokensCannotBePredictedFromEarlierSessions) {
  WorkerPool pool(1);
  metrics::Registry metric_registry;
  auto metrics = ServiceMetrics::Create(&metric_registry, "cpu");
  ASSERT_TRUE(metrics.ok());
  RegistryOptions options;
  options.max_sessions = 200;
  SessionRegistry registry(options, &pool, metrics->get());
  const v1::SessionConfig config = wire::ConfigToProto(DetectionConfig(), "attacker");

  // Each session shows 3 outputs of the former generator: its id, then two for its token.
  std::vector<uint64_t> seen;
  std::set<std::string> secrets;
  while (static_cast<int>(seen.size()) < kStateWords) {
    auto host = registry.Open(config);
    ASSERT_TRUE(host.ok()) << host.status().message();
    const std::string id = (*host)->id();
    const std::string token = (*host)->resume_token();
    ASSERT_EQ(id.size(), 16u);
    ASSERT_EQ(token.size(), 32u);  // 128 bits
    EXPECT_EQ(token.find(id), std::string::npos) << "the id must carry no token material";
    EXPECT_TRUE(secrets.insert(id).second);
    EXPECT_TRUE(secrets.insert(token).second);
    seen.push_back(OutputOfHex(id));
    seen.push_back(OutputOfHex(token.substr(0, 16)));
    seen.push_back(OutputOfHex(token.substr(16, 16)));
  }
  const std::vector<uint64_t> predicted = PredictNext(seen, 3);
  auto victim = registry.Open(wire::ConfigToProto(DetectionConfig(), "victim"));
  ASSERT_TRUE(victim.ok());
  EXPECT_NE(HexOfOutput(predicted[0]), (*victim)->id());
  EXPECT_NE(HexOfOutput(predicted[1]) + HexOfOutput(predicted[2]), (*victim)->resume_token());
  EXPECT_FALSE(registry.Find((*victim)->id(), HexOfOutput(predicted[1]) + HexOfOutput(predicted[2])).ok());
}

TEST(SecureRandomHex, GivesHexDigitsOfTheAskedLengthAndRefusesNonPositive) {
  for (int digits : {1, 15, 16, 32, 33}) {
    auto hex = SecureRandomHex(digits);
    ASSERT_TRUE(hex.ok());
    EXPECT_EQ(static_cast<int>(hex->size()), digits);
    EXPECT_EQ(hex->find_first_not_of("0123456789abcdef"), std::string::npos);
  }
  EXPECT_FALSE(SecureRandomHex(0).ok());
}

// Every digit value appears about equally often (a broken encoder would skew it).
TEST(SecureRandomHex, DigitsAreUniform) {
  std::vector<int> counts(16, 0);
  for (int i = 0; i < 1000; ++i) {
    const std::string hex = *SecureRandomHex(32);
    for (char c : hex) ++counts[static_cast<size_t>(c <= '9' ? c - '0' : c - 'a' + 10)];
  }
  // 32000 digits, 2000 expected per value, sd ~43: 6 sd either way.
  for (int n : counts) EXPECT_NEAR(n, 2000, 260);
}

}  // namespace
}  // namespace localizer::server
