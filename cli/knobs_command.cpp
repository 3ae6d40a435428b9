#include "cli/knobs_command.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>
#include <iterator>

#include "renderer/render_knobs.h"

namespace nephele {

void addKnobsCommand(CLI::App& app, KnobsCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "knobs",
      "Print the render knobs as README.md's [render] block, or as docs/ACCURACY.md's table");
  cmd->add_flag("--markdown", o.markdown, "docs/ACCURACY.md's knob table instead");
  cmd->add_option("--measured", o.measured_from,
                  "With --markdown: the document whose table's measured columns are kept")
      ->capture_default_str();
}

int runKnobsCommand(const KnobsCommandOptions& o) {
  if (!o.markdown) {
    std::fputs(knobsToml().c_str(), stdout);
    return 0;
  }
  std::ifstream in(o.measured_from);
  if (!in) {
    spdlog::error("--measured: cannot read '{}'", o.measured_from);
    return 1;
  }
  const std::string document(std::istreambuf_iterator<char>(in), {});
  std::fputs(knobsMarkdown(measuredKnobColumns(document)).c_str(), stdout);
  return 0;
}

}  // namespace nephele
