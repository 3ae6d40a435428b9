#include "server/modbus_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <future>

#include "server/log_limiter.h"
#include "server/tcp_peer.h"

namespace nephele {
namespace {

constexpr int kPollMs = 100;  // how often waiting threads look at their flags and deadlines

// Writes all of `bytes`; false if the peer is gone or does not read within the send timeout.
bool sendAll(int fd, const std::vector<std::uint8_t>& bytes) {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += std::size_t(n);
  }
  return true;
}

// A client that does not read its replies is dropped rather than blocking its thread.
void setSendTimeout(int fd, double seconds) {
  const auto send_timeout = secondsToDuration(seconds);
  timeval tv{};
  tv.tv_sec = std::chrono::duration_cast<std::chrono::seconds>(send_timeout).count();
  tv.tv_usec =
      long(std::chrono::duration_cast<std::chrono::microseconds>(send_timeout).count() % 1000000);
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
}

// One ADU arriving from a stream: the MBAP header first, then exactly the PDU it announces,
// reading no further (the next request stays in the socket).
struct AduAssembly {
  std::array<std::uint8_t, ModbusAdu::kMaxAduBytes> bytes{};
  std::size_t have = 0;  // bytes received
  MbapHeader header;     // once `have` reaches the header's size

  std::size_t wanted() const {
    return have < ModbusAdu::kHeaderBytes ? ModbusAdu::kHeaderBytes
                                          : ModbusAdu::kHeaderBytes + header.pduBytes();
  }
  bool complete() const {
    return have >= ModbusAdu::kHeaderBytes && have >= ModbusAdu::kHeaderBytes + header.pduBytes();
  }
  std::span<const std::uint8_t> pdu() const {
    return {bytes.data() + ModbusAdu::kHeaderBytes, header.pduBytes()};
  }
};

}  // namespace

bool ModbusServer::ClientState::connectionOver() {
  std::lock_guard lock(fd_mutex);
  return fd < 0 || peerHasClosed(fd);
}

void ModbusServer::ClientState::closeSocket() {
  std::lock_guard lock(fd_mutex);
  ::close(fd);
  fd = -1;
}

ModbusServer::ModbusServer(Engine& engine) : engine_(engine) {}

ModbusServer::~ModbusServer() {
  close();
}

std::string ModbusServer::listen(const ListenConfig& where) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(std::uint16_t(where.port));
  if (inet_pton(AF_INET, where.bind.c_str(), &address.sin_addr) != 1)
    return "modbus.bind: \"" + where.bind + "\" is not an IPv4 address";
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const int yes = 1;
  setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  // The kernel's longest backlog, as the socket listener has: a burst of connections waits
  // there for the accept thread instead of having its SYNs dropped (a client then retries
  // only after a second).
  if (listen_fd_ < 0 || ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) ||
      ::listen(listen_fd_, SOMAXCONN)) {
    const std::string why = std::strerror(errno);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    return "cannot listen for modbus on " + where.bind + ":" + std::to_string(where.port) + ": " +
           why;
  }
  socklen_t length = sizeof address;
  getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&address), &length);
  port_ = ntohs(address.sin_port);
  accept_thread_ = std::thread([this] { acceptLoop(); });
  return "";
}

void ModbusServer::close() {
  if (stop_.exchange(true)) return;
  if (accept_thread_.joinable()) accept_thread_.join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
  std::lock_guard lock(clients_mutex_);
  for (Client& c : clients_) c.thread.join();
  clients_.clear();
  listenerLog().flushAll();
}

int ModbusServer::activeClients() const {
  return int(std::count_if(clients_.begin(), clients_.end(),
                           [](const Client& c) { return !c.state->end; }));
}

void ModbusServer::makeRoom() {
  // A peer that closed its connection (dropped in the middle of a frame, say) holds a slot
  // for nothing: its thread may not have read the end yet, or not even started.
  for (Client& c : clients_)
    if (!c.state->end && c.state->connectionOver()) c.state->end = "closed";
  if (activeClients() < engine_.config().modbus_max_clients) return;
  // The newcomer takes the place of the client idle longest, if that has been idle (between
  // frames) for at least the request timeout.
  const Clock::rep now = Clock::now().time_since_epoch().count();
  ClientState* idlest = nullptr;
  Clock::rep longest = secondsToDuration(engine_.config().modbus_timeouts.request_s).count();
  for (Client& c : clients_) {
    ClientState& s = *c.state;
    if (s.end || s.mid_request) continue;
    if (const Clock::rep idle = now - s.last_activity; idle >= longest) {
      longest = idle;
      idlest = &s;
    }
  }
  if (idlest) idlest->end = "evicted_idle";
}

