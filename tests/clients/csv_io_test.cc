#include "clients/io/csv_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "clients/io/presence_summary.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::FirstLine;
using testing::TempDir;

TEST(CsvIo, TruthRoundTrips) {
  TempDir dir;
  std::vector<engine::TruthRow> truth;
  for (int i = 0; i < 50; ++i) {
    engine::TruthRow row;
    row.t_s = 0.01 * i;
    row.position_m = engine::Vec3(1.0 + 0.123456789 * i, -2.5, 3.0 / 7.0);
    row.velocity_mps = engine::Vec3(1.5, 0.0, -0.25);
    truth.push_back(row);
  }
  ASSERT_TRUE(WriteTruthCsv(dir.File("truth.csv"), truth).ok());
  EXPECT_EQ(FirstLine(dir.File("truth.csv")), "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps");
  auto read = ReadTruthCsv(dir.File("truth.csv"));
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  ASSERT_EQ(read->size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    EXPECT_NEAR((*read)[i].t_s, truth[i].t_s, 1e-12);
    EXPECT_LT(((*read)[i].position_m - truth[i].position_m).norm(), 1e-8);
    EXPECT_LT(((*read)[i].velocity_mps - truth[i].velocity_mps).norm(), 1e-8);
  }
}

engine::Estimate MakeEstimate(double t_s, bool initialised) {
  engine::Estimate e;
  e.t_s = t_s;
  e.initialised = initialised;
  e.state << 1, 2, 3, 0.1, 0.2, 0.3;
  e.covariance = engine::Mat6::Identity() * 0.04;
  e.ess = 900;
  e.nis = 2.5;
  e.delay_s = {1e-4, -2e-4, 3e-4};
  e.quality = {5, 6, 7};
  e.timings.tdoa_s = 0.001;
  e.timings.filter_s = 0.002;
  return e;
}

TEST(CsvIo, EstimatesHeaderAndRows) {
  TempDir dir;
  auto writer = EstimatesCsvWriter::Open(dir.File("est.csv"), {1, 2, 3});
  ASSERT_TRUE(writer.ok());
  ASSERT_TRUE(writer->Write(MakeEstimate(0.25, false)).ok());
  engine::Estimate short_pairs = MakeEstimate(0.5, true);
  short_pairs.delay_s.clear();  // an estimate without pair data still writes a full row
  ASSERT_TRUE(writer->Write(short_pairs).ok());
  ASSERT_TRUE(writer->Close().ok());
  EXPECT_EQ(FirstLine(dir.File("est.csv")),
            "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,sx_m,sy_m,sz_m,ess,nis,pairs_used,tdoa_sigma_us,initialised,"
            "reinitialised,tdoa_ms,filter_ms,source_present,presence_statistic,presence_threshold,ambiguous,modes,far_field,range_sd_m,"
            "delay_s_1,quality_1,delay_s_2,quality_2,"
            "delay_s_3,quality_3");
  auto rows = ReadEstimatesCsv(dir.File("est.csv"));
  ASSERT_TRUE(rows.ok()) << rows.status().ToString();
  ASSERT_EQ(rows->size(), 2u);
  EXPECT_FALSE((*rows)[0].initialised);
  EXPECT_TRUE((*rows)[1].initialised);
  EXPECT_EQ((*rows)[1].t_s, 0.5);
  EXPECT_EQ((*rows)[1].position_m, engine::Vec3(1, 2, 3));
  EXPECT_NEAR((*rows)[1].velocity_mps.z(), 0.3, 1e-12);
}

TEST(CsvIo, PresenceColumnsRoundTrip) {
  TempDir dir;
  auto writer = EstimatesCsvWriter::Open(dir.File("est.csv"), {1, 2, 3});
  ASSERT_TRUE(writer.ok());
  engine::Estimate silent = MakeEstimate(0.25, false);
  silent.presence_statistic = 2.5;
  silent.presence_threshold = 6.75;
  engine::Estimate heard = MakeEstimate(0.5, true);
  heard.source_present = true;
  heard.presence_statistic = 31.25;
  heard.presence_threshold = 6.75;
  heard.ambiguous = true;
  heard.modes = 2;
  ASSERT_TRUE(writer->Write(silent).ok());
  ASSERT_TRUE(writer->Write(heard).ok());
  ASSERT_TRUE(writer->Close().ok());
  auto rows = ReadEstimatesCsv(dir.File("est.csv"));
  ASSERT_TRUE(rows.ok()) << rows.status().ToString();
  ASSERT_EQ(rows->size(), 2u);
  ASSERT_TRUE((*rows)[0].source_present.has_value());
  EXPECT_FALSE(*(*rows)[0].source_present);
  EXPECT_EQ((*rows)[0].presence_statistic, 2.5);
  EXPECT_EQ((*rows)[0].presence_threshold, 6.75);
  EXPECT_FALSE((*rows)[0].ambiguous);
  EXPECT_EQ((*rows)[0].modes, 0);
  ASSERT_TRUE((*rows)[1].source_present.has_value());
  EXPECT_TRUE(*(*rows)[1].source_present);
  EXPECT_EQ((*rows)[1].presence_statistic, 31.25);
  EXPECT_TRUE((*rows)[1].ambiguous);
  EXPECT_EQ((*rows)[1].modes, 2);
}

