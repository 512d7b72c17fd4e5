// A throwaway PKI for the HTTPS tests: deploy/tls/make_test_certs.sh (the openssl CLI) run
// into a temporary directory, removed at the end. Needs LOCALIZER_SOURCE_DIR defined.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/server/run_shell.h"

namespace localizer::testing {

inline std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A temporary directory with test PKIs (deploy/tls/make_test_certs.sh); removed at the end.
class Pki {
 public:
  Pki() {
    char pattern[] = "/tmp/localizer-https-XXXXXX";
    dir_ = mkdtemp(pattern);
  }
  ~Pki() {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  static bool HaveOpenssl() { return localizer::testing::RunShell("openssl version >/dev/null 2>&1") == 0; }
  // Makes a CA with server and client certificates in dir()/name; false when it failed.
  bool Make(const std::string& name) {
    const std::string command = "bash '" LOCALIZER_SOURCE_DIR "/deploy/tls/make_test_certs.sh' '" +
                                (dir_ / name).string() + "' >/dev/null 2>&1";
    return localizer::testing::RunShell(command) == 0;
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Cert(const std::string& file, const std::string& pki = "pki") const { return Path(pki + "/" + file); }
  std::string Pem(const std::string& file, const std::string& pki = "pki") const { return ReadText(Cert(file, pki)); }

 private:
  std::filesystem::path dir_;
};

}  // namespace localizer::testing

// For a fixture with a Pki member pki_: skips without the openssl CLI, else makes dir()/pki.
#define SKIP_WITHOUT_PKI()                                                             \
  if (!::localizer::testing::Pki::HaveOpenssl())                                       \
    GTEST_SKIP() << "the openssl CLI is not installed (Debian: openssl): no test PKI"; \
  ASSERT_TRUE(pki_.Make("pki")) << "deploy/tls/make_test_certs.sh failed"
