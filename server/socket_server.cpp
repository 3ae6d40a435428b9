#include "server/socket_server.h"

#include <spdlog/spdlog.h>

#include <array>
#include <chrono>
#include <deque>
#include <optional>
#include <utility>

#include "server/log_limiter.h"
#include "server/tcp_peer.h"

namespace nephele {

using asio::ip::tcp;

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kMaxInFlight = 16;  // requests of one connection waiting for the world thread
constexpr int kMaxBadTokens = 3;  // wrong tokens before the connection is closed
constexpr int kMaxRefusing = 64;  // over-limit connections being answered at once
constexpr auto kRefusalWait = std::chrono::seconds(2);     // for an over-limit client's request
constexpr auto kShutdownDrain = std::chrono::seconds(10);  // to finish writing at shutdown
constexpr auto kSweepPeriod = std::chrono::milliseconds(250);
constexpr auto kAcceptRetry = std::chrono::milliseconds(100);  // after a failed accept
constexpr std::size_t kMaxMetricsConnections = 16;

// Compares a presented token with the configured one in time that depends only on the
// configured token's length, so that timing tells a guesser nothing about a prefix.
bool tokenMatches(std::string_view presented, std::string_view expected) {
  unsigned char diff = presented.size() == expected.size() ? 0 : 1;
  for (std::size_t i = 0; i < expected.size(); ++i)
    diff |= static_cast<unsigned char>(expected[i] ^ (i < presented.size() ? presented[i] : 0));
  return diff == 0;
}

std::string overLimitRefusal(const nlohmann::json& id, int max_clients) {
  return errorReply(
      id, {ErrorCode::kLimit, "too many clients (allowed: " + std::to_string(max_clients) +
                                  "); the connection is closed"});
}

}  // namespace

