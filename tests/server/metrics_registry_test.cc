// Registry, Family and the text format (server/metrics/registry.h, family.h,
// text_format.h): name rules, label handling, the exact exposition text of a small
// registry, escaping, number formatting and scrape-time collectors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "server/metrics/names.h"
#include "server/metrics/registry.h"
#include "server/metrics/text_format.h"

namespace localizer::server::metrics {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(MetricNames, FollowThePrometheusRules) {
  for (const char* good : {"a", "_a", ":a", "a_b:c9", "localizer_blocks_total", "A"}) {
    EXPECT_TRUE(ValidateMetricName(good).ok()) << good;
  }
  for (const char* bad : {"", "9a", "a-b", "a b", "a.b", "é", "a{b}"}) {
    const Status s = ValidateMetricName(bad);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << bad;
  }
  for (const char* good : {"a", "_a", "a9", "stage_name"}) {
    EXPECT_TRUE(ValidateLabelName(good).ok()) << good;
  }
  for (const char* bad : {"", "9a", "a:b", "a-b", "__name__", "__x"}) {
    EXPECT_EQ(ValidateLabelName(bad).code(), StatusCode::kInvalidArgument) << bad;
  }
}

TEST(Registry, AddReturnsInvalidArgumentNamingTheProblem) {
  Registry registry;
  const auto bad_name = registry.AddCounter("requests-total", "Requests.");
  ASSERT_FALSE(bad_name.ok());
  EXPECT_EQ(bad_name.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad_name.status().message().find("requests-total"), std::string::npos);

  const auto reserved_label = registry.AddGauge("g", "Gauge.", {"__meta"});
  EXPECT_EQ(reserved_label.status().code(), StatusCode::kInvalidArgument);
  const auto bad_label = registry.AddGauge("g", "Gauge.", {"a-b"});
  EXPECT_EQ(bad_label.status().code(), StatusCode::kInvalidArgument);
  const auto repeated_label = registry.AddGauge("g", "Gauge.", {"a", "a"});
  EXPECT_EQ(repeated_label.status().code(), StatusCode::kInvalidArgument);
  const auto no_help = registry.AddGauge("g", "");
  EXPECT_EQ(no_help.status().code(), StatusCode::kInvalidArgument);
  const auto bad_help = registry.AddGauge("g", "\xff\xfe");
  EXPECT_EQ(bad_help.status().code(), StatusCode::kInvalidArgument);

  const auto le = registry.AddHistogram("h", "Histogram.", {"le"}, {1.0});
  EXPECT_EQ(le.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(le.status().message().find("le"), std::string::npos);
  EXPECT_TRUE(registry.AddGauge("gauge_with_le", "A gauge may use le.", {"le"}).ok());

  for (const std::vector<double>& bounds :
       std::vector<std::vector<double>>{{}, {1.0, 1.0}, {2.0, 1.0}, {1.0, kInf}, {std::nan("")}}) {
    EXPECT_EQ(registry.AddHistogram("h", "Histogram.", {}, bounds).status().code(), StatusCode::kInvalidArgument);
  }
  // Nothing above registered anything but gauge_with_le.
  EXPECT_EQ(registry.Collect().size(), 1u);
}

TEST(Registry, DuplicateNamesAndHistogramSeriesClashesAreRejected) {
  Registry registry;
  ASSERT_TRUE(registry.AddCounter("x_total", "X.").ok());
  const auto again = registry.AddGauge("x_total", "X again.");
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(again.status().message().find("already registered"), std::string::npos);

  ASSERT_TRUE(registry.AddHistogram("lat_seconds", "Latency.", {}, {1.0}).ok());
  EXPECT_FALSE(registry.AddGauge("lat_seconds_count", "Clash.").ok());
  EXPECT_FALSE(registry.AddCounter("lat_seconds_bucket", "Clash.").ok());
  ASSERT_TRUE(registry.AddGauge("depth_sum", "A gauge.").ok());
  EXPECT_FALSE(registry.AddHistogram("depth", "Clash.", {}, {1.0}).ok());
}

TEST(Family, WithLabelsReturnsTheSameSeriesForTheSameValues) {
  Registry registry;
  Family<Counter>* family = registry.AddCounter("c_total", "C.", {"a", "b"}).value();
  Counter* first = family->WithLabels({"x", "y"}).value();
  Counter* again = family->WithLabels({"x", "y"}).value();
  Counter* other = family->WithLabels({"x", "z"}).value();
  EXPECT_EQ(first, again);
  EXPECT_NE(first, other);
  first->Increment(2);
  EXPECT_EQ(again->value(), 2.0);
  EXPECT_EQ(other->value(), 0.0);

  const auto wrong_count = family->WithLabels({"x"});
  EXPECT_EQ(wrong_count.status().code(), StatusCode::kInvalidArgument);
  const auto bad_utf8 = family->WithLabels({"x", "\xc3\x28"});
  EXPECT_EQ(bad_utf8.status().code(), StatusCode::kInvalidArgument);
  // Creating many more series does not move the ones already handed out.
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(family->WithLabels({std::to_string(i), ""}).ok());
  EXPECT_EQ(family->WithLabels({"x", "y"}).value(), first);
  EXPECT_EQ(first->value(), 2.0);
}

TEST(TextFormat, SmallRegistryGivesTheExactText) {
  Registry registry;
  // Registered out of name order: families come out sorted by name.
  Family<Gauge>* temperature = registry.AddGauge("app_temperature_celsius", "Temperature.").value();
  Family<Counter>* requests =
      registry.AddCounter("app_requests_total", "Requests served.\nBy path \\ code.", {"path", "code"}).value();
  Family<Histogram>* latency =
      registry.AddHistogram("app_latency_seconds", "Latency.", {"stage"}, {0.25, 0.5, 1.0}).value();

  temperature->WithLabels({}).value()->Set(-2.5);
  requests->WithLabels({"/b\"x\"\n\\", "500"}).value()->Increment(1.5);
  requests->WithLabels({"/a", "200"}).value()->Increment(3);
  Histogram* gcc = latency->WithLabels({"gcc"}).value();
  for (const double v : {0.125, 0.25, 0.375, 4.0}) gcc->Observe(v);

  // Derived by hand from the 0.4.0 format: 0.25 is on a bound, so le="0.25" counts 2.
  const std::string expected =
      "# HELP app_latency_seconds Latency.\n"
      "# TYPE app_latency_seconds histogram\n"
      "app_latency_seconds_bucket{stage=\"gcc\",le=\"0.25\"} 2\n"
      "app_latency_seconds_bucket{stage=\"gcc\",le=\"0.5\"} 3\n"
      "app_latency_seconds_bucket{stage=\"gcc\",le=\"1\"} 3\n"
      "app_latency_seconds_bucket{stage=\"gcc\",le=\"+Inf\"} 4\n"
      "app_latency_seconds_sum{stage=\"gcc\"} 4.75\n"
      "app_latency_seconds_count{stage=\"gcc\"} 4\n"
      "# HELP app_requests_total Requests served.\\nBy path \\\\ code.\n"
      "# TYPE app_requests_total counter\n"
      "app_requests_total{path=\"/a\",code=\"200\"} 3\n"
      "app_requests_total{path=\"/b\\\"x\\\"\\n\\\\\",code=\"500\"} 1.5\n"
      "# HELP app_temperature_celsius Temperature.\n"
      "# TYPE app_temperature_celsius gauge\n"
      "app_temperature_celsius -2.5\n";
  EXPECT_EQ(registry.Serialize(), expected);
}

TEST(TextFormat, FamilyWithoutSeriesWritesOnlyHelpAndType) {
  Registry registry;
  ASSERT_TRUE(registry.AddCounter("empty_total", "Nothing yet.", {"kind"}).ok());
  EXPECT_EQ(registry.Serialize(), "# HELP empty_total Nothing yet.\n# TYPE empty_total counter\n");
}

TEST(TextFormat, EscapesLabelValuesAndHelp) {
  EXPECT_EQ(EscapeLabelValue("a\\b\"c\nd'e\tf"), "a\\\\b\\\"c\\nd'e\tf");
  EXPECT_EQ(EscapeHelp("a\\b\"c\nd"), "a\\\\b\"c\\nd");  // quotes stay as they are in HELP
  EXPECT_EQ(EscapeLabelValue("naïve ☃"), "naïve ☃");     // UTF-8 passes through
}

TEST(TextFormat, NumbersAsPrometheusSpellsThem) {
  EXPECT_EQ(FormatNumber(0.0), "0");
  EXPECT_EQ(FormatNumber(-0.0), "0");
  EXPECT_EQ(FormatNumber(3.0), "3");
  EXPECT_EQ(FormatNumber(-12.0), "-12");
  EXPECT_EQ(FormatNumber(1e6), "1000000");  // integer-valued: no exponent
  EXPECT_EQ(FormatNumber(9007199254740991.0), "9007199254740991");
  EXPECT_EQ(FormatNumber(1e16), "1e+16");  // beyond 2^53
  EXPECT_EQ(FormatNumber(0.1), "0.1");
  EXPECT_EQ(FormatNumber(-1.5), "-1.5");
  // As Go's FormatFloat(v, 'g', -1, 64): plain for exponents -4..5, else exponent form.
  EXPECT_EQ(FormatNumber(1e-4), "0.0001");
  EXPECT_EQ(FormatNumber(2.5e-4), "0.00025");
  EXPECT_EQ(FormatNumber(2.5e-5), "2.5e-05");
  EXPECT_EQ(FormatNumber(123456.5), "123456.5");
  EXPECT_EQ(FormatNumber(1234567.5), "1.2345675e+06");
  EXPECT_EQ(FormatNumber(1e300), "1e+300");
  EXPECT_EQ(FormatNumber(-1e-300), "-1e-300");
  EXPECT_EQ(FormatNumber(kInf), "+Inf");
  EXPECT_EQ(FormatNumber(-kInf), "-Inf");
  EXPECT_EQ(FormatNumber(std::nan("")), "NaN");
}

TEST(TextFormat, NumbersRoundTripThroughStrtod) {
  std::mt19937_64 rng(20240611);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-300, 300);
  for (int i = 0; i < 100000; ++i) {
    const double v = std::ldexp(mantissa(rng), exponent(rng));
    const std::string text = FormatNumber(v);
    ASSERT_EQ(std::strtod(text.c_str(), nullptr), v) << text;
  }
}

TEST(Registry, CollectorsRunBeforeEverySerialization) {
  Registry registry;
  Gauge* depth = registry.AddGauge("queue_depth", "Blocks waiting.").value()->WithLabels({}).value();
  int scrapes = 0;
  registry.AddCollector([&] { depth->Set(++scrapes * 10); });
  EXPECT_EQ(registry.Serialize(), "# HELP queue_depth Blocks waiting.\n# TYPE queue_depth gauge\nqueue_depth 10\n");
  EXPECT_NE(registry.Serialize().find("queue_depth 20\n"), std::string::npos);
  EXPECT_EQ(scrapes, 2);
}

TEST(Registry, CollectorMayRegisterAndLabelMetrics) {
  Registry registry;
  registry.AddCollector([&registry] {
    static int calls = 0;
    if (calls++ == 0) {
      auto family = registry.AddGauge("late_gauge", "Registered by a collector.", {"k"});
      ASSERT_TRUE(family.ok());
      (*family)->WithLabels({"v"}).value()->Set(1);
    }
  });
  EXPECT_EQ(registry.Serialize(),
            "# HELP late_gauge Registered by a collector.\n# TYPE late_gauge gauge\n"
            "late_gauge{k=\"v\"} 1\n");
}

TEST(Buckets, ExponentialBuckets) {
  EXPECT_EQ(ExponentialBuckets(1.0, 2.0, 4), (std::vector<double>{1, 2, 4, 8}));
  EXPECT_EQ(ExponentialBuckets(0.5, 10.0, 1), (std::vector<double>{0.5}));
  EXPECT_TRUE(ExponentialBuckets(0.0, 2.0, 4).empty());
  EXPECT_TRUE(ExponentialBuckets(-1.0, 2.0, 4).empty());
  EXPECT_TRUE(ExponentialBuckets(1.0, 1.0, 4).empty());
  EXPECT_TRUE(ExponentialBuckets(1.0, 2.0, 0).empty());
  EXPECT_TRUE(ExponentialBuckets(1e300, 1e10, 3).empty());  // overflows to +Inf
  Registry registry;
  EXPECT_EQ(registry.AddHistogram("h", "H.", {}, ExponentialBuckets(1, 1, 1)).status().code(),
            StatusCode::kInvalidArgument);
}

TEST(Buckets, DefaultLatencyBucketsCoverTenMicrosecondsToOneSecond) {
  const std::vector<double> bounds = DefaultLatencyBucketsSeconds();
  EXPECT_TRUE(ValidateBucketBounds(bounds).ok());
  EXPECT_EQ(bounds.front(), 1e-5);
  EXPECT_EQ(bounds.back(), 1.0);
  EXPECT_LE(bounds.size(), 20u);
  for (size_t i = 1; i < bounds.size(); ++i) {
    EXPECT_LE(bounds[i] / bounds[i - 1], 2.5 + 1e-12) << i;  // at most 2.5x apart
  }
}

TEST(Utf8, AcceptsWellFormedAndRejectsMalformedSequences) {
  EXPECT_TRUE(IsValidUtf8(""));
  EXPECT_TRUE(IsValidUtf8("plain ascii"));
  EXPECT_TRUE(IsValidUtf8("\xc3\xa9 \xe2\x98\x83 \xf0\x9f\x94\x8a"));  // é ☃ 🔊
  EXPECT_FALSE(IsValidUtf8("\x80"));                                   // lone continuation byte
  EXPECT_FALSE(IsValidUtf8("\xc3"));                                   // truncated
  EXPECT_FALSE(IsValidUtf8("\xc0\xaf"));                               // overlong '/'
  EXPECT_FALSE(IsValidUtf8("\xed\xa0\x80"));                           // surrogate U+D800
  EXPECT_FALSE(IsValidUtf8("\xf4\x90\x80\x80"));                       // above U+10FFFF
}

}  // namespace
}  // namespace localizer::server::metrics
