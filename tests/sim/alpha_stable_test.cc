#include "engine/sim/alpha_stable.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "tests/sim/npy_reader.h"

namespace localizer::engine {
namespace {

// Nolan's quantile table as shipped by Debian's python3-scipy (deploy/install.sh installs it).
// Columns: x, p, alpha, beta, pct: p = F(x) for S1(alpha, beta, 1, 0) computed by Nolan's
// stablec, pct the nominal percentile that x was solved for; alpha 0.1..2 step 0.1, beta
// -1..1 step 0.1, pct in {.01 .05 .1 .25 .35 .5 .65 .75 .9 .95 .99}. The file is stored with
// fortran_order True. It is in S1 ("Z1"), not S0: e.g. alpha 1.5, beta 1 has median -0.7167,
// which is S0's median shifted by -beta tan(pi alpha / 2) = -1 (scipy's own comment in
// test_distributions.py calls it "equivalent to S0", but the numbers match scipy's "S1").
constexpr char kNolanCdfTable[] =
    "/usr/lib/python3/dist-packages/scipy/stats/tests/data/levy_stable/"
    "stable-Z1-cdf-sample-data.npy";

constexpr int kSamples = 200000;
constexpr double kSigmas = 4.5;
constexpr double kTableRounding = 1e-3;

struct TableRow {
  double x, p;
};

const testing::NpyMatrix* Table() {
  static const auto* table = [] {
    StatusOr<testing::NpyMatrix> read = testing::ReadNpyMatrix(kNolanCdfTable);
    return read.ok() && read->cols == 5 ? new testing::NpyMatrix(std::move(*read)) : nullptr;
  }();
  return table;
}

// Rows for (alpha, beta) with p in [0.01, 0.99] (p is stored as e.g. 0.0099999999999999).
std::vector<TableRow> RowsFor(double alpha, double beta) {
  std::vector<TableRow> rows;
  const testing::NpyMatrix& t = *Table();
  for (int64_t r = 0; r < t.rows; ++r) {
    const double p = t.at(r, 1);
    if (std::abs(t.at(r, 2) - alpha) < 1e-9 && std::abs(t.at(r, 3) - beta) < 1e-9 && p >= 0.01 - 1e-9 &&
        p <= 0.99 + 1e-9) {
      rows.push_back({t.at(r, 0), p});
    }
  }
  return rows;
}

std::vector<double> SortedSamples(const AlphaStable& params, uint64_t seed, int n = kSamples) {
  std::mt19937_64 engine(seed);
  std::vector<double> samples(n);
  for (double& s : samples) s = SampleAlphaStable(params, engine);
  std::sort(samples.begin(), samples.end());
  return samples;
}

// Fraction of `sorted` that is <= x.
double Ecdf(const std::vector<double>& sorted, double x) {
  return static_cast<double>(std::upper_bound(sorted.begin(), sorted.end(), x) - sorted.begin()) /
         static_cast<double>(sorted.size());
}

// Checks the empirical CDF of `sorted` (standardised by (s - location) / scale) against every
// table row of (alpha, beta); returns the number of rows checked.
int ExpectMatchesTable(const std::vector<double>& sorted, double alpha, double beta, double scale = 1.0,
                       double location = 0.0) {
  const std::vector<TableRow> rows = RowsFor(alpha, beta);
  for (const TableRow& row : rows) {
    const double n = static_cast<double>(sorted.size());
    const double tolerance = kSigmas * std::sqrt(row.p * (1.0 - row.p) / n) + kTableRounding;
    EXPECT_NEAR(Ecdf(sorted, scale * row.x + location), row.p, tolerance)
        << "alpha " << alpha << " beta " << beta << " x " << row.x;
  }
  return static_cast<int>(rows.size());
}

class AlphaStableTable : public ::testing::Test {
 protected:
  void SetUp() override {
    if (Table() == nullptr) {
      StatusOr<testing::NpyMatrix> read = testing::ReadNpyMatrix(kNolanCdfTable);
      FAIL() << "cannot use Nolan's table (install python3-scipy: deploy/install.sh): "
             << (read.ok() ? "expected 5 columns, got " + std::to_string(read->cols) : read.status().ToString());
    }
  }
};

// All the (alpha, beta) pairs asked for are in the table (11 rows each); alpha 1 is added
// for the Cauchy (beta 0) and skewed alpha = 1 (beta 1) branch of the transform.
TEST_F(AlphaStableTable, EmpiricalCdfMatchesNolanS1Quantiles) {
  uint64_t seed = 1000;
  for (double alpha : {1.0, 1.1, 1.5, 1.7, 2.0}) {
    for (double beta : {0.0, 1.0}) {
      const std::vector<double> sorted = SortedSamples({alpha, beta}, ++seed);
      EXPECT_EQ(ExpectMatchesTable(sorted, alpha, beta), 11) << alpha << " " << beta;
    }
  }
}

TEST_F(AlphaStableTable, LocationAndScaleShiftTheStandardDistribution) {
  // For alpha != 1, S1(a, b, 3, -2) = 3 S1(a, b, 1, 0) - 2.
  uint64_t seed = 2000;
  for (double alpha : {1.5, 1.7}) {
    for (double beta : {0.0, 1.0}) {
      const std::vector<double> sorted = SortedSamples({alpha, beta, 3.0, -2.0}, ++seed);
      EXPECT_GT(ExpectMatchesTable(sorted, alpha, beta, 3.0, -2.0), 0) << alpha << " " << beta;
    }
  }
}

TEST_F(AlphaStableTable, SeedExperimentMixtureComponentHasTheTableMedian) {
  const AlphaStable component{1.7, 1.0, 10.0, -3.0};
  double table_median = std::numeric_limits<double>::quiet_NaN();
  const testing::NpyMatrix& t = *Table();
  for (int64_t r = 0; r < t.rows; ++r) {
    if (std::abs(t.at(r, 2) - 1.7) < 1e-9 && t.at(r, 3) == 1.0 && t.at(r, 4) == 0.5) {
      table_median = t.at(r, 0);
    }
  }
  ASSERT_TRUE(std::isfinite(table_median));
  EXPECT_NEAR(table_median, -0.331145, 1e-5);  // S1; S0's is -0.331145 - 1 * tan(0.85 pi)
  const std::vector<double> sorted = SortedSamples(component, 3001);
  const double expected = table_median * 10.0 - 3.0;
  const double median = 0.5 * (sorted[kSamples / 2 - 1] + sorted[kSamples / 2]);
  EXPECT_NEAR(median, expected, 0.25);  // standard error about 0.05
  EXPECT_NEAR(Ecdf(sorted, expected), 0.5, kSigmas * 0.5 / std::sqrt(double{kSamples}));
}

TEST(AlphaStable, AlphaTwoIsGaussianWithVarianceTwoScaleSquared) {
  const AlphaStable params{2.0, 0.7, 1.5, 0.8};  // beta has no effect at alpha 2
  std::mt19937_64 engine(42);
  const int n = kSamples;
  double sum = 0.0, sum_sq = 0.0;
  std::vector<double> samples(n);
  for (double& s : samples) {
    s = SampleAlphaStable(params, engine);
    sum += s;
  }
  const double mean = sum / n;
  for (double s : samples) sum_sq += (s - mean) * (s - mean);
  const double variance = sum_sq / (n - 1);
  const double expected_variance = 2.0 * 1.5 * 1.5;
  EXPECT_NEAR(mean, 0.8, kSigmas * std::sqrt(expected_variance / n));
  EXPECT_NEAR(variance, expected_variance, kSigmas * expected_variance * std::sqrt(2.0 / (n - 1)));
}

TEST(AlphaStable, TransformIsAffineInScaleAndLocation) {
  std::mt19937_64 engine(7);
  std::uniform_real_distribution<double> uniform(0.001, 0.999);
  std::exponential_distribution<double> exponential(1.0);
  for (int i = 0; i < 1000; ++i) {
    const double u = uniform(engine), w = exponential(engine);
    for (double alpha : {0.5, 1.0, 1.3, 2.0}) {
      for (double beta : {-1.0, 0.0, 0.4, 1.0}) {
        const double x = SampleAlphaStable({alpha, beta}, u, w);
        const double y = SampleAlphaStable({alpha, beta, 3.0, -2.0}, u, w);
        // alpha = 1 adds (2/pi) beta g ln g to the location (S1's alpha = 1 scale rule).
        const double extra = alpha == 1.0 ? 2.0 / std::numbers::pi * beta * 3.0 * std::log(3.0) : 0.0;
        EXPECT_NEAR(y, 3.0 * x - 2.0 + extra, 1e-12 * (1.0 + std::abs(y)))
            << alpha << " " << beta << " u " << u << " w " << w;
      }
    }
  }
}

TEST(AlphaStable, SymmetricIsOddInTheUniform) {
  for (double alpha : {0.7, 1.0, 1.5}) {
    for (double u : {0.05, 0.3, 0.49}) {
      EXPECT_NEAR(SampleAlphaStable({alpha, 0.0}, u, 0.8), -SampleAlphaStable({alpha, 0.0}, 1 - u, 0.8), 1e-9);
    }
  }
}

TEST(AlphaStable, SameSeedSameSamples) {
  const AlphaStable params{1.7, 1.0, 10.0, -3.0};
  std::mt19937_64 a(123), b(123), c(124);
  bool any_differs = false;
  for (int i = 0; i < 1000; ++i) {
    const double x = SampleAlphaStable(params, a);
    ASSERT_TRUE(std::isfinite(x));
    EXPECT_EQ(x, SampleAlphaStable(params, b));
    any_differs |= x != SampleAlphaStable(params, c);
  }
  EXPECT_TRUE(any_differs);
}

TEST(AlphaStable, ValidateAcceptsTheClosedEnds) {
  EXPECT_TRUE((AlphaStable{2.0, 1.0}.Validate().ok()));
  EXPECT_TRUE((AlphaStable{1e-3, -1.0, 1e-9, -1e9}.Validate().ok()));
  EXPECT_TRUE((AlphaStable{1.0, 0.0}.Validate().ok()));
}

TEST(AlphaStable, ValidateRejectsOutOfRangeNamingTheField) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const struct {
    AlphaStable params;
    const char* field = nullptr;
  } cases[] = {
      {{0.0, 0.0}, "alpha"},
      {{-1.0, 0.0}, "alpha"},
      {{2.0000001, 0.0}, "alpha"},
      {{nan, 0.0}, "alpha"},
      {{inf, 0.0}, "alpha"},
      {{1.5, 1.0000001}, "beta"},
      {{1.5, -1.5}, "beta"},
      {{1.5, nan}, "beta"},
      {{1.5, 0.0, 0.0}, "scale"},
      {{1.5, 0.0, -1.0}, "scale"},
      {{1.5, 0.0, inf}, "scale"},
      {{1.5, 0.0, nan}, "scale"},
      {{1.5, 0.0, 1.0, inf}, "location"},
      {{1.5, 0.0, 1.0, nan}, "location"},
  };
  for (const auto& c : cases) {
    const Status status = c.params.Validate();
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << c.field;
    EXPECT_EQ(status.message().rfind(c.field, 0), 0u) << status.message();
  }
}

TEST(NpyReader, MissingFileIsNotFound) {
  StatusOr<testing::NpyMatrix> read = testing::ReadNpyMatrix("/nonexistent/table.npy");
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), StatusCode::kNotFound);
}

