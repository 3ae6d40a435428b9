#pragma once
// Modbus TCP (libmodbus) for the host simulator, register map in protocol/MODBUS.md. Each
// client has its own thread, so a slow or half-written request holds up only its sender.
// Writes are decoded and checked before anything changes; a bad one gets an exception.
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/engine.h"

typedef struct _modbus modbus_t;
typedef struct _modbus_mapping_t modbus_mapping_t;

namespace nephele {

class ModbusServer {
 public:
  explicit ModbusServer(Engine& engine);
  ~ModbusServer();
  std::string listen(const ListenConfig& where);
  int port() const { return port_; }
  void close();  // stops accepting, ends every client thread

 private:
  struct Client {
    std::thread thread;
    std::shared_ptr<std::atomic<bool>> finished;
  };
  void acceptLoop();
  void serveClient(int fd, std::string peer);
  // Answers one request; false when the connection should close.
  bool handle(modbus_t* ctx, const std::uint8_t* query, int length);
  std::optional<ProtocolError> runBatch(std::vector<Command> commands);
  void refreshMapping();  // from the engine's published state; call with mapping_mutex_ held

  Engine& engine_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread accept_thread_;
  std::mutex clients_mutex_;
  std::vector<Client> clients_;
  std::mutex mapping_mutex_;
  modbus_mapping_t* mapping_ = nullptr;
};

}  // namespace nephele
