// The chi^2 gate: its quantiles, and a plot just inside or just outside it.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/tws/chi_square.h"
#include "engine/tws/tws_tracker.h"

namespace localizer::engine::tws {
namespace {

TEST(ChiSquare, QuantilesMatchTables) {
  // Standard table values (e.g. Bar-Shalom, Li & Kirubarajan, Table 1.5.4-1).
  EXPECT_NEAR(ChiSquareQuantile(1, 0.99), 6.635, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(2, 0.99), 9.210, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(3, 0.99), 11.345, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(3, 0.95), 7.815, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(4, 0.99), 13.277, 1e-3);
  for (int dof = 1; dof <= 6; ++dof) {
    EXPECT_NEAR(ChiSquareCdf(dof, ChiSquareQuantile(dof, 0.9995)), 0.9995, 1e-12);
  }
}

// A track started by one Cartesian plot at the origin (R = r I), then a plot at distance
// d along x one period later: the gate is d^2 / S_xx <= g with
// S_xx = r + dt^2 sigma_v^2 + q dt^4 / 4 + r (the one-point prior, predicted, plus R).
struct GateCase {
  double sxx;
  double g;
};

GateCase Expected(const TwsOptions& o, double r, double dt) {
  const double q = o.accel_noise_mps2 * o.accel_noise_mps2;
  const double sv2 = o.initial_speed_sigma_mps * o.initial_speed_sigma_mps;
  return {r + dt * dt * sv2 + q * dt * dt * dt * dt / 4.0 + r, ChiSquareQuantile(2, o.gate_probability)};
}

int AssignedSecondPlot(const TwsOptions& o, double r, double dt, double distance_m) {
  auto tracker = TwsTracker::Create(o);
  EXPECT_TRUE(tracker.ok());
  CartesianPlot first;
  first.covariance_m2 = r * Eigen::Matrix3d::Identity();
  EXPECT_TRUE((*tracker)->ProcessCartesian(0.0, {first}).ok());
  CartesianPlot second = first;
  second.position_m.x() = distance_m;
  ScanSummary summary;
  EXPECT_TRUE((*tracker)->ProcessCartesian(dt, {second}, &summary).ok());
  return summary.assigned;
}

TEST(Gate, PlotJustInsideIsAssignedJustOutsideStartsANewTrack) {
  for (int dims : {2, 3}) {
    TwsOptions o;
    o.dimensions = dims;
    const double r = 400.0, dt = 1.8182;
    GateCase c = Expected(o, r, dt);
    c.g = ChiSquareQuantile(dims, o.gate_probability);
    const double edge = std::sqrt(c.g * c.sxx);
    EXPECT_EQ(AssignedSecondPlot(o, r, dt, edge * (1.0 - 1e-6)), 1) << dims << "-D";
    EXPECT_EQ(AssignedSecondPlot(o, r, dt, edge * (1.0 + 1e-6)), 0) << dims << "-D";
  }
}

TEST(Gate, CorrelatedCovarianceGatesOnTheEllipseNotTheBox) {
  // Two plots at the same distance from the prediction, one along the long axis of a
  // strongly correlated R and one across it: only the first is inside.
  TwsOptions o;
  o.initial_speed_sigma_mps = 1.0;  // the prior barely widens the gate
  o.accel_noise_mps2 = 0.0;
  auto run = [&](const Eigen::Vector3d& offset) {
    auto tracker = TwsTracker::Create(o);
    CartesianPlot p;
    p.covariance_m2 << 10000.0, 9900.0, 0.0, 9900.0, 10000.0, 0.0, 0.0, 0.0, 1.0;
    EXPECT_TRUE((*tracker)->ProcessCartesian(0.0, {p}).ok());
    p.position_m = offset;
    ScanSummary s;
    EXPECT_TRUE((*tracker)->ProcessCartesian(1.0, {p}, &s).ok());
    return s.assigned;
  };
  const double d = 300.0 / std::sqrt(2.0);
  EXPECT_EQ(run({d, d, 0.0}), 1);   // along (1, 1): variance ~2 x 19900 per S
  EXPECT_EQ(run({d, -d, 0.0}), 0);  // across: variance ~2 x 100
}

}  // namespace
}  // namespace localizer::engine::tws