// One client of the socket protocol. Every member is used on the io thread only, except
// closed_, which frame sinks on other threads read.
//
// Memory per connection is bounded (docs/RELIABILITY.md): at most kMaxInFlight requests wait
// for the world thread, reading stops while that many are out or the unread output exceeds
// max_pending_bytes, and an image reply that would take the output beyond that limit is
// replaced by a busy error (rendering changes nothing, so refusing it late is still clean).
class Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(tcp::socket socket, Engine& engine, std::int64_t id)
      : socket_(std::move(socket)),
        engine_(engine),
        id_(id),
        authorised_(engine.config().token.empty()),
        last_activity_(Clock::now()) {
    std::error_code ec;
    const tcp::endpoint peer = socket_.remote_endpoint(ec);
    peer_ = ec ? "?" : peer.address().to_string() + ":" + std::to_string(peer.port());
    socket_.set_option(tcp::no_delay(true), ec);
  }

  void start() {
    ++engine_.telemetry().socket_clients;
    if (listenerLog().admit("client_connected"))
      spdlog::info("event=client_connected id={} peer={}", id_, peer_);
    resume();
  }

  bool closed() const { return closed_; }

  // Whether the peer has closed the connection while this side still reads it: no request
  // can come any more, and replies still owed are dropped at its end of file anyway.
  bool closedByPeer() { return !closed_ && !finishing_ && peerHasClosed(socket_.native_handle()); }

  void close(const char* why) {
    if (closed_.exchange(true)) return;
    std::error_code ec;
    socket_.shutdown(tcp::socket::shutdown_both, ec);
    socket_.close(ec);
    if (drain_timer_) drain_timer_->cancel();
    --engine_.telemetry().socket_clients;
    engine_.clientGone(id_);
    if (listenerLog().admit(std::string("client_closed/") + why))
      spdlog::info("event=client_closed id={} peer={} reason={}", id_, peer_, why);
  }

  // Stops reading and closes once everything queued is written, or after `limit`.
  void finish(const char* why, Clock::duration limit) {
    if (closed_ || finishing_) return;
    finishing_ = why;
    std::error_code ec;
    socket_.shutdown(tcp::socket::shutdown_receive, ec);
    if (std::string_view(why) == "shutdown") answerUnread();
    if (out_.empty()) {
      close(why);
      return;
    }
    drain_timer_ = std::make_unique<asio::steady_timer>(socket_.get_executor(), limit);
    drain_timer_->async_wait([self = shared_from_this()](std::error_code ec) {
      if (!ec) self->close("drain_timeout");
    });
  }

  // Queues a reply or frame for writing; a request's `trace` is noted once it is written.
  void send(SharedReply reply, std::shared_ptr<RequestTrace> trace = nullptr) {
    if (closed_) return;
    pending_bytes_ += reply->size();
    out_.push_back({std::move(reply), std::move(trace)});
    if (!writing_) write();
  }

  // A request's reply, from the world thread or the encoder.
  void reply(const nlohmann::json& id, SharedReply r, std::shared_ptr<RequestTrace> trace) {
    --in_flight_;
    if (closed_) return;
    trace->replied = Clock::now();
    if (r->body && pending_bytes_ > 0 &&
        pending_bytes_ + r->size() > engine_.config().max_pending_bytes) {
      engine_.telemetry().noteError(ErrorCode::kBusy);
      r = makeReply(errorReply(
          id, {ErrorCode::kBusy, "this connection has " + std::to_string(pending_bytes_ >> 20) +
                                     " MiB of output unread (allowed: " +
                                     std::to_string(engine_.config().max_pending_bytes >> 20) +
                                     " MiB); the image was not sent; read first, then ask again"}));
    }
    send(std::move(r), std::move(trace));
    resume();
  }

  // A subscribed frame: dropped when the client is already too far behind.
  void offerFrame(SharedReply frame) {
    if (closed_) return;
    if (pending_bytes_ + frame->size() > engine_.config().max_pending_bytes) {
      ++engine_.telemetry().frames_dropped;
      return;
    }
    send(std::move(frame));
  }

  // Why the connection should close now (a timeout), or nullptr.
  const char* overdue(Clock::time_point now) const {
    if (closed_ || finishing_) return nullptr;
    const Timeouts& t = engine_.config().socket_timeouts;
    if (line_started_ && now - *line_started_ > secondsToDuration(t.request_s))
      return "request_timeout";
    if (t.idle_s > 0.0 && now - last_activity_ > secondsToDuration(t.idle_s)) {
      if (!out_.empty()) return "write_timeout";  // nothing read of its output, subscribed or not
      if (in_flight_ == 0 && engine_.subscriptionsOf(id_) == 0) return "idle_timeout";
    }
    return nullptr;
  }

  // How long the connection has had nothing to do, if it has nothing to do at all: no
  // request begun or waiting, no output, no subscription.
  std::optional<Clock::duration> idleFor(Clock::time_point now) const {
    if (closed_ || finishing_ || line_started_ || in_flight_ > 0 || !out_.empty() ||
        engine_.subscriptionsOf(id_) > 0)
      return std::nullopt;
    return now - last_activity_;
  }

 private:
  bool paused() const {
    return in_flight_ >= kMaxInFlight || pending_bytes_ > engine_.config().max_pending_bytes;
  }

  // Handles what has been read, then reads more, unless paused, reading or closing.
  void resume() {
    if (closed_ || finishing_ || processing_) return;
    processing_ = true;
    processInput();
    processing_ = false;
    if (!closed_ && !finishing_ && !reading_ && !paused()) read();
  }

  void read() {
    reading_ = true;
    socket_.async_read_some(asio::buffer(chunk_),
                            [self = shared_from_this()](std::error_code ec, std::size_t n) {
                              self->reading_ = false;
                              self->onRead(ec, n);
                            });
  }

  void onRead(std::error_code ec, std::size_t n) {
    if (closed_ || finishing_) return;
    if (ec) {
      close(ec == asio::error::eof ? "eof" : "read_error");
      return;
    }
    last_activity_ = Clock::now();
    if (!line_started_) line_started_ = last_activity_;
    in_.append(chunk_.data(), n);
    resume();
  }

  // Splits in_ into request lines and handles them while the connection is not paused.
  void processInput() {
    while (!closed_ && !finishing_ && !paused()) {
      const std::size_t newline = in_.find('\n');
      if (newline == std::string::npos) break;
      if (!discarding_) {
        line_.assign(in_, 0, newline);
        handleLine();
      }
      discarding_ = false;
      in_.erase(0, newline + 1);
    }
    if (!discarding_ && in_.find('\n') == std::string::npos &&
        in_.size() >= ProtocolLimits::kMaxRequestBytes) {
      // Answer once, then skip the rest of the line: the connection stays usable.
      sendError(nullptr,
                {ErrorCode::kTooLarge, "request line is longer than " +
                                           std::to_string(ProtocolLimits::kMaxRequestBytes) +
                                           " bytes (allowed: less); it was skipped"});
      discarding_ = true;
    }
    // The rest of an over-long line is dropped as it comes; the loop above skips its end.
    if (discarding_ && in_.find('\n') == std::string::npos) in_.clear();
    // A request begun and not finished is held to the request timeout from its first byte
    // (or from when the previous one was taken), but only while the daemon waits for it:
    // not while reading is paused on the daemon's side.
    if ((in_.empty() && !discarding_) || paused())
      line_started_.reset();
    else if (!line_started_)
      line_started_ = Clock::now();
  }

  // At shutdown: whole requests read but not yet handed on (reading was paused) are answered
  // too, so that every request sent gets its answer.
  void answerUnread() {
    for (std::size_t newline; (newline = in_.find('\n')) != std::string::npos;
         in_.erase(0, newline + 1)) {
      if (std::exchange(discarding_, false)) continue;
      line_.assign(in_, 0, newline);
      if (line_.find_first_not_of(" \t\r") == std::string::npos) continue;
      auto parsed = parseRequest(line_);
      const nlohmann::json id = std::holds_alternative<BadRequest>(parsed)
                                    ? std::get<BadRequest>(parsed).id
                                    : std::get<Request>(parsed).id;
      sendError(id, {ErrorCode::kFailed, "the daemon is shutting down"});
    }
  }

  void handleLine() {
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    if (line_.find_first_not_of(" \t") == std::string::npos) return;
    auto parsed = parseRequest(line_);
    if (auto* bad = std::get_if<BadRequest>(&parsed)) {
      sendError(bad->id, bad->error);
      return;
    }
    Request& request = std::get<Request>(parsed);
    const std::string& token = engine_.config().token;
    if (auto* hello = std::get_if<command::Hello>(&request.command); hello && !token.empty()) {
      authorised_ = hello->token && tokenMatches(*hello->token, token);
      if (!authorised_) {
        ++bad_tokens_;
        if (listenerLog().admit("bad_token"))
          spdlog::warn("event=bad_token id={} peer={} count={}", id_, peer_, bad_tokens_);
        const bool last = bad_tokens_ >= kMaxBadTokens;
        sendError(request.id, {ErrorCode::kUnauthorized,
                               last ? "token: wrong " + std::to_string(kMaxBadTokens) +
                                          " times; the connection is closed"
                                    : "token: missing or wrong"});
        if (last) finish("bad_tokens", kShutdownDrain);
        return;
      }
    }
    if (!authorised_) {
      sendError(request.id, {ErrorCode::kUnauthorized,
                             "this daemon needs a token: send {\"cmd\":\"hello\",\"token\":...} "
                             "first"});
      return;
    }
    const nlohmann::json id = request.id;
    // The control plane: with nothing of this client's in flight, hello and stats are answered
    // here, from what the world thread has published, even while it renders.
    if (in_flight_ == 0)
      if (std::optional<nlohmann::json> answer = engine_.answerAtOnce(request.command)) {
        send(makeReply(okReply(id, *answer)));
        return;
      }
    std::weak_ptr<Connection> weak = weak_from_this();
    asio::io_context& io = static_cast<asio::io_context&>(socket_.get_executor().context());
    auto trace = std::make_shared<RequestTrace>();
    trace->command = commandName(request.command);
    trace->client = id_;
    auto reply = [weak, &io, id, trace](SharedReply r) {
      asio::post(io, [weak, id, r = std::move(r), trace] {
        if (auto c = weak.lock()) c->reply(id, r, trace);
      });
    };
    auto frames = [weak, &io](SharedReply r) {
      auto c = weak.lock();
      if (!c || c->closed_) return false;
      asio::post(io, [c, r = std::move(r)] { c->offerFrame(r); });
      return true;
    };
    ++in_flight_;
    if (!engine_.submit(std::move(request), id_, frames, reply, trace)) {
      --in_flight_;
      sendError(
          id, engine_.stopping()
                  ? ProtocolError{ErrorCode::kFailed, "the daemon is shutting down"}
                  : ProtocolError{ErrorCode::kBusy, "the request queue is full (" +
                                                        std::to_string(engine_.config().max_queue) +
                                                        " waiting); try again"});
    }
  }

  void sendError(const nlohmann::json& id, const ProtocolError& error) {
    engine_.telemetry().noteError(error.code);
    send(makeReply(errorReply(id, error)));
  }

  void write() {
    writing_ = true;
    const SharedReply& r = out_.front().reply;
    std::vector<asio::const_buffer> buffers{asio::buffer(r->header)};
    if (r->body) buffers.push_back(asio::buffer(*r->body));
    for (const SharedReply& then : r->then) {
      buffers.push_back(asio::buffer(then->header));
      if (then->body) buffers.push_back(asio::buffer(*then->body));
    }
    asio::async_write(socket_, buffers,
                      [self = shared_from_this()](std::error_code ec, std::size_t) {
                        const Outgoing& done = self->out_.front();
                        self->pending_bytes_ -= done.reply->size();
                        if (done.trace && !ec) {
                          done.trace->written = Clock::now();
                          self->engine_.telemetry().noteTrace(*done.trace);
                        }
                        self->out_.pop_front();
                        self->last_activity_ = Clock::now();
                        if (ec) {
                          self->close("write_error");
                          return;
                        }
                        if (!self->out_.empty()) {
                          self->write();
                          return;
                        }
                        self->writing_ = false;
                        if (self->finishing_)
                          self->close(self->finishing_);
                        else
                          self->resume();
                      });
  }

  tcp::socket socket_;
  Engine& engine_;
  std::int64_t id_;
  std::string peer_;
  bool authorised_;
  int bad_tokens_ = 0;
  std::array<char, 16384> chunk_{};
  std::string in_;    // bytes read and not yet handled
  std::string line_;  // the request line being handled
  bool discarding_ = false;
  bool reading_ = false;
  bool processing_ = false;
  int in_flight_ = 0;
  Clock::time_point last_activity_;
  std::optional<Clock::time_point> line_started_;
  struct Outgoing {
    SharedReply reply;
    std::shared_ptr<RequestTrace> trace;  // a request's, noted when written
  };
  std::deque<Outgoing> out_;
  std::size_t pending_bytes_ = 0;
  bool writing_ = false;
  const char* finishing_ = nullptr;  // why the connection is closing once written out
  std::unique_ptr<asio::steady_timer> drain_timer_;
  std::atomic<bool> closed_{false};
};

