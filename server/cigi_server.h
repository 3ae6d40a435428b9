#pragma once
// CIGI 3.3 over UDP (docs/CIGI.md): host messages arrive on [cigi] ig_port, are decoded
// (protocol/cigi.h), mapped to commands (protocol/cigi_session.h) and applied by the Engine
// as one batch; Start of Frame goes back to the sender's address at [cigi] host_port, for
// each host frame in synchronous (lockstep) mode, for each IG frame in asynchronous (realtime).
// Messages are handled one at a time, in arrival order; a refused one changes nothing and is
// counted by reason in the daemon's stats.
#include <asio.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "protocol/cigi.h"
#include "protocol/cigi_session.h"
#include "server/engine.h"

namespace nephele {

class CigiServer {
 public:
  CigiServer(asio::io_context& io, Engine& engine);
  std::string listen(const CigiConfig& config);
  int port() const { return port_; }
  void close();

 private:
  struct Datagram {
    std::vector<std::uint8_t> bytes;
    asio::ip::udp::endpoint from;
  };
  void receive();
  void next();  // handles the oldest waiting datagram, if none is in hand
  void refuse(const std::string& reason, const std::string& message,
              const asio::ip::udp::endpoint& from);
  // The answer to the host frame of `control`; `status` is a cigi::IgStatus code. Synchronous
  // (lockstep) mode: its Start of Frame now. Asynchronous (realtime): the next IG frame's.
  void answer(const cigi::IgControl& control, cigi::ByteOrder order,
              const asio::ip::udp::endpoint& from, std::uint8_t status);
  void igFrame();  // an IG frame has started (the Engine's frame listener)
  void sendStartOfFrame(const cigi::IgControl& control, cigi::ByteOrder order,
                        const asio::ip::udp::endpoint& to, std::uint8_t status);

  asio::io_context& io_;
  Engine& engine_;
  asio::ip::udp::socket socket_;
  int port_ = 0;
  int host_port_ = 0;
  std::array<std::uint8_t, 65536> buffer_{};
  asio::ip::udp::endpoint sender_;
  std::deque<Datagram> waiting_;
  bool busy_ = false;  // a message is with the Engine
  bool closed_ = false;
  cigi::Session session_;
  std::uint32_t ig_frame_ = 0;
  struct Handled {
    cigi::IgControl control;
    cigi::ByteOrder order;
    asio::ip::udp::endpoint from;
    std::uint8_t status;
  };
  std::optional<Handled> last_handled_;  // asynchronous mode: what the next IG frame reports
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
};

}  // namespace nephele
