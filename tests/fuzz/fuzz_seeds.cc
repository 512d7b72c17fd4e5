// Writes the seed corpora of the fuzz targets: fuzz_seeds OUT_DIR writes OUT_DIR/<target>/*
// (the `fuzz_corpus` build target, deploy/check.sh). The seeds are valid inputs like the
// tests' (a tetrahedral array, detection and moving-array configs, blocks in both encodings,
// IMU batches, scans, array.json, the CSV tables and WAV files the CLI writes), the XAV
// hydrophone table when ../shared/data holds it, and every input checked in under
// tests/fuzz/regressions/<target>/ (what the fuzzers once found). Idempotent: files are
// named by content and overwritten.
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/util/delimited_message_util.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>

#include "clients/io/array_json.h"
#include "clients/io/csv_io.h"
#include "clients/io/wav_io.h"
#include "fuzz_util.h"
#include "wire/block_wire.h"
#include "wire/imu_wire.h"
#include "wire/scan_wire.h"

namespace fs = std::filesystem;
using namespace localizer;

namespace {

fs::path g_out;

void Seed(const std::string& target, const std::string& bytes) {
  const fs::path dir = g_out / target;
  fs::create_directories(dir);
  std::ostringstream name;
  name << "seed-" << std::hex << std::hash<std::string>{}(bytes);
  std::ofstream(dir / name.str(), std::ios::binary) << bytes;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

v1::SampleBlock Block(int channels, int frames, bool pcm16, uint64_t sequence) {
  std::vector<float> samples(static_cast<size_t>(channels * frames));
  for (int c = 0; c < channels; ++c) {
    for (int i = 0; i < frames; ++i)
      samples[c * frames + i] = 0.25f * static_cast<float>(((i * 7 + c * 3) % 17) - 8) / 8;
  }
  engine::BlockView view{sequence, channels, frames, samples.data()};
  v1::SampleBlock block;
  wire::EncodeBlock(view, pcm16, &block);
  return block;
}

v1::ImuBatch Imu(bool mag, bool origin) {
  std::vector<engine::ImuSample> samples;
  for (int i = 0; i < 3; ++i) {
    engine::ImuSample s;
    s.t_s = 0.01 * i;
    s.gyro_rps = {0.01, -0.02, 0.1 * i};
    s.accel_mps2 = {0.0, 0.1, 9.81};
    if (mag) s.mag_uT = {20.0, 5.0, -40.0};
    samples.push_back(s);
  }
  const engine::Vec3 o(1.0, 2.0, -3.0);
  v1::ImuBatch batch;
  wire::EncodeImuBatch(samples, origin ? &o : nullptr, 5, &batch);
  return batch;
}

v1::Scan ScanOf(bool elevation) {
  engine::Scan scan;
  scan.time_s = 1.5;
  scan.sensor_position_m = {0.0, 0.0, 10.0};
  for (int i = 0; i < 3; ++i) {
    engine::Detection d;
    d.range_m = 1000.0 + 250.0 * i;
    d.bearing_rad = -1.0 + i;
    if (elevation) d.elevation_rad = 0.1 * i;
    if (i == 1) d.snr_db = 12.0;
    scan.detections.push_back(d);
  }
  v1::Scan p;
  wire::EncodeScan(scan, 3, &p);
  return p;
}

std::vector<v1::SessionConfig> Configs() {
  std::vector<v1::SessionConfig> configs;
  configs.push_back(fuzz::TetraConfig());
  v1::SessionConfig c = fuzz::TetraConfig();
  c.set_frame_samples(2048);
  c.set_hop_samples(512);
  c.set_weighting(v1::WEIGHTING_PHAT_BETA);
  c.set_phat_beta(0.7);
  c.set_band_low_hz(100.0);
  c.set_band_high_hz(9000.0);
  c.mutable_filter()->set_particles(777);
  c.mutable_filter()->set_likelihood(v1::LIKELIHOOD_MIXTURE);
  c.mutable_filter()->set_outlier_probability(0.2);
  c.set_seed(0);
  c.mutable_init_region()->mutable_min_m()->set_x(-1.0);
  c.mutable_init_region()->mutable_max_m()->set_x(1.0);
  c.mutable_bounds()->set_max_z_m(0.0);
  c.mutable_bounds()->set_min_z_m(-8.0);
  c.set_search_radius_m(30.0);
  c.set_presence_false_alarm(0.01);
  c.set_source_timeout_s(5.0);
  c.set_despike_k(0.0);
  configs.push_back(c);
  c = fuzz::TetraConfig();
  c.mutable_filter()->set_type(v1::FILTER_TYPE_IMM);
  c.mutable_filter()->set_imm_modes("cv,ca");
  c.mutable_filter()->set_imm_variant("ukf");
  c.mutable_filter()->set_robust("huber");
  c.set_backend("cpu");
  configs.push_back(c);
  c = fuzz::TetraConfig();
  c.mutable_filter()->set_type(v1::FILTER_TYPE_UKF);
  c.mutable_filter()->set_motion_model("singer");
  configs.push_back(c);
  c = fuzz::TetraConfig();  // a moving array
  c.mutable_platform()->set_attitude_filter("euler");
  c.mutable_platform()->set_use_magnetometer(true);
  c.mutable_platform()->mutable_origin_m()->set_z(-2.0);
  configs.push_back(c);
  v1::SessionConfig d;  // a detection session
  d.mutable_detections()->set_dimensions(3);
  d.mutable_detections()->set_confirm_hits(2);
  d.mutable_detections()->set_two_point_initiation(true);
  d.mutable_detections()->set_max_tracks(100);
  d.set_label("radar");
  configs.push_back(d);
  return configs;
}

std::string Delimited(const std::vector<v1::TrackRequest>& requests) {
  std::string bytes;
  google::protobuf::io::StringOutputStream out(&bytes);
  for (const v1::TrackRequest& r : requests) google::protobuf::util::SerializeDelimitedToZeroCopyStream(r, &out);
  return bytes;
}

void ProtoSeeds() {
  const std::vector<v1::SessionConfig> configs = Configs();
  for (const v1::SessionConfig& c : configs) Seed("fuzz_session_config", c.SerializeAsString());
  for (const bool pcm16 : {false, true}) {
    Seed("fuzz_sample_block", std::string{3, 8} + Block(4, 16, pcm16, 7).SerializeAsString());
    Seed("fuzz_sample_block", std::string{0, 1} + Block(1, 5, pcm16, 1).SerializeAsString());
  }
  Seed("fuzz_imu_batch", Imu(true, false).SerializeAsString());
  Seed("fuzz_imu_batch", Imu(false, true).SerializeAsString());
  Seed("fuzz_scan", ScanOf(true).SerializeAsString());
  Seed("fuzz_scan", ScanOf(false).SerializeAsString());
  for (const bool pcm16 : {false, true}) {
    v1::LocateRequest locate;
    *locate.mutable_config() = configs[0];
    *locate.mutable_block() = Block(4, 64, pcm16, 1);
    Seed("fuzz_locate_request", locate.SerializeAsString());
  }
  // Streams: audio (blocks), moving array (IMU then blocks), detections (scans), a resume.
  v1::TrackRequest open, block, imu, scan, resume;
  *open.mutable_open() = configs[0];
  *block.mutable_block() = Block(4, 32, false, 1);
  Seed("fuzz_track_stream", Delimited({open, block, block}));
  *block.mutable_block() = Block(4, 32, true, 2);
  *imu.mutable_imu() = Imu(true, true);
  *open.mutable_open() = configs[4];
  Seed("fuzz_track_stream", Delimited({open, imu, block}));
  *open.mutable_open() = configs[5];
  *scan.mutable_scan() = ScanOf(true);
  Seed("fuzz_track_stream", Delimited({open, scan, scan}));
  resume.mutable_resume()->set_session_id("0123456789abcdef0123456789abcdef");
  resume.mutable_resume()->set_resume_token("fedcba9876543210fedcba9876543210");
  resume.mutable_resume()->set_last_frame_received(4);
  Seed("fuzz_track_stream", Delimited({resume, block}));
}

// The file readers' seeds are written by the writers the CLI uses, into a scratch folder.
void FileSeeds(const fs::path& scratch) {
  fs::create_directories(scratch);
  io::ArrayFile array;
  array.sensors_m = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  array.sound_speed_mps = 1500.0;
  array.sample_rate_hz = 48000.0;
  array.reference_sensor = 1;
  array.band_hz = std::make_pair(300.0, 3000.0);
  array.bounds_max_m.z() = 7.03;
  array.bounds_min_m.x() = -50.0;
  const fs::path json = scratch / "array.json";
  if (io::WriteArrayJson(json, array).ok()) Seed("fuzz_array_json", ReadFile(json));
  Seed("fuzz_array_json",
       R"({"sound_speed_mps": 343, "sensors_m": [[0,0,0],[0.1,0,0],[0,0.1,0],[0,0,0.1]], "surface_z_m": 2.5,)"
       R"( "bottom_z_m": -1, "bounds_min_m": [null, -5, null], "bounds_max_m": ["inf", 5, null]})");
  Seed("fuzz_array_json",  // a session file: the array and its "session" settings (session_file.h)
       R"({"sound_speed_mps": 1500, "sensors_m": [[0,0,0],[2,0,0],[0,2,0],[0,0,2]], "session": {"filter": "ekf",)"
       R"( "motion_model": "ct", "particles": 1024, "frame_samples": 2048, "hop_samples": 1024, "seed": 7,)"
       R"( "tdoa_sigma_s": 2.5e-05, "imm_modes": "cv,ct", "weighting": "phat-beta", "phat_beta": 0.5}})");

  // Room scenes: the named ones of the tree, and one with every field.
  for (const auto& entry : fs::directory_iterator(fs::path(LOCALIZER_SOURCE_DIR) / "scenes" / "rooms")) {
    Seed("fuzz_room_scene", ReadFile(entry.path()));
  }
  Seed("fuzz_room_scene",
       R"({"room": {"size_m": [6, 5, 3], "rt60_s": 0.3}, "array_position_m": [2, 2, 1], "sample_rate_hz": 8000,)"
       R"( "duration_s": 2, "noise_db": -30, "sources": [{"position_m": [4, 3, 1.5], "signal": "tones",)"
       R"( "band_hz": [200, 3000], "level_db": -6, "on_s": [0.2, 0.5], "off_s": [0.1, 0.3], "start_s": 0.5,)"
       R"( "stop_s": 1.5}]})");

  const auto csv_seed = [](char selector, const std::string& text) { Seed("fuzz_csv_readers", selector + text); };
  std::vector<engine::TruthRow> truth(3);
  for (int i = 0; i < 3; ++i) {
    truth[i].t_s = 0.1 * i;
    truth[i].position_m = {1.0 * i, 2.0, -3.0};
    truth[i].velocity_mps = {1.0, 0.0, 0.5};
  }
  if (io::WriteTruthCsv(scratch / "truth.csv", truth).ok()) csv_seed(0, ReadFile(scratch / "truth.csv"));
  auto writer = io::EstimatesCsvWriter::Open(scratch / "estimates.csv", {1, 2, 3});
  if (writer.ok()) {
    engine::Estimate e;
    e.initialised = true;
    e.state << 1.0, 2.0, 3.0, 0.5, 0.0, -0.5;
    (void)writer->Write(e);
    (void)writer->Write(e);
    if (writer->Close().ok()) csv_seed(1, ReadFile(scratch / "estimates.csv"));
  }
  const std::string imu =
      "t_s,gyr_x_rps,gyr_y_rps,gyr_z_rps,acc_x_mps2,acc_y_mps2,acc_z_mps2,mag_x_uT,mag_y_uT,mag_z_uT,"
      "truth_qw,truth_qx,truth_qy,truth_qz,movement\n"
      "0.00,0.01,0.02,0.03,0.1,0.2,9.81,20,5,-40,1,0,0,0,1\n"
      "0.01,0.01,0.02,0.03,0.1,0.2,9.81,nan,nan,nan,nan,nan,nan,nan,0\n"
      "0.02,0.01,0.02,0.03,0.1,0.2,9.81,21,5,-41,0.7071067811865476,0,0,0.7071067811865476,1\n";
  for (char selector = 2; selector <= 5; ++selector) csv_seed(selector, imu);
  csv_seed(6,
           "t_s,qw,qx,qy,qz,roll_rad,pitch_rad,yaw_rad,roll_sd_rad,pitch_sd_rad,yaw_sd_rad\n"
           "0,1,0,0,0,0,0,0,0.1,0.1,0.2\n0.01,0.9999,0.01,0,0,0.02,0,0,0.1,0.1,0.2\n");
  csv_seed(7,
           "name,x,y,z,file_name_root\nH1,0,0,0,AMAR173.1.\nH2,1,0,0,AMAR173.2.\nH3,0,1,0,AMAR173.3.\n"
           "H4,0.3,0.3,0.5,AMAR173.4.\nH5,0,0,-0.671,AMAR173.5.\n");
  const fs::path xav =
      fs::path(LOCALIZER_SOURCE_DIR) / ".." / "shared" / "data" / "xav-large-array" / "hydrophones_config_07-HI.csv";
  if (fs::exists(xav)) csv_seed(7, ReadFile(xav));

  io::Recording recording;
  recording.sample_rate_hz = 8000.0;
  recording.channel_count = 4;
  recording.frames = 40;
  recording.samples.resize(160);
  for (size_t i = 0; i < recording.samples.size(); ++i) recording.samples[i] = 0.01f * static_cast<float>(i % 50);
  if (io::WriteWavFloat(scratch / "float.wav", recording).ok()) Seed("fuzz_wav", ReadFile(scratch / "float.wav"));
  // A 16-bit PCM file, mono, 8 frames: the header by hand.
  std::string pcm = "RIFF";
  const auto u32 = [&pcm](uint32_t v) {
    for (int b = 0; b < 4; ++b) pcm.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
  };
  const auto u16 = [&pcm](uint16_t v) {
    pcm.push_back(static_cast<char>(v & 0xff));
    pcm.push_back(static_cast<char>(v >> 8));
  };
  u32(36 + 16);
  pcm += "WAVEfmt ";
  u32(16);
  u16(1);  // PCM
  u16(1);  // mono
  u32(8000);
  u32(16000);
  u16(2);
  u16(16);
  pcm += "data";
  u32(16);
  for (int i = 0; i < 8; ++i) u16(static_cast<uint16_t>(i * 4000 - 16000));
  Seed("fuzz_wav", pcm);
}

void RegressionSeeds() {
  const fs::path root = fs::path(LOCALIZER_SOURCE_DIR) / "tests" / "fuzz" / "regressions";
  if (!fs::exists(root)) return;
  for (const auto& target : fs::directory_iterator(root)) {
    if (!target.is_directory()) continue;
    for (const auto& input : fs::directory_iterator(target.path())) {
      if (input.is_regular_file()) Seed(target.path().filename().string(), ReadFile(input.path()));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_seeds OUT_DIR   (writes OUT_DIR/<fuzz target>/seed-*)\n";
    return 2;
  }
  g_out = argv[1];
  ProtoSeeds();
  FileSeeds(g_out / ".scratch");
  RegressionSeeds();
  fs::remove_all(g_out / ".scratch");
  for (const auto& target : fs::directory_iterator(g_out)) {
    const auto n = std::distance(fs::directory_iterator(target.path()), fs::directory_iterator{});
    std::cout << target.path().filename().string() << ": " << n << " seeds\n";
  }
  return 0;
}
