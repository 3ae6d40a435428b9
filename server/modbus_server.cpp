#include "server/modbus_server.h"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <future>

namespace nephele {
namespace {

constexpr int kPollMs = 200;  // how often idle threads look at the stop flag
constexpr auto kWriteTimeout = std::chrono::seconds(5);  // a write waits this long for the world

std::uint16_t be16(const std::uint8_t* p) {
  return std::uint16_t(p[0] << 8 | p[1]);
}

}  // namespace

ModbusServer::ModbusServer(Engine& engine) : engine_(engine) {
  mapping_ = modbus_mapping_new(ModbusMap::kCoilCount, 0, ModbusMap::kHoldingCount,
                                ModbusMap::kInputCount);
}

ModbusServer::~ModbusServer() {
  close();
  modbus_mapping_free(mapping_);
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
  if (listen_fd_ < 0 || ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) ||
      ::listen(listen_fd_, 64)) {
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
}

void ModbusServer::acceptLoop() {
  const DaemonConfig& config = engine_.config();
  while (!stop_) {
    pollfd p{listen_fd_, POLLIN, 0};
    if (poll(&p, 1, kPollMs) <= 0) continue;
    sockaddr_in peer{};
    socklen_t length = sizeof peer;
    const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &length, SOCK_CLOEXEC);
    if (fd < 0) continue;
    char text[INET_ADDRSTRLEN] = {};
    inet_ntop(AF_INET, &peer.sin_addr, text, sizeof text);
    const std::string address = text;
    const auto& allow = config.modbus_allow;
    if (std::find(allow.begin(), allow.end(), "*") == allow.end() &&
        std::find(allow.begin(), allow.end(), address) == allow.end()) {
      spdlog::warn("event=modbus_refused peer={} reason=not_allowed", address);
      engine_.noteError(ErrorCode::kUnauthorized);
      ::close(fd);
      continue;
    }
    std::lock_guard lock(clients_mutex_);
    std::erase_if(clients_, [](Client& c) {
      if (!c.finished->load()) return false;
      c.thread.join();
      return true;
    });
    if (int(clients_.size()) >= config.modbus_max_clients) {
      spdlog::warn("event=modbus_refused peer={} reason=max_clients", address);
      engine_.noteError(ErrorCode::kLimit);
      ::close(fd);
      continue;
    }
    auto finished = std::make_shared<std::atomic<bool>>(false);
    const std::string peer_name = address + ":" + std::to_string(ntohs(peer.sin_port));
    clients_.push_back({std::thread([this, fd, peer_name, finished] {
                          serveClient(fd, peer_name);
                          *finished = true;
                        }),
                        finished});
  }
}

void ModbusServer::serveClient(int fd, std::string peer) {
  ++engine_.modbus_clients;
  spdlog::info("event=modbus_connected peer={}", peer);
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", 0);  // the address is unused: the socket is given
  modbus_set_socket(ctx, fd);
  modbus_set_byte_timeout(ctx, 0, 500000);  // a half-written request is dropped after 0.5 s
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  const char* why = "stop";
  while (!stop_) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, kPollMs) <= 0) continue;
    const int length = modbus_receive(ctx, query);
    if (length == 0) continue;  // a request for another unit
    if (length < 0) {
      why = errno == ETIMEDOUT ? "incomplete_request" : "closed";
      break;
    }
    if (!handle(ctx, query, length)) {
      why = "reply_failed";
      break;
    }
  }
  modbus_close(ctx);
  modbus_free(ctx);
  --engine_.modbus_clients;
  spdlog::info("event=modbus_closed peer={} reason={}", peer, why);
}

void ModbusServer::refreshMapping() {
  const HoldingRegisters holding = encodeHolding(engine_.modbusSettings());
  const ModbusStatus status = engine_.modbusStatus();
  const InputRegisters input = encodeInput(status);
  std::copy(holding.begin(), holding.end(), mapping_->tab_registers);
  std::copy(input.begin(), input.end(), mapping_->tab_input_registers);
  mapping_->tab_bits[ModbusMap::kRenderCoil] = engine_.renderTriggerPending() ? 1 : 0;
  mapping_->tab_bits[ModbusMap::kPauseCoil] = status.status == ModbusStatusCode::kPaused ? 1 : 0;
}