void ModbusServer::acceptLoop() {
  const DaemonConfig& config = engine_.config();
  while (!stop_) {
    listenerLog().flush();
    pollfd p{listen_fd_, POLLIN, 0};
    if (poll(&p, 1, kPollMs) <= 0) continue;
    sockaddr_in peer{};
    socklen_t length = sizeof peer;
    const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &length, SOCK_CLOEXEC);
    if (fd < 0) {
      // Out of file descriptors, say: the connection stays in the backlog and the listening
      // socket readable, so accepting again at once would spin; pause as the socket server does.
      if (errno != EINTR && errno != ECONNABORTED && errno != EAGAIN) {
        if (listenerLog().admit("modbus_accept_failed"))
          spdlog::warn("event=modbus_accept_failed error=\"{}\"", std::strerror(errno));
        std::this_thread::sleep_for(std::chrono::milliseconds(kPollMs));
      }
      continue;
    }
    char text[INET_ADDRSTRLEN] = {};
    inet_ntop(AF_INET, &peer.sin_addr, text, sizeof text);
    const std::string address = text;
    const auto& allow = config.modbus_allow;
    if (std::find(allow.begin(), allow.end(), "*") == allow.end() &&
        std::find(allow.begin(), allow.end(), address) == allow.end()) {
      if (listenerLog().admit("modbus_refused/not_allowed"))
        spdlog::warn("event=modbus_refused peer={} reason=not_allowed", address);
      engine_.telemetry().noteError(ErrorCode::kUnauthorized);
      ::close(fd);
      continue;
    }
    std::lock_guard lock(clients_mutex_);
    std::erase_if(clients_, [](Client& c) {
      if (!c.state->finished) return false;
      c.thread.join();
      return true;
    });
    if (activeClients() >= config.modbus_max_clients) makeRoom();
    if (activeClients() >= config.modbus_max_clients) {
      if (listenerLog().admit("modbus_refused/max_clients"))
        spdlog::warn("event=modbus_refused peer={} reason=max_clients", address);
      engine_.telemetry().noteError(ErrorCode::kLimit);
      ::close(fd);
      continue;
    }
    auto state = std::make_shared<ClientState>(fd);
    state->last_activity = Clock::now().time_since_epoch().count();
    const std::string peer_name = address + ":" + std::to_string(ntohs(peer.sin_port));
    clients_.push_back({std::thread([this, fd, peer_name, state] {
                          serveClient(fd, peer_name, *state);
                          state->finished = true;
                        }),
                        state});
  }
}

void ModbusServer::serveClient(int fd, const std::string& peer, ClientState& state) {
  ++engine_.telemetry().modbus_clients;
  if (listenerLog().admit("modbus_connected")) spdlog::info("event=modbus_connected peer={}", peer);
  const Timeouts& timeouts = engine_.config().modbus_timeouts;
  setSendTimeout(fd, timeouts.request_s);
  AduAssembly adu;
  Clock::time_point started;  // when the current ADU's first byte arrived
  Clock::time_point last_activity = Clock::now();
  const char* why = "stop";
  while (!stop_) {
    if (const char* end = state.end) {
      why = end;
      break;
    }
    const auto now = Clock::now();
    if (adu.have > 0 && now - started > secondsToDuration(timeouts.request_s)) {
      why = "request_timeout";
      break;
    }
    if (adu.have == 0 && timeouts.idle_s > 0.0 &&
        now - last_activity > secondsToDuration(timeouts.idle_s)) {
      why = "idle_timeout";
      break;
    }
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, kPollMs) <= 0) continue;
    const ssize_t n = ::recv(fd, adu.bytes.data() + adu.have, adu.wanted() - adu.have, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      why = n == 0 ? "closed" : "read_error";
      break;
    }
    if (adu.have == 0) {
      started = Clock::now();
      state.mid_request = true;
    }
    adu.have += std::size_t(n);
    if (adu.have == ModbusAdu::kHeaderBytes) {
      auto decoded = decodeMbapHeader(
          std::span<const std::uint8_t, ModbusAdu::kHeaderBytes>(adu.bytes.data(), 7));
      if (auto* e = std::get_if<std::string>(&decoded)) {
        // The stream cannot be framed past this header: close rather than guess.
        if (listenerLog().admit("modbus_bad_frame"))
          spdlog::warn("event=modbus_bad_frame peer={} error=\"{}\"", peer, *e);
        engine_.telemetry().noteError(ErrorCode::kBadField);
        why = "bad_frame";
        break;
      }
      adu.header = std::get<MbapHeader>(decoded);
    }
    if (!adu.complete()) continue;
    auto request = decodeModbusPdu(adu.header, adu.pdu());
    const std::vector<std::uint8_t> reply =
        std::holds_alternative<ModbusRequest>(request)
            ? answer(std::get<ModbusRequest>(request))
            : refuse(adu.header, std::get<ModbusException>(request));
    adu.have = 0;
    state.mid_request = false;
    last_activity = Clock::now();
    state.last_activity = last_activity.time_since_epoch().count();
    if (!sendAll(fd, reply)) {
      why = "reply_failed";
      break;
    }
  }
  state.closeSocket();
  --engine_.telemetry().modbus_clients;
  if (listenerLog().admit(std::string("modbus_closed/") + why))
    spdlog::info("event=modbus_closed peer={} reason={}", peer, why);
}

