// Helpers shared by the clients tests: a scratch directory removed on scope exit, and the
// location of the shared real recordings.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace localizer::io::testing {

// A fresh directory under the system temp folder, deleted with everything in it.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device entropy;
    path_ = std::filesystem::temp_directory_path() /
            ("localizer_" + std::string(info ? info->name() : "test") + "_" + std::to_string(entropy()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  std::string File(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// The first line of a text file ("" if it cannot be read).
inline std::string FirstLine(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

inline std::string XavDir() { return std::string(LOCALIZER_DATA_DIR) + "/xav-large-array"; }
inline std::string XavConfigCsv() { return XavDir() + "/hydrophones_config_07-HI.csv"; }

}  // namespace localizer::io::testing
