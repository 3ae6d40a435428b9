#include "server/socket_server.h"

#include <spdlog/spdlog.h>

#include <array>
#include <deque>

namespace nephele {

using asio::ip::tcp;

// One client of the socket protocol. Every member is used on the io thread only, except
// closed_, which frame sinks on other threads read.
class Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(tcp::socket socket, Engine& engine, std::int64_t id)
      : socket_(std::move(socket)),
        engine_(engine),
        id_(id),
        authorised_(engine.config().token.empty()) {
    std::error_code ec;
    const tcp::endpoint peer = socket_.remote_endpoint(ec);
    peer_ = ec ? "?" : peer.address().to_string() + ":" + std::to_string(peer.port());
    socket_.set_option(tcp::no_delay(true), ec);
  }

  void start() {
    ++engine_.socket_clients;
    spdlog::info("event=client_connected id={} peer={}", id_, peer_);
    read();
  }

  void close(const char* why) {
    if (closed_.exchange(true)) return;
    std::error_code ec;
    socket_.shutdown(tcp::socket::shutdown_both, ec);
    socket_.close(ec);
    --engine_.socket_clients;
    spdlog::info("event=client_closed id={} peer={} reason={}", id_, peer_, why);
  }

  // Queues a reply or frame for writing.
  void send(SharedReply reply) {
    if (closed_) return;
    pending_bytes_ += reply->size();
    out_.push_back(std::move(reply));
    if (!writing_) write();
  }

  // A subscribed frame: dropped when the client is already too far behind.
  void offerFrame(SharedReply frame) {
    if (closed_) return;
    if (pending_bytes_ + frame->size() > engine_.config().max_pending_bytes) {
      ++engine_.frames_dropped;
      return;
    }
    send(std::move(frame));
  }

 private:
  void read() {
    socket_.async_read_some(
        asio::buffer(chunk_),
        [self = shared_from_this()](std::error_code ec, std::size_t n) { self->onRead(ec, n); });
  }

  void onRead(std::error_code ec, std::size_t n) {
    if (ec) {
      close(ec == asio::error::eof ? "eof" : "read_error");
      return;
    }
    std::string_view data(chunk_.data(), n);
    while (!data.empty() && !closed_) {
      const std::size_t newline = data.find('\n');
      const std::string_view part = data.substr(0, newline);
      if (!discarding_) line_.append(part);
      if (!discarding_ && line_.size() >= ProtocolLimits::kMaxRequestBytes) {
        // Answer once, then skip the rest of the line: the connection stays usable.
        sendError(nullptr,
                  {ErrorCode::kTooLarge, "request line is longer than " +
                                             std::to_string(ProtocolLimits::kMaxRequestBytes) +
                                             " bytes (allowed: less); it was skipped"});
        discarding_ = true;
        line_.clear();
      }
      if (newline == std::string_view::npos) break;
      if (!discarding_) handleLine();
      discarding_ = false;
      line_.clear();
      data.remove_prefix(newline + 1);
    }
    if (!closed_) read();
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
    if (auto* hello = std::get_if<command::Hello>(&request.command);
        hello && !engine_.config().token.empty()) {
      authorised_ = hello->token && *hello->token == engine_.config().token;
      if (!authorised_) {
        spdlog::warn("event=bad_token id={} peer={}", id_, peer_);
        sendError(request.id, {ErrorCode::kUnauthorized, "token: missing or wrong"});
        return;
      }
    }
    if (!authorised_) {
      sendError(request.id, {ErrorCode::kUnauthorized,
                             "this daemon needs a token: send {\"cmd\":\"hello\",\"token\":...} "
                             "first"});
      return;
    }
    if (pending_bytes_ > engine_.config().max_pending_bytes) {
      sendError(request.id,
                {ErrorCode::kBusy, "this connection has " + std::to_string(pending_bytes_ >> 20) +
                                       " MiB of replies unread; read them first"});
      return;
    }
    const nlohmann::json id = request.id;
    std::weak_ptr<Connection> weak = weak_from_this();
    asio::io_context& io = static_cast<asio::io_context&>(socket_.get_executor().context());
    auto reply = [weak, &io](SharedReply r) {
      asio::post(io, [weak, r = std::move(r)] {
        if (auto c = weak.lock()) c->send(r);
      });
    };
    auto frames = [weak, &io](SharedReply r) {
      auto c = weak.lock();
      if (!c || c->closed_) return false;
      asio::post(io, [c, r = std::move(r)] { c->offerFrame(r); });
      return true;
    };
    if (!engine_.submit(std::move(request), id_, frames, reply))
      sendError(id, {ErrorCode::kBusy, "the request queue is full (" +
                                           std::to_string(engine_.config().max_queue) +
                                           " waiting); try again"});
  }

