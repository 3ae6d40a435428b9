#pragma once
// Modbus TCP for the host simulator, register map in protocol/MODBUS.md, frames decoded by
// protocol/modbus_adu.h. Each client has its own thread, so a slow or half-written request
// holds up only its sender; request and idle timeouts, and room made at the client limit by
// ending connections whose peer has closed them and then the idlest, keep a few clients from
// starving the rest (docs/RELIABILITY.md). Writes are decoded and checked before anything
// changes; a refused one changes nothing.
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "protocol/modbus_adu.h"
#include "protocol/register_map.h"
#include "server/engine.h"

namespace nephele {

class ModbusServer {
 public:
  explicit ModbusServer(Engine& engine);
  ~ModbusServer();
  std::string listen(const ListenConfig& where);
  int port() const { return port_; }
  void close();  // stops accepting, ends every client thread

 private:
  using Clock = std::chrono::steady_clock;
  // What the accept thread knows of a client thread.
  struct ClientState {
    explicit ClientState(int socket) : fd(socket) {}
    // Whether the connection is over: closed by the client thread, which is ending, or by
    // the peer, which the client thread may not have read yet (or not even started).
    bool connectionOver();
    void closeSocket();  // by the client thread, when it ends

    std::atomic<bool> finished{false};
    // Set by the accept thread to make room: why the client must end (nullptr: it need not).
    std::atomic<const char*> end{nullptr};
    std::atomic<bool> mid_request{false};  // part of a frame has arrived
    std::atomic<Clock::rep> last_activity{0};

   private:
    std::mutex fd_mutex;  // the accept thread looks at the socket while the client may close it
    int fd;               // -1 once closed
  };
  struct Client {
    std::thread thread;
    std::shared_ptr<ClientState> state;
  };
  void acceptLoop();
  // At the client limit: ends the clients whose connection is over (closed by the peer), then,
  // if that freed no slot, the one idle longest (at least the request timeout). Call with
  // clients_mutex_ held.
  void makeRoom();
  int activeClients() const;  // not told to end; call with clients_mutex_ held
  void serveClient(int fd, const std::string& peer, ClientState& state);
  // The reply to one decoded request (an exception or the data).
  std::vector<std::uint8_t> answer(const ModbusRequest& request);
  std::vector<std::uint8_t> refuse(const MbapHeader& header, const ModbusException& exception);
  // Runs a write on the world thread and waits for it, at most the request timeout; on
  // timeout the write is withdrawn and answered busy, having changed nothing.
  std::optional<ProtocolError> runBatch(std::vector<Command> commands, bool render);

  Engine& engine_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread accept_thread_;
  std::mutex clients_mutex_;
  std::vector<Client> clients_;
};

}  // namespace nephele
