// An in-process localizer-server on a loopback port (cpu backend, two workers, no metrics
// port) and a connected channel to it: the fixture of the client-against-server tests.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "clients/grpc/connection.h"
#include "server/service/server.h"

namespace localizer::client {

class LoopbackServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    server::ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.metrics_listen = "";
    options.workers = 2;
    options.backend = "cpu";
    options.log_level = "warn";
    auto started = server::Server::Start(options);
    ASSERT_TRUE(started.ok()) << started.status().ToString();
    server_ = std::move(started).value();
    target_ = "127.0.0.1:" + std::to_string(server_->grpc_port());
    channel_ = Connect(target_);
    const Status connected = WaitConnected(channel_, 10.0);
    ASSERT_TRUE(connected.ok()) << connected.ToString();
  }
  void TearDown() override {
    if (server_) server_->Shutdown();
  }

  std::unique_ptr<server::Server> server_;
  std::string target_;
  std::shared_ptr<grpc::Channel> channel_;
};

}  // namespace localizer::client
