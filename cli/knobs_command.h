#pragma once
// `nephele knobs`: the documents generated from the render knobs' table
// (renderer/render_knobs.inc): README.md's [render] block, or with --markdown
// docs/ACCURACY.md's knob table. tests/render_knobs_test.cpp fails while either differs.
#include <string>

#include <CLI/CLI.hpp>

namespace nephele {

struct KnobsCommandOptions {
  bool markdown = false;
  // The document whose knob table holds the measured columns kept in the generated one.
  std::string measured_from = NEPHELE_SOURCE_DIR "/docs/ACCURACY.md";
};

void addKnobsCommand(CLI::App& app, KnobsCommandOptions& options);

// Prints the document; returns the process exit code (0 ok, 1 when --measured cannot be read).
int runKnobsCommand(const KnobsCommandOptions& options);

}  // namespace nephele