// A connection over the client limit: it is told so in answer to its first request, with
// that request's id, so that the client knows which request was refused.
void refuseOverLimit(tcp::socket socket, int max_clients, std::shared_ptr<std::atomic<int>> count) {
  struct Refusal {
    Refusal(tcp::socket s, std::shared_ptr<std::atomic<int>> n)
        : socket(std::move(s)), timer(socket.get_executor(), kRefusalWait), count(std::move(n)) {
      ++*count;
    }
    ~Refusal() { --*count; }
    tcp::socket socket;
    asio::streambuf in{ProtocolLimits::kMaxRequestBytes};
    asio::steady_timer timer;
    std::string reply;
    bool answered = false;
    std::shared_ptr<std::atomic<int>> count;
  };
  auto r = std::make_shared<Refusal>(std::move(socket), std::move(count));
  auto answer = [r](const nlohmann::json& id, int max) {
    if (r->answered) return;
    r->answered = true;
    r->timer.cancel();
    r->reply = overLimitRefusal(id, max);
    asio::async_write(r->socket, asio::buffer(r->reply), [r](std::error_code, std::size_t) {
      std::error_code ignored;
      r->socket.shutdown(tcp::socket::shutdown_both, ignored);
      r->socket.close(ignored);
    });
  };
  r->timer.async_wait([r, answer, max_clients](std::error_code ec) {
    if (!ec) answer(nullptr, max_clients);  // no request in time: refuse without an id
  });
  asio::async_read_until(r->socket, r->in, '\n',
                         [r, answer, max_clients](std::error_code ec, std::size_t n) {
                           nlohmann::json id = nullptr;
                           if (!ec) {
                             std::string line(asio::buffers_begin(r->in.data()),
                                              asio::buffers_begin(r->in.data()) + n);
                             auto parsed = parseRequest(line);
                             if (auto* bad = std::get_if<BadRequest>(&parsed))
                               id = bad->id;
                             else
                               id = std::get<Request>(parsed).id;
                           }
                           answer(id, max_clients);
                         });
}