std::optional<ProtocolError> ModbusServer::runBatch(std::vector<Command> commands) {
  auto outcome = std::make_shared<std::promise<std::optional<ProtocolError>>>();
  std::future<std::optional<ProtocolError>> result = outcome->get_future();
  if (!engine_.submitBatch(std::move(commands),
                           [outcome](std::optional<ProtocolError> e) { outcome->set_value(e); }))
    return ProtocolError{ErrorCode::kBusy, "the request queue is full"};
  if (result.wait_for(kWriteTimeout) != std::future_status::ready)
    return ProtocolError{ErrorCode::kBusy, "the world thread did not answer in time"};
  return result.get();
}

bool ModbusServer::handle(modbus_t* ctx, const std::uint8_t* query, int length) {
  const int h = modbus_get_header_length(ctx);
  const std::uint8_t function = query[h];
  auto exception = [&](int code, const std::string& message) {
    spdlog::warn("event=modbus_exception function=0x{:02x} code={} message=\"{}\"", function, code,
                 message);
    engine_.noteError(code == kServerDeviceBusy ? ErrorCode::kBusy : ErrorCode::kBadField);
    return modbus_reply_exception(ctx, query, unsigned(code)) >= 0;
  };
  auto reply = [&] {
    std::lock_guard lock(mapping_mutex_);
    refreshMapping();
    return modbus_reply(ctx, query, length, mapping_) >= 0;
  };
  auto applied = [&](std::optional<ProtocolError> error) {
    if (!error) return reply();
    return exception(error->code == ErrorCode::kBusy ? kServerDeviceBusy : kIllegalDataValue,
                     error->message);
  };

  if (function == MODBUS_FC_WRITE_SINGLE_REGISTER ||
      function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS) {
    const int address = be16(query + h + 1);
    std::vector<std::uint16_t> values;
    if (function == MODBUS_FC_WRITE_SINGLE_REGISTER) {
      values.push_back(be16(query + h + 3));
    } else {
      const int count = be16(query + h + 3);
      const int bytes = query[h + 5];
      if (count < 1 || count > MODBUS_MAX_WRITE_REGISTERS || bytes != 2 * count ||
          h + 6 + bytes > length)
        return exception(kIllegalDataValue, "register count and byte count disagree");
      for (int i = 0; i < count; ++i) values.push_back(be16(query + h + 6 + 2 * i));
    }
    HoldingRegisters current;
    {
      std::lock_guard lock(mapping_mutex_);
      current = encodeHolding(engine_.modbusSettings());
    }
    auto decoded = decodeHoldingWrite(current, address, values, engine_.config().modbus_view);
    if (auto* e = std::get_if<RegisterError>(&decoded)) return exception(e->exception, e->message);
    return applied(runBatch(std::move(std::get<std::vector<Command>>(decoded))));
  }
  if (function == MODBUS_FC_WRITE_SINGLE_COIL || function == MODBUS_FC_WRITE_MULTIPLE_COILS) {
    const int address = be16(query + h + 1);
    std::vector<std::uint8_t> bits;
    if (function == MODBUS_FC_WRITE_SINGLE_COIL) {
      const std::uint16_t value = be16(query + h + 3);
      if (value != 0xFF00 && value != 0x0000)
        return exception(kIllegalDataValue, "a coil takes 0xFF00 (on) or 0x0000 (off)");
      bits.push_back(value == 0xFF00);
    } else {
      const int count = be16(query + h + 3);
      const int bytes = query[h + 5];
      if (count < 1 || count > MODBUS_MAX_WRITE_BITS || bytes != (count + 7) / 8 ||
          h + 6 + bytes > length)
        return exception(kIllegalDataValue, "coil count and byte count disagree");
      for (int i = 0; i < count; ++i) bits.push_back((query[h + 6 + i / 8] >> (i % 8)) & 1);
    }
    auto decoded = decodeCoilWrite(address, bits);
    if (auto* e = std::get_if<RegisterError>(&decoded)) return exception(e->exception, e->message);
    const CoilWrite& write = std::get<CoilWrite>(decoded);
    if (write.paused) {
      if (auto error = runBatch({command::SetTime{{}, write.paused, {}}})) return applied(error);
    }
    if (write.render && !engine_.submitRenderTrigger([](std::optional<ProtocolError>) {}))
      return exception(kServerDeviceBusy, "the request queue is full");
    return reply();
  }
  if (function == MODBUS_FC_WRITE_AND_READ_REGISTERS || function == MODBUS_FC_MASK_WRITE_REGISTER)
    return exception(MODBUS_EXCEPTION_ILLEGAL_FUNCTION,
                     "write holding registers with function 0x06 or 0x10");
  return reply();  // reads, and libmodbus's own answers for anything else
}

}  // namespace nephele