std::vector<std::uint8_t> ModbusServer::refuse(const MbapHeader& header,
                                               const ModbusException& exception) {
  if (listenerLog().admit("modbus_exception"))
    spdlog::warn("event=modbus_exception function=0x{:02x} code={} message=\"{}\"",
                 exception.function, exception.code, exception.message);
  engine_.telemetry().noteError(exception.code == kServerDeviceBusy ? ErrorCode::kBusy
                                                                    : ErrorCode::kBadField);
  return encodeModbusException(header, exception);
}

std::optional<ProtocolError> ModbusServer::runBatch(std::vector<Command> commands, bool render) {
  auto ticket = std::make_shared<BatchTicket>();
  auto outcome = std::make_shared<std::promise<std::optional<ProtocolError>>>();
  std::future<std::optional<ProtocolError>> result = outcome->get_future();
  if (!engine_.submitBatch(std::move(commands), render, ticket,
                           [outcome](std::optional<ProtocolError> e) { outcome->set_value(e); }))
    return ProtocolError{ErrorCode::kBusy, "the request queue is full; nothing was changed"};
  if (result.wait_for(secondsToDuration(engine_.config().modbus_timeouts.request_s)) !=
          std::future_status::ready &&
      ticket->withdraw()) {
    if (render) engine_.clearRenderTrigger();
    return ProtocolError{ErrorCode::kBusy,
                         "the world thread did not take the write in time; nothing was changed"};
  }
  return result.get();  // taken by the world thread: its outcome, whenever it comes
}

std::vector<std::uint8_t> ModbusServer::answer(const ModbusRequest& request) {
  const std::uint8_t function = std::uint8_t(request.function);
  auto exception = [&](int code, std::string message) {
    return refuse(request.header, {function, code, std::move(message)});
  };
  auto outOfMap = [&](int size, const char* what) {
    return exception(kIllegalDataAddress,
                     std::string(what) + " " + std::to_string(request.address) + " to " +
                         std::to_string(request.address + request.count - 1) +
                         " are not in the map (allowed: 0 to " + std::to_string(size - 1) + ")");
  };
  auto fits = [&](int size) { return request.address + request.count <= size; };
  auto applied = [&](std::optional<ProtocolError> error) {
    if (!error) return encodeWriteReply(request);
    return exception(error->code == ErrorCode::kBusy ? kServerDeviceBusy : kIllegalDataValue,
                     error->message);
  };

  switch (request.function) {
    case ModbusFunction::kReadCoils: {
      if (!fits(ModbusMap::kCoilCount)) return outOfMap(ModbusMap::kCoilCount, "coils");
      std::array<std::uint8_t, ModbusMap::kCoilCount> coils{};
      coils[ModbusMap::kRenderCoil] = engine_.renderTriggerPending();
      coils[ModbusMap::kPauseCoil] = engine_.telemetry().status().status == RunState::kPaused;
      return encodeReadBits(request, std::span(coils).subspan(std::size_t(request.address),
                                                              std::size_t(request.count)));
    }
    case ModbusFunction::kReadDiscreteInputs:
      return exception(kIllegalDataAddress,
                       "the map has no discrete inputs (read the coils with function 1)");
    case ModbusFunction::kReadHoldingRegisters: {
      if (!fits(ModbusMap::kHoldingCount))
        return outOfMap(ModbusMap::kHoldingCount, "holding registers");
      const HoldingRegisters holding = encodeHolding(engine_.telemetry().readings());
      return encodeReadRegisters(request, std::span(holding).subspan(std::size_t(request.address),
                                                                     std::size_t(request.count)));
    }
    case ModbusFunction::kReadInputRegisters: {
      if (!fits(ModbusMap::kInputCount)) return outOfMap(ModbusMap::kInputCount, "input registers");
      const InputRegisters input = encodeInput(engine_.telemetry().status());
      return encodeReadRegisters(request, std::span(input).subspan(std::size_t(request.address),
                                                                   std::size_t(request.count)));
    }
    case ModbusFunction::kWriteSingleRegister:
    case ModbusFunction::kWriteMultipleRegisters: {
      const HoldingRegisters current = encodeHolding(engine_.telemetry().readings());
      auto decoded = decodeHoldingWrite(current, request.address, request.registers,
                                        engine_.config().modbus_view);
      if (auto* e = std::get_if<RegisterError>(&decoded))
        return exception(e->exception, e->message);
      return applied(runBatch(std::move(std::get<std::vector<Command>>(decoded)), false));
    }
    case ModbusFunction::kWriteSingleCoil:
    case ModbusFunction::kWriteMultipleCoils: {
      auto decoded = decodeCoilWrite(request.address, request.bits);
      if (auto* e = std::get_if<RegisterError>(&decoded))
        return exception(e->exception, e->message);
      const CoilWrite& write = std::get<CoilWrite>(decoded);
      std::vector<Command> commands;
      if (write.paused) commands.push_back(command::SetTime{{}, write.paused, {}, {}});
      if (commands.empty() && !write.render) return encodeWriteReply(request);
      return applied(runBatch(std::move(commands), write.render));
    }
  }
  return exception(kIllegalFunction, "function is not served");
}

}  // namespace nephele