std::string openAcceptor(tcp::acceptor& acceptor, const ListenConfig& where, const char* what) {
  std::error_code ec;
  const asio::ip::address address = asio::ip::make_address(where.bind, ec);
  if (ec) return std::string(what) + ".bind: \"" + where.bind + "\" is not an IP address";
  const tcp::endpoint endpoint(address, asio::ip::port_type(where.port));
  acceptor.open(endpoint.protocol(), ec);
  if (!ec) acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec)
    return std::string("cannot listen for ") + what + " on " + where.bind + ":" +
           std::to_string(where.port) + ": " + ec.message();
  return "";
}

SocketServer::SocketServer(asio::io_context& io, Engine& engine)
    : io_(io),
      engine_(engine),
      acceptor_(io),
      sweep_timer_(io),
      accept_timer_(io),
      refusing_(std::make_shared<std::atomic<int>>(0)) {}

// Last of the listeners to go (serve destroys them in reverse order): what the log held back
// until now, the lines of connections drained at shutdown included, is summarised.
SocketServer::~SocketServer() {
  listenerLog().flushAll();
}

std::string SocketServer::listen(const ListenConfig& where) {
  if (std::string e = openAcceptor(acceptor_, where, "socket"); !e.empty()) return e;
  port_ = acceptor_.local_endpoint().port();
  accept();
  sweep();
  return "";
}

