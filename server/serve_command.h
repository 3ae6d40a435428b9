#pragma once
// `nephele serve --config FILE`: the daemon.
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace nephele {

struct ServeCommandOptions {
  std::string config_path;
  std::optional<int> socket_port, modbus_port, metrics_port;
  std::optional<std::string> snapshot_path;
};

void addServeCommand(CLI::App& app, ServeCommandOptions& options);

// Runs until SIGTERM or SIGINT; returns the process exit code (0 clean, 2 bad config,
// 1 failure).
int runServeCommand(const ServeCommandOptions& options);

}  // namespace nephele