TEST(NpyReader, ReadsBothOrdersAndRejectsMalformedFiles) {
  const std::string path = ::testing::TempDir() + "alpha_stable_test.npy";
  const auto write = [&](const std::string& header, size_t doubles) {
    std::string text = "\x93NUMPY" + std::string("\x01\x00", 2);
    text += static_cast<char>(header.size() & 0xff);
    text += static_cast<char>(header.size() >> 8);
    text += header;
    for (size_t i = 0; i < doubles; ++i) {
      const double v = static_cast<double>(i);
      text.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
    std::ofstream(path, std::ios::binary) << text;
  };
  write("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }\n", 6);
  StatusOr<testing::NpyMatrix> c_order = testing::ReadNpyMatrix(path);
  ASSERT_TRUE(c_order.ok()) << c_order.status().ToString();
  EXPECT_EQ(c_order->at(1, 0), 3.0);
  write("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 3), }\n", 6);
  StatusOr<testing::NpyMatrix> f_order = testing::ReadNpyMatrix(path);
  ASSERT_TRUE(f_order.ok()) << f_order.status().ToString();
  EXPECT_EQ(f_order->at(1, 0), 1.0);
  for (const auto& [header, doubles] : std::vector<std::pair<std::string, size_t>>{
           {"{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }\n", 6},
           {"{'descr': '<f8', 'fortran_order': False, 'shape': (6,), }\n", 6},
           {"{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }\n", 5},
           {"{'descr': '<f8', 'shape': (2, 3), }\n", 6},
           {"{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }\n", 0}}) {
    write(header, doubles);
    StatusOr<testing::NpyMatrix> read = testing::ReadNpyMatrix(path);
    EXPECT_FALSE(read.ok()) << header << " " << doubles;
    if (!read.ok()) {
      EXPECT_EQ(read.status().code(), StatusCode::kInvalidArgument) << header;
    }
  }
  std::ofstream(path, std::ios::binary) << "not an npy file";
  EXPECT_FALSE(testing::ReadNpyMatrix(path).ok());
}

}  // namespace
}  // namespace localizer::engine