  void sendError(const nlohmann::json& id, const ProtocolError& error) {
    engine_.noteError(error.code);
    send(makeReply(errorReply(id, error)));
  }

  void write() {
    writing_ = true;
    const SharedReply& r = out_.front();
    std::array<asio::const_buffer, 2> buffers{
        asio::buffer(r->header), r->body ? asio::buffer(*r->body) : asio::const_buffer()};
    asio::async_write(socket_, buffers,
                      [self = shared_from_this()](std::error_code ec, std::size_t) {
                        const SharedReply& done = self->out_.front();
                        self->pending_bytes_ -= done->size();
                        self->out_.pop_front();
                        if (ec) {
                          self->close("write_error");
                          return;
                        }
                        if (!self->out_.empty())
                          self->write();
                        else
                          self->writing_ = false;
                      });
  }

  tcp::socket socket_;
  Engine& engine_;
  std::int64_t id_;
  std::string peer_;
  bool authorised_;
  std::array<char, 16384> chunk_{};
  std::string line_;
  bool discarding_ = false;
  std::deque<SharedReply> out_;
  std::size_t pending_bytes_ = 0;
  bool writing_ = false;
  std::atomic<bool> closed_{false};

  friend class SocketServer;
};

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
    : io_(io), engine_(engine), acceptor_(io) {}

SocketServer::~SocketServer() = default;

std::string SocketServer::listen(const ListenConfig& where) {
  if (std::string e = openAcceptor(acceptor_, where, "socket"); !e.empty()) return e;
  port_ = acceptor_.local_endpoint().port();
  accept();
  return "";
}

void SocketServer::accept() {
  acceptor_.async_accept([this](std::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec != asio::error::operation_aborted) {
        spdlog::warn("event=accept_failed error=\"{}\"", ec.message());
        accept();
      }
      return;
    }
    std::erase_if(connections_, [](const auto& entry) { return entry.second.expired(); });
    if (engine_.socket_clients.load() >= engine_.config().max_clients) {
      const std::string refusal = errorReply(
          nullptr, {ErrorCode::kLimit, "too many clients (allowed: " +
                                           std::to_string(engine_.config().max_clients) + ")"});
      std::error_code ignored;
      socket.non_blocking(true, ignored);
      asio::write(socket, asio::buffer(refusal), ignored);
      socket.close(ignored);
      spdlog::warn("event=client_refused reason=max_clients");
    } else {
      auto connection = std::make_shared<Connection>(std::move(socket), engine_, next_id_);
      connections_[next_id_++] = connection;
      connection->start();
    }
    accept();
  });
}

void SocketServer::close() {
  std::error_code ec;
  acceptor_.close(ec);
  for (auto& [id, weak] : connections_)
    if (auto c = weak.lock()) c->close("shutdown");
  connections_.clear();
}

MetricsServer::MetricsServer(asio::io_context& io, Engine& engine)
    : io_(io), engine_(engine), acceptor_(io) {}

std::string MetricsServer::listen(const ListenConfig& where) {
  if (std::string e = openAcceptor(acceptor_, where, "metrics"); !e.empty()) return e;
  port_ = acceptor_.local_endpoint().port();
  accept();
  return "";
}

void MetricsServer::accept() {
  acceptor_.async_accept([this](std::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted) return;
    if (!ec) {
      auto s = std::make_shared<tcp::socket>(std::move(socket));
      auto request = std::make_shared<asio::streambuf>(8192);
      asio::async_read_until(
          *s, *request, "\r\n\r\n", [this, s, request](std::error_code ec, std::size_t) {
            if (ec) return;
            std::string first_line;
            std::istream in(request.get());
            std::getline(in, first_line);
            const bool metrics = first_line.rfind("GET /metrics ", 0) == 0;
            const std::string body = metrics ? engine_.prometheusText() : "not found\n";
            auto response = std::make_shared<std::string>(
                std::string(metrics ? "HTTP/1.1 200 OK\r\n" : "HTTP/1.1 404 Not Found\r\n") +
                "Content-Type: text/plain; version=0.0.4\r\n"
                "Content-Length: " +
                std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body);
            asio::async_write(*s, asio::buffer(*response),
                              [s, response](std::error_code, std::size_t) {
                                std::error_code ignored;
                                s->close(ignored);
                              });
          });
    }
    accept();
  });
}

void MetricsServer::close() {
  std::error_code ec;
  acceptor_.close(ec);
}

}  // namespace nephele