void SocketServer::sweep() {
  listenerLog().flush();
  const auto now = Clock::now();
  std::erase_if(connections_, [&](const auto& entry) {
    Connection& c = *entry.second;
    if (const char* why = c.overdue(now)) c.close(why);
    return c.closed();
  });
  sweep_timer_.expires_after(kSweepPeriod);
  sweep_timer_.async_wait([this](std::error_code ec) {
    if (!ec && !closed_) sweep();
  });
}

void SocketServer::accept() {
  acceptor_.async_accept([this](std::error_code ec, tcp::socket socket) {
    if (closed_) return;  // accepted just before close(): the socket closes with this handler
    if (ec) {
      if (ec != asio::error::operation_aborted) {
        // Out of file descriptors, say: the listening socket stays readable, so accepting
        // again at once would spin; try again after a pause.
        if (listenerLog().admit("accept_failed"))
          spdlog::warn("event=accept_failed error=\"{}\"", ec.message());
        accept_timer_.expires_after(kAcceptRetry);
        accept_timer_.async_wait([this](std::error_code e) {
          if (!e && !closed_) accept();
        });
      }
      return;
    }
    auto dropClosed = [&] {
      std::erase_if(connections_, [](const auto& entry) { return entry.second->closed(); });
    };
    dropClosed();
    const int max_clients = engine_.config().max_clients;
    if (int(connections_.size()) >= max_clients) {
      // At the limit, connections whose peer has closed them hold their slots for nothing
      // (their end of file may be read after this handler): they go first.
      for (auto& [id, c] : connections_)
        if (c->closedByPeer()) c->close("eof");
      dropClosed();
    }
    if (int(connections_.size()) >= max_clients) {
      // Still at the limit, a newcomer takes the place of the connection that has had nothing
      // to do for longest, if that has been idle for at least the request timeout: idle
      // connections never starve a working one.
      const auto now = Clock::now();
      std::shared_ptr<Connection> idlest;
      Clock::duration longest = secondsToDuration(engine_.config().socket_timeouts.request_s);
      for (auto& [id, c] : connections_)
        if (auto idle = c->idleFor(now); idle && *idle >= longest) {
          longest = *idle;
          idlest = c;
        }
      if (idlest) idlest->close("evicted_idle");
      dropClosed();
    }
    if (int(connections_.size()) >= max_clients) {
      if (listenerLog().admit("client_refused/max_clients"))
        spdlog::warn("event=client_refused reason=max_clients");
      engine_.telemetry().noteError(ErrorCode::kLimit);
      if (refusing_->load() < kMaxRefusing) {
        refuseOverLimit(std::move(socket), max_clients, refusing_);
      } else {
        const std::string refusal = overLimitRefusal(nullptr, max_clients);
        std::error_code ignored;
        socket.non_blocking(true, ignored);
        asio::write(socket, asio::buffer(refusal), ignored);
        socket.close(ignored);
      }
    } else {
      auto connection = std::make_shared<Connection>(std::move(socket), engine_, next_id_);
      connections_[next_id_++] = connection;
      connection->start();
    }
    accept();
  });
}

