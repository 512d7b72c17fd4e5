// localizer-cli comes as two executables built from the same sources (clients/CMakeLists.txt):
//
//   localizer-cli       the offline commands (track on a file, --raw or --alsa; simulate, doa,
//                       score, plot, experiment, attitude...) on the CPU. It links the engine,
//                       FFTW and the file formats, and neither gRPC/protobuf/abseil nor the CUDA
//                       runtime and cuFFT: loading and relocating those was about two thirds of
//                       an offline command's start-up CPU (BENCHMARKS.md, "Start-up of
//                       localizer-cli").
//   localizer-cli-full  every command, as localizer-cli was before the split: the gRPC client
//                       (--server, locate, list, close) and the GPU backend registered.
//
// localizer-cli hands a command to localizer-cli-full by exec (the same arguments, the same
// process id, standard streams and exit code), so a user sees one program:
//   - before running it, when the command line asks for a server or a GPU (NeedsFullCli);
//   - while running it, when a session asks the backend factory for the GPU although the
//     command line did not (the array file's "session": {"backend": "auto"}): the offline
//     build registers a provider (FullCliGpuProvider) whose first consultation execs. Such a
//     consultation happens when the config is checked (BuildSessionConfig), before anything
//     is written to stdout or to an output file.
// Why two executables and not one with a dlopen'd module for gRPC and CUDA: the engine, FFTW
// (its planner and wisdom), the backend provider slot and the session registries are static
// state. A module linked with its own copy of the engine static libraries would hold a second
// copy of each (a provider installed in one copy is not seen by the other); a module resolving
// the engine from the executable needs every engine symbol it uses exported and already
// linked into the executable, which a static library does not guarantee. Two processes, one
// after the other, each hold exactly one copy. The cost is a second start-up (about the
// offline one, a few ms) for the commands that go through a server or a GPU.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engine/pipeline/backend.h"

namespace localizer::cli {

// Remembers the process's arguments for ExecFullCli. Call first thing in main.
void SetProcessArguments(int argc, char** argv);

// Why `command args` must run in localizer-cli-full, or "" when localizer-cli runs it:
//   - locate, list, close: they only talk to a server;
//   - any argument "--server" or "--server=..." (track, simulate, experiment tws);
//   - "--backend V" or "--backend=V" with V other than "cpu".
// A false positive costs only the second start-up (localizer-cli-full runs every command).
std::string NeedsFullCli(const std::string& command, const std::vector<std::string>& args);

// Where localizer-cli-full is: beside this executable (/proc/self/exe's directory).
std::string FullCliPath();

// Replaces this process with localizer-cli-full and the arguments SetProcessArguments saw,
// after flushing stdout and stderr. Returns only when that fails: prints
// "localizer-cli: <why> needs localizer-cli-full, which could not be started: PATH: <errno
// text>" on stderr and returns 1 (kExitRuntimeError).
int ExecFullCli(const std::string& why);

// The command-table entry of locate, list and close in localizer-cli: ExecFullCli.
int RunInFullCli(const std::vector<std::string>& args);

// The GPU provider of localizer-cli: consulted (backend gpu or auto), it execs
// localizer-cli-full, which redoes the command with the CUDA backend registered (or reports,
// as before the split, that there is no device). When the exec fails, it reports itself
// unavailable with ExecFullCli's reason, so that gpu fails and auto runs on the CPU.
std::shared_ptr<engine::BackendProvider> MakeFullCliGpuProvider();

}  // namespace localizer::cli
