#include "server/cigi_server.h"

#include <spdlog/spdlog.h>

#include <memory>

#include "server/log_limiter.h"

namespace nephele {

using asio::ip::udp;

namespace {

constexpr std::size_t kMaxWaiting = 64;  // datagrams held while one is with the Engine

cigi::SessionSettings sessionSettings(const DaemonConfig& config) {
  cigi::SessionSettings s;
  s.site = config.site;
  s.recentre_m = config.cigi.recentre_distance_m;
  s.views = config.cigi.views;
  for (const EntityType& t : config.entity_types) s.entity_types.emplace_back(t.id, t.name);
  s.default_frame_s = 1.0 / config.tick_rate_hz;
  return s;
}

}  // namespace

CigiServer::CigiServer(asio::io_context& io, Engine& engine)
    : io_(io), engine_(engine), socket_(io), session_(sessionSettings(engine.config())) {}

std::string CigiServer::listen(const CigiConfig& config) {
  std::error_code ec;
  const asio::ip::address address = asio::ip::make_address(config.bind, ec);
  if (ec) return "cigi.bind: \"" + config.bind + "\" is not an IP address";
  socket_.open(address.is_v6() ? udp::v6() : udp::v4(), ec);
  if (!ec) socket_.bind(udp::endpoint(address, std::uint16_t(config.ig_port)), ec);
  if (ec)
    return "cigi: cannot listen on " + config.bind + ":" + std::to_string(config.ig_port) + ": " +
           ec.message();
  port_ = socket_.local_endpoint().port();
  host_port_ = config.host_port;
  engine_.onFrameStart([this] { asio::post(io_, [this] { igFrame(); }); });
  receive();
  return "";
}

void CigiServer::close() {
  closed_ = true;
  engine_.onFrameStart({});
  std::error_code ec;
  socket_.close(ec);
}

void CigiServer::receive() {
  socket_.async_receive_from(
      asio::buffer(buffer_), sender_, [this](std::error_code ec, std::size_t n) {
        if (closed_) return;
        if (!ec) {
          if (waiting_.size() >= kMaxWaiting) {
            refuse("busy",
                   "more than " + std::to_string(kMaxWaiting) +
                       " messages are waiting for the world thread",
                   sender_);
          } else {
            waiting_.push_back(
                {std::vector<std::uint8_t>(buffer_.begin(), buffer_.begin() + n), sender_});
            next();
          }
        }
        receive();
      });
}

// The one place where a datagram or a packet is refused: counted by reason in the daemon's
// stats and metrics, and logged through the listeners' limiter (the reasons are the code's,
// never a datagram's).
void CigiServer::refuse(const std::string& reason, const std::string& message,
                        const udp::endpoint& from) {
  engine_.telemetry().countCigi("refused_" + reason);
  if (listenerLog().admit("cigi_refused/" + reason))
    spdlog::warn("event=cigi_refused reason={} from={}:{} error=\"{}\"", reason,
                 from.address().to_string(), from.port(), message);
}

void CigiServer::next() {
  if (busy_ || waiting_.empty() || closed_) return;
  Datagram d = std::move(waiting_.front());
  waiting_.pop_front();
  auto decoded = cigi::decodeHostMessage(d.bytes);
  if (auto* e = std::get_if<cigi::DecodeError>(&decoded)) {
    refuse(std::string(cigi::faultName(e->fault)), e->message, d.from);
    return next();
  }
  const cigi::Message& message = std::get<cigi::Message>(decoded);
  // Every message with a valid IG Control is answered with a Start of Frame, whose IG status
  // says what became of it (docs/CIGI.md): a host in synchronous mode never waits in vain.
  // In asynchronous mode the answer is the next IG frame's Start of Frame (answer()).
  auto mapped = session_.map(message);
  if (auto* r = std::get_if<cigi::Refusal>(&mapped)) {
    refuse(r->reason, r->message, d.from);
    answer(r->control, message.order, d.from, r->status);
    return next();
  }
  cigi::MappedMessage& frame = std::get<cigi::MappedMessage>(mapped);
  for (const std::string& what : frame.ignored) {
    engine_.telemetry().countCigi("ignored");
    spdlog::debug("event=cigi_ignored what=\"{}\"", what);
  }
  for (const std::string& what : frame.refused) refuse("bad_value", what, d.from);
  if (frame.site_adopted)
    spdlog::info(
        "event=cigi_site latitude={:.6f} longitude={:.6f} what=\"no [site] configured: the "
        "database origin is the host's first position\"",
        frame.site_adopted->latitude_deg, frame.site_adopted->longitude_deg);
  if (frame.recentred) engine_.telemetry().countCigi("recentred");
  const std::uint8_t status =
      frame.refused.empty() ? cigi::IgStatus::kApplied : cigi::IgStatus::kPacketsRefused;
  // Synchronous (lockstep) mode: the world advances by the host's frame time, and the tick
  // renders each subscribed view once.
  if (engine_.lockstep() && frame.control.mode != cigi::IgMode::kStandby)
    frame.commands.emplace_back(command::Tick{frame.dt_s});
  busy_ = true;
  const cigi::IgControl control = frame.control;
  auto done = [this, order = message.order, control, status,
               from = d.from](std::optional<ProtocolError> error) {
    asio::post(io_, [this, order, control, status, from, error] {
      busy_ = false;
      if (closed_) return;
      if (error) {
        refuse("refused_by_world", error->message, from);
        session_.forget();
        answer(control, order, from, cigi::IgStatus::kWorldRefused);
      } else {
        session_.commit();
        engine_.telemetry().countCigi("messages");
        answer(control, order, from, status);
      }
      next();
    });
  };
  if (!engine_.submitBatch(std::move(frame.commands), false, nullptr, done)) {
    busy_ = false;
    refuse("busy", "the daemon's request queue is full", d.from);
    answer(control, message.order, d.from, cigi::IgStatus::kBusy);
    next();
  }
}

void CigiServer::answer(const cigi::IgControl& control, cigi::ByteOrder order,
                        const udp::endpoint& from, std::uint8_t status) {
  if (engine_.lockstep()) return sendStartOfFrame(control, order, from, status);
  last_handled_ = Handled{control, order, from, status};
}

// Asynchronous mode: the IG announces each of its frames at its own rate (the world's tick
// rate), to the host that last sent a frame, reporting the last host frame it handled.
void CigiServer::igFrame() {
  if (closed_ || !last_handled_ || engine_.lockstep()) return;
  sendStartOfFrame(last_handled_->control, last_handled_->order, last_handled_->from,
                   last_handled_->status);
}

void CigiServer::sendStartOfFrame(const cigi::IgControl& control, cigi::ByteOrder order,
                                  const udp::endpoint& to, std::uint8_t status) {
  cigi::StartOfFrame sof;
  sof.database = control.database;
  sof.ig_status = status;
  sof.mode =
      control.mode == cigi::IgMode::kStandby ? cigi::IgMode::kStandby : cigi::IgMode::kOperate;
  sof.ig_frame = ++ig_frame_;
  sof.last_host_frame = control.host_frame;
  sof.timestamp_valid = true;
  sof.timestamp = std::uint32_t(std::chrono::duration_cast<std::chrono::microseconds>(
                                    std::chrono::steady_clock::now() - started_)
                                    .count() /
                                10);
  auto bytes = std::make_shared<std::vector<std::uint8_t>>();
  cigi::encode(sof, order, *bytes);  // answered in the host's own byte order
  const udp::endpoint target(to.address(), host_port_ ? std::uint16_t(host_port_) : to.port());
  socket_.async_send_to(asio::buffer(*bytes), target, [bytes](std::error_code, std::size_t) {});
}

}  // namespace nephele
