// Runs a shell command line for the tests that drive the built binaries and outside tools
// (openssl, promtool). posix_spawn + waitpid instead of std::system, which is not
// thread-safe (it changes the process's signal dispositions while the command runs) and
// these tests run servers and gRPC threads in the same process.
#pragma once

#include <spawn.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <string>

namespace localizer::testing {

// `/bin/sh -c command` with this process's environment; returns the wait status as
// std::system does (WIFEXITED, WEXITSTATUS apply), or -1 when the shell could not be started
// or waited for.
inline int RunShell(const std::string& command) {
  std::string name = "sh", flag = "-c", line = command;  // posix_spawn takes char* const[]
  char* const argv[] = {name.data(), flag.data(), line.data(), nullptr};
  pid_t pid = 0;
  if (posix_spawn(&pid, "/bin/sh", nullptr, nullptr, argv, environ) != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return status;
}

}  // namespace localizer::testing
