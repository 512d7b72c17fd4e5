// The floor under the service's overhead: a Track server with no engine, no worker pool
// and no session state. It answers `open` with `opened` and each block with two small
// estimates written from the gRPC thread, so loadtest.py can drive it exactly as it
// drives localizer-server. Process CPU per block here is what gRPC and the kernel cost;
// tests/bench/service_capacity.py --server-binary points at it.
//   build/tests/bench/bare_stream_server --listen 127.0.0.1:0 --ready-file F
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <deque>
#include <fstream>
#include <mutex>
#include <string>

#include "localizer/v1/localizer.grpc.pb.h"

namespace {

using localizer::v1::TrackRequest;
using localizer::v1::TrackResponse;

class BareTrack final : public grpc::ServerBidiReactor<TrackRequest, TrackResponse> {
 public:
  BareTrack() { StartRead(&request_); }

  void OnReadDone(bool ok) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!ok) {
      done_reading_ = true;
      MaybeFinish();
      return;
    }
    if (request_.has_open()) {
      TrackResponse r;
      r.mutable_opened()->set_session_id("bare");
      r.mutable_opened()->set_backend("none");
      Queue(std::move(r));
    } else if (request_.has_block()) {
      for (uint64_t frame = 0; frame < 2; ++frame) {
        TrackResponse r;
        r.mutable_estimate()->set_sequence(request_.block().sequence());
        r.mutable_estimate()->set_frame_index(frames_++);
        r.mutable_estimate()->mutable_covariance()->Resize(36, 0.0);
        Queue(std::move(r));
      }
    }
    StartRead(&request_);
  }

  void OnWriteDone(bool ok) override {
    std::lock_guard<std::mutex> lock(mutex_);
    writing_ = false;
    outbox_.pop_front();
    if (!ok) {
      outbox_.clear();
      done_reading_ = true;
    }
    Pump();
    MaybeFinish();
  }

  void OnDone() override { delete this; }

 private:
  void Queue(TrackResponse r) {
    outbox_.push_back(std::move(r));
    Pump();
  }
  void Pump() {
    if (writing_ || outbox_.empty()) return;
    writing_ = true;
    StartWrite(&outbox_.front());
  }
  void MaybeFinish() {
    if (done_reading_ && !writing_ && outbox_.empty() && !finished_) {
      finished_ = true;
      Finish(grpc::Status::OK);
    }
  }

  std::mutex mutex_;
  TrackRequest request_;
  std::deque<TrackResponse> outbox_;  // front is in flight while writing_
  uint64_t frames_ = 0;
  bool writing_ = false, done_reading_ = false, finished_ = false;
};

class BareService final : public localizer::v1::Localizer::CallbackService {
  grpc::ServerBidiReactor<TrackRequest, TrackResponse>* Track(grpc::CallbackServerContext*) override {
    return new BareTrack();
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::string listen = "127.0.0.1:0", ready_file;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--listen")
      listen = argv[i + 1];
    else if (flag == "--ready-file")
      ready_file = argv[i + 1];
  }
  sigset_t stop;
  sigemptyset(&stop);
  sigaddset(&stop, SIGTERM);
  sigaddset(&stop, SIGINT);
  pthread_sigmask(SIG_BLOCK, &stop, nullptr);
  BareService service;
  int port = 0;
  grpc::ServerBuilder builder;
  builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), &port);
  builder.SetMaxReceiveMessageSize(64 << 20);
  builder.RegisterService(&service);
  auto server = builder.BuildAndStart();
  if (!server) {
    std::fprintf(stderr, "bare_stream_server: cannot listen on %s\n", listen.c_str());
    return 1;
  }
  if (!ready_file.empty()) {
    std::ofstream(ready_file + ".tmp") << "{\"grpc_port\": " << port << ", \"metrics_port\": 0, \"pid\": " << getpid()
                                       << "}\n";
    std::rename((ready_file + ".tmp").c_str(), ready_file.c_str());
  }
  int signal_number = 0;
  sigwait(&stop, &signal_number);
  server->Shutdown();
  return 0;
}
