// nephele: headless cloud image generator.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>

#include "cli/bench_command.h"
#include "cli/dataset_command.h"
#include "cli/knobs_command.h"
#include "cli/render_command.h"
#include "server/serve_command.h"

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("nephele"));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ %v");

  CLI::App app("Nephele: headless cloud image generator for simulators");
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "Log level")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->capture_default_str();
  nephele::RenderCommandOptions render;
  nephele::addRenderCommand(app, render);
  nephele::ServeCommandOptions serve;
  nephele::addServeCommand(app, serve);
  nephele::BenchCommandOptions bench;
  nephele::addBenchCommand(app, bench);
  nephele::DatasetCommandOptions dataset;
  nephele::addDatasetCommand(app, dataset);
  nephele::KnobsCommandOptions knobs;
  nephele::addKnobsCommand(app, knobs);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every bad flag or missing file exits with the documented
    // status 2, not the command-line library's own codes.
    return app.exit(e) == 0 ? 0 : 2;
  }
  spdlog::set_level(spdlog::level::from_str(log_level));
  if (app.got_subcommand("render")) return nephele::runRenderCommand(render);
  if (app.got_subcommand("serve")) return nephele::runServeCommand(serve);
  if (app.got_subcommand("bench")) return nephele::runBenchCommand(bench);
  if (app.got_subcommand("dataset")) return nephele::runDatasetCommand(dataset);
  if (app.got_subcommand("knobs")) return nephele::runKnobsCommand(knobs);
  return 2;
}