void SocketServer::close() {
  closed_ = true;
  std::error_code ec;
  acceptor_.close(ec);
  sweep_timer_.cancel();
  accept_timer_.cancel();
  // Replies already posted are written out (within kShutdownDrain) before each closes.
  for (auto& [id, c] : connections_) c->finish("shutdown", kShutdownDrain);
  connections_.clear();
}

MetricsServer::MetricsServer(asio::io_context& io, Engine& engine)
    : io_(io), engine_(engine), acceptor_(io), accept_timer_(io) {}

std::string MetricsServer::listen(const ListenConfig& where) {
  if (std::string e = openAcceptor(acceptor_, where, "metrics"); !e.empty()) return e;
  port_ = acceptor_.local_endpoint().port();
  accept();
  return "";
}

// One scrape: a request, a response, then the connection closes.
struct MetricsExchange {
  explicit MetricsExchange(tcp::socket s) : socket(std::move(s)), timer(socket.get_executor()) {}
  void close() {
    std::error_code ignored;
    timer.cancel();
    socket.close(ignored);
  }
  tcp::socket socket;
  asio::steady_timer timer;
  asio::streambuf request{8192};
  std::string response;
};

void MetricsServer::accept() {
  acceptor_.async_accept([this](std::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || closed_) return;
    if (ec) {  // as SocketServer::accept: a pause, not a spin
      if (listenerLog().admit("metrics_accept_failed"))
        spdlog::warn("event=metrics_accept_failed error=\"{}\"", ec.message());
      accept_timer_.expires_after(kAcceptRetry);
      accept_timer_.async_wait([this](std::error_code e) {
        if (!e && !closed_) accept();
      });
      return;
    }
    std::erase_if(open_, [](const auto& weak) { return weak.expired(); });
    if (!ec && open_.size() >= kMaxMetricsConnections) {
      std::error_code ignored;
      socket.close(ignored);  // a scraper needs one at a time; more are not scrapers
    } else if (!ec) {
      // One exchange per connection, the whole of it within the socket request timeout.
      auto x = std::make_shared<MetricsExchange>(std::move(socket));
      open_.push_back(x);
      x->timer.expires_after(secondsToDuration(engine_.config().socket_timeouts.request_s));
      x->timer.async_wait([x](std::error_code ec) {
        std::error_code ignored;
        if (!ec) x->socket.close(ignored);
      });
      asio::async_read_until(
          x->socket, x->request, "\r\n\r\n", [this, x](std::error_code ec, std::size_t) {
            if (ec) {
              x->close();
              return;
            }
            std::string first_line;
            std::istream in(&x->request);
            std::getline(in, first_line);
            // GET /metrics: Prometheus text. GET /healthz: 200 while the world thread runs its
            // loop (it wakes at least twice a second), 503 once it has been stuck for
            // kStuckSeconds (a render or advance that long is a fault for an IG).
            const bool metrics = first_line.rfind("GET /metrics ", 0) == 0;
            const bool health = first_line.rfind("GET /healthz ", 0) == 0;
            const bool healthy = engine_.telemetry().heartbeatAge() < Telemetry::kStuckSeconds;
            const std::string body = metrics  ? engine_.prometheusText()
                                     : health ? (healthy ? "ok\n" : "world thread stuck\n")
                                              : "not found\n";
            const char* status = metrics || (health && healthy) ? "HTTP/1.1 200 OK\r\n"
                                 : health ? "HTTP/1.1 503 Service Unavailable\r\n"
                                          : "HTTP/1.1 404 Not Found\r\n";
            x->response = std::string(status) +
                          "Content-Type: text/plain; version=0.0.4\r\n"
                          "Content-Length: " +
                          std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body;
            asio::async_write(x->socket, asio::buffer(x->response),
                              [x](std::error_code, std::size_t) { x->close(); });
          });
    }
    accept();
  });
}

void MetricsServer::close() {
  closed_ = true;
  std::error_code ec;
  acceptor_.close(ec);
  accept_timer_.cancel();
  for (auto& weak : open_)
    if (auto x = weak.lock()) x->close();
  open_.clear();
}

}  // namespace nephele