TEST(CsvIo, EstimatesWithoutPresenceColumnsStillRead) {
  TempDir dir;
  {
    std::ofstream out(dir.File("old.csv"));  // as written before the presence columns
    out << "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,sx_m,sy_m,sz_m,ess,nis,pairs_used,tdoa_sigma_us,initialised,"
           "reinitialised,tdoa_ms,filter_ms,delay_s_1,quality_1\n"
           "0.5,1,2,3,0,0,0,0.1,0.1,0.1,900,2,3,10,1,0,0.1,0.2,1e-4,5\n";
  }
  auto rows = ReadEstimatesCsv(dir.File("old.csv"));
  ASSERT_TRUE(rows.ok()) << rows.status().ToString();
  ASSERT_EQ(rows->size(), 1u);
  EXPECT_TRUE((*rows)[0].initialised);
  EXPECT_EQ((*rows)[0].position_m, engine::Vec3(1, 2, 3));
  EXPECT_FALSE((*rows)[0].source_present.has_value());
  {
    std::ofstream out(dir.File("half.csv"));  // some presence columns but not all: named
    out << "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,initialised,source_present\n0.5,1,2,3,0,0,0,1,1\n";
  }
  auto half = ReadEstimatesCsv(dir.File("half.csv"));
  ASSERT_FALSE(half.ok());
  EXPECT_NE(half.status().message().find("presence_statistic"), std::string::npos) << half.status().message();
}

TEST(PresenceSummary, FarFieldLineCountsThePositionsWithoutARange) {
  PresenceSummary summary;
  summary.Add(MakeEstimate(0.0, false));  // not initialised: not a position
  for (int i = 1; i <= 4; ++i) summary.Add(MakeEstimate(0.1 * i, true));
  EXPECT_FALSE(summary.FarFieldLine().has_value());
  engine::Estimate far = MakeEstimate(0.5, true);
  far.far_field = true;
  summary.Add(far);
  ASSERT_TRUE(summary.FarFieldLine().has_value());
  EXPECT_EQ(*summary.FarFieldLine(),
            "range unobservable (far field) in 1 of 5 positions: their direction from the array's centroid holds, "
            "their range does not");
}

TEST(PresenceSummary, NoSourceLineWhenNoFrameHeldASource) {
  PresenceSummary summary;
  for (int i = 0; i < 12; ++i) {
    engine::Estimate e = MakeEstimate(0.1 * i, false);
    e.presence_statistic = 1.0 + 0.25 * i;  // max 3.75 on the last frame
    e.presence_threshold = 6.5;
    summary.Add(e);
  }
  ASSERT_TRUE(summary.NoSourceLine().has_value());
  EXPECT_EQ(*summary.NoSourceLine(), "no source found in 12 frames (presence statistic max 3.75, threshold 6.5)");
  engine::Estimate heard = MakeEstimate(1.3, true);
  heard.source_present = true;
  heard.presence_statistic = 9.0;
  heard.presence_threshold = 6.5;
  summary.Add(heard);
  EXPECT_FALSE(summary.NoSourceLine().has_value());
  EXPECT_EQ(summary.present, 1u);
  // Estimates that carry no presence test (threshold 0: an engine or server that does not
  // report presence) never read as a silent run.
  PresenceSummary untested;
  for (int i = 0; i < 5; ++i) untested.Add(MakeEstimate(0.1 * i, true));
  EXPECT_FALSE(untested.NoSourceLine().has_value());
}

// Found with fuzz_csv_readers (UBSan: "nan is outside the range of representable values of
// type 'int'"): the modes column was cast to int unchecked. A value that is not a whole count
// is refused, naming the file, row and column.
TEST(CsvIo, ModesThatAreNotACountAreRefused) {
  TempDir dir;
  for (const char* modes : {"nan", "1e300", "-1", "2.5", "inf"}) {
    {
      std::ofstream out(dir.File("est.csv"));
      out << "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,initialised,source_present,presence_statistic,"
             "presence_threshold,ambiguous,modes\n0,0,0,0,0,0,0,1,1,0,0,0,1\n0.1,0,0,0,0,0,0,1,1,0,0,0,"
          << modes << "\n";
    }
    auto rows = ReadEstimatesCsv(dir.File("est.csv"));
    ASSERT_FALSE(rows.ok()) << modes;
    EXPECT_EQ(rows.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(rows.status().message().find("data row 2, column modes: value " + std::string(modes)), std::string::npos)
        << rows.status().message();
  }
}

TEST(CsvIo, ReadErrorsNameFileLineAndColumn) {
  TempDir dir;
  {
    std::ofstream out(dir.File("bad.csv"));
    out << "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps\n0,1,2,3,0,0,0\n0.1,1,abc,3,0,0,0\n";
  }
  auto bad = ReadTruthCsv(dir.File("bad.csv"));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("bad.csv:3: column y_m is \"abc\""), std::string::npos)
      << bad.status().message();
  {
    std::ofstream out(dir.File("nocol.csv"));
    out << "t_s,x_m,y_m\n0,1,2\n";
  }
  auto missing = ReadTruthCsv(dir.File("nocol.csv"));
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("no column named z_m"), std::string::npos);
  auto no_flag = ReadEstimatesCsv(dir.File("bad.csv"));
  ASSERT_FALSE(no_flag.ok());
}

}  // namespace
}  // namespace localizer::io
