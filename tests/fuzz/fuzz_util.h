// Shared by the libFuzzer targets of tests/fuzz and their seed writer (docs/FUZZING.md).
//
// FUZZ_CHECK turns a broken invariant into a crash, so libFuzzer keeps the input: the
// targets look for logic errors (a decoder that accepts what it documents it refuses, a
// decode that does not round-trip), not only for memory errors and undefined behaviour.
#pragma once

#include <google/protobuf/stubs/logging.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "localizer/v1/localizer.pb.h"
#include "tests/wire/minimal_config.h"
#include "wire/config_wire.h"

#define FUZZ_CHECK(cond, what)                                                                  \
  do {                                                                                          \
    if (!(cond)) {                                                                              \
      std::fprintf(stderr, "FUZZ_CHECK failed at %s:%d: %s\n  %s\n", __FILE__, __LINE__, #cond, \
                   std::string(what).c_str());                                                  \
      std::abort();                                                                             \
    }                                                                                           \
  } while (0)

namespace localizer::fuzz {

// protobuf logs every string field that is not UTF-8 as it parses; millions of such lines
// would bury the fuzzer's own output. Dropped before main.
inline const bool kProtobufQuiet = [] {
  google::protobuf::SetLogHandler(nullptr);
  return true;
}();

// The server's defaults (server_options.cc: --max-block-samples, --max-channels,
// --max-particles), except the block limit: 4096 samples per channel keeps one execution
// small; the decoders treat the limit as a number like any other.
inline wire::ConfigPolicy FuzzPolicy() {
  wire::ConfigPolicy policy;
  policy.default_backend = "auto";
  policy.max_block_samples = 4096;
  return policy;
}

// A valid audio config as the tests send it: the wire tests' tetrahedron in water, 48 kHz.
inline v1::SessionConfig TetraConfig() {
  v1::SessionConfig c = wire::testing::MinimalConfig();
  c.set_frame_samples(1024);
  c.set_label("fuzz");
  return c;
}

// Path readers (CSV, WAV) read an in-memory file: a memfd named by /proc/self/fd/N, so no
// execution touches the disk and nothing is left behind.
class MemFile {
 public:
  MemFile() {
    fd_ = memfd_create("localizer-fuzz", 0);
    if (fd_ < 0) {
      std::perror("memfd_create");
      std::abort();
    }
    path_ = "/proc/self/fd/" + std::to_string(fd_);
  }
  MemFile(const MemFile&) = delete;
  MemFile& operator=(const MemFile&) = delete;
  ~MemFile() { close(fd_); }

  // Replaces the file's contents; returns its path.
  const std::string& Write(const uint8_t* data, size_t size) {
    if (ftruncate(fd_, 0) != 0 || (size > 0 && pwrite(fd_, data, size, 0) != static_cast<ssize_t>(size))) {
      std::perror("memfd write");
      std::abort();
    }
    return path_;
  }

 private:
  int fd_ = -1;
  std::string path_;
};

}  // namespace localizer::fuzz
