// The byte pump of the TLS front (tls_front.h), internal to server/metrics: waits on a
// connection's sockets, and the relay between a TLS connection and the plain backend socket.
#pragma once

#include <openssl/ssl.h>
#include <sys/socket.h>

#include <chrono>
#include <string>

namespace localizer::server::metrics {

// "ip:port" or "[ip6]:port".
std::string PeerString(const sockaddr_storage& peer);

// Milliseconds from now to `deadline`, in [0, 2^30].
int MillisecondsUntil(std::chrono::steady_clock::time_point deadline);

// What a poll on a connection's sockets says.
enum class Wait { kReady, kStop, kTimeout };

// Waits until `fd` has `events` (or an error), the stop eventfd is written, or `deadline`.
Wait WaitFor(int fd, short events, int stop_fd, std::chrono::steady_clock::time_point deadline);

// Relays between the TLS connection and the backend socket until the backend has closed and
// everything it sent is delivered, either side fails, the stop eventfd is written, nothing
// moves for `idle`, or `deadline` passes. Reads from a side stop while its buffer of
// `buffer_bytes` is full (backpressure).
void Relay(SSL* ssl, int client_fd, int backend_fd, int stop_fd, int buffer_bytes,
           std::chrono::steady_clock::duration idle, std::chrono::steady_clock::time_point deadline);

}  // namespace localizer::server::metrics
