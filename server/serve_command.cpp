#include "server/serve_command.h"

#include <signal.h>

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <cstdio>
#include <thread>

#include "server/cigi_server.h"
#include "server/daemon_config.h"
#include "server/engine.h"
#include "server/modbus_server.h"
#include "server/socket_server.h"

namespace nephele {

void addServeCommand(CLI::App& app, ServeCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "serve", "Run the image generator daemon (socket protocol and Modbus TCP)");
  cmd->add_option("-c,--config", o.config_path, "Daemon config file (TOML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--socket-port", o.socket_port, "Socket protocol port (0: any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--modbus-port", o.modbus_port, "Modbus TCP port (0: any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--metrics-port", o.metrics_port,
                  "Prometheus metrics port (0: any free port); turns metrics on")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--snapshot", o.snapshot_path,
                  "Snapshot file: restored at start if present, saved periodically and at exit");
}

namespace {

// SIGTERM and SIGINT, blocked before any thread starts so that every thread inherits the mask;
// runServeCommand takes them with sigwait.
sigset_t blockStopSignals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);  // a vanished client is a write error, not a dead daemon
  return signals;
}

// The daemon config file, with the command line's ports and snapshot over it.
std::string loadServeConfig(const ServeCommandOptions& o, DaemonConfig& config) {
  if (std::string error = loadDaemonConfig(o.config_path, config); !error.empty()) return error;
  if (o.socket_port) config.socket.port = *o.socket_port;
  if (o.modbus_port) config.modbus.port = *o.modbus_port;
  if (o.metrics_port) {
    config.metrics.port = *o.metrics_port;
    config.metrics_enabled = true;
  }
  if (o.snapshot_path) config.snapshot_path = *o.snapshot_path;
  return "";
}

// With systemd's WatchdogSec, a thread that beats every half period while the world thread
// keeps going round its loop, until `stopping`; without it, no thread.
std::thread startWatchdog(const Engine& engine, const std::atomic<bool>& stopping) {
  std::uint64_t watchdog_us = 0;
  if (sd_watchdog_enabled(0, &watchdog_us) <= 0) return {};
  return std::thread([&engine, &stopping, watchdog_us] {
    const auto period = std::chrono::microseconds(watchdog_us / 2);
    while (!stopping) {
      if (engine.telemetry().heartbeatAge() < double(watchdog_us) * 1e-6)
        sd_notify(0, "WATCHDOG=1");
      std::this_thread::sleep_for(
          std::min<std::chrono::microseconds>(period, std::chrono::milliseconds(200)));
    }
  });
}

}  // namespace

int runServeCommand(const ServeCommandOptions& o) {
  const sigset_t signals = blockStopSignals();
  DaemonConfig config;
  if (std::string error = loadServeConfig(o, config); !error.empty()) {
    spdlog::error("{}", error);
    return 2;
  }

  Engine engine(config);
  if (std::string error = engine.start(); !error.empty()) {
    spdlog::error("{}", error);
    return 1;
  }
  asio::io_context io;
  SocketServer socket(io, engine);
  MetricsServer metrics(io, engine);
  ModbusServer modbus(engine);
  CigiServer cigi(io, engine);
  std::string error;
  if (config.socket_enabled) error = socket.listen(config.socket);
  if (error.empty() && config.metrics_enabled) error = metrics.listen(config.metrics);
  if (error.empty() && config.modbus_enabled) error = modbus.listen(config.modbus);
  if (error.empty() && config.cigi.enabled) error = cigi.listen(config.cigi);
  if (!error.empty()) {
    spdlog::error("{}", error);
    modbus.close();
    engine.stop();
    return 1;
  }
  auto work = asio::make_work_guard(io);
  std::thread io_thread([&io] { io.run(); });

  // The ready line: tests and supervisors read the ports from it.
  std::printf("nephele ready socket=%d modbus=%d metrics=%d cigi=%d\n",
              config.socket_enabled ? socket.port() : -1,
              config.modbus_enabled ? modbus.port() : -1,
              config.metrics_enabled ? metrics.port() : -1, config.cigi.enabled ? cigi.port() : -1);
  std::fflush(stdout);
  // systemd (Type=notify): ready now; with WatchdogSec, a beat every half period while the
  // world thread keeps going round its loop. Without systemd these do nothing.
  sd_notifyf(0, "READY=1\nSTATUS=serving socket %d modbus %d cigi %d",
             config.socket_enabled ? socket.port() : -1, config.modbus_enabled ? modbus.port() : -1,
             config.cigi.enabled ? cigi.port() : -1);
  std::atomic<bool> stopping{false};
  std::thread watchdog = startWatchdog(engine, stopping);
  spdlog::info("event=listening socket={}:{} modbus={}:{} metrics={}", config.socket.bind,
               socket.port(), config.modbus.bind, modbus.port(),
               config.metrics_enabled ? std::to_string(metrics.port()) : "off");

  int received = 0;
  sigwait(&signals, &received);
  spdlog::info("event=stopping signal={}", received == SIGTERM ? "SIGTERM" : "SIGINT");
  sd_notify(0, "STOPPING=1");
  stopping = true;
  if (watchdog.joinable()) watchdog.join();
  modbus.close();
  // A render in hand is cancelled at its next batch boundary, other requests in hand finish,
  // queued ones are answered "shutting down", the snapshot is saved. Then each connection
  // writes out what it was sent (docs/RELIABILITY.md).
  const bool saved = engine.stop();
  asio::post(io, [&] {
    socket.close();
    metrics.close();
    cigi.close();
  });
  work.reset();
  io_thread.join();
  if (!saved) {
    // A supervisor must know that the world's state was lost.
    spdlog::error("event=stopped error=\"the shutdown snapshot could not be saved\"");
    return 1;
  }
  spdlog::info("event=stopped");
  return 0;
}

}  // namespace nephele
