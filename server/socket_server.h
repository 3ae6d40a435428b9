#pragma once
// The socket protocol's transport (protocol/PROTOCOL.md) and the Prometheus endpoint, on
// Asio: connections read request lines, hand them to the Engine and write replies and
// subscribed frames back. A slow client only fills its own bounded queue.
#include <asio.hpp>

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "server/engine.h"

namespace nephele {

class Connection;

class SocketServer {
 public:
  SocketServer(asio::io_context& io, Engine& engine);
  ~SocketServer();
  // Binds and starts accepting; returns an error naming the address on failure.
  std::string listen(const ListenConfig& where);
  int port() const { return port_; }
  // Stops accepting; every connection finishes writing what it was sent, then closes (call on
  // the io thread or before it runs).
  void close();

 private:
  void accept();
  void sweep();  // closes connections past their request or idle timeout

  asio::io_context& io_;
  Engine& engine_;
  asio::ip::tcp::acceptor acceptor_;
  asio::steady_timer sweep_timer_;
  asio::steady_timer accept_timer_;             // retries accepting after an error
  std::shared_ptr<std::atomic<int>> refusing_;  // over-limit connections being answered
  int port_ = 0;
  std::int64_t next_id_ = 1;
  // Set by close(): a sweep or accept whose handler was already queued when close() cancelled
  // it must not start another (the io thread would never run out of work).
  bool closed_ = false;
  // Owned here while open (a connection that has paused reading has no pending operation
  // to keep it alive); closed ones are dropped by the sweep.
  std::map<std::int64_t, std::shared_ptr<Connection>> connections_;
};

struct MetricsExchange;

// GET /metrics in the Prometheus text format; anything else is 404. A scrape must be done
// within the socket request timeout; at most 16 are served at once.
class MetricsServer {
 public:
  MetricsServer(asio::io_context& io, Engine& engine);
  std::string listen(const ListenConfig& where);
  int port() const { return port_; }
  void close();

 private:
  void accept();

  asio::io_context& io_;
  Engine& engine_;
  asio::ip::tcp::acceptor acceptor_;
  int port_ = 0;
  std::vector<std::weak_ptr<MetricsExchange>> open_;
  asio::steady_timer accept_timer_;  // retries accepting after an error
  bool closed_ = false;              // as SocketServer::closed_
};

// Opens `acceptor` on `where`; returns the error, naming the address, on failure.
std::string openAcceptor(asio::ip::tcp::acceptor& acceptor, const ListenConfig& where,
                         const char* what);

}  // namespace nephele
