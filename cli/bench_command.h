#pragma once
// `nephele bench`: every quality knob's error against the CPU reference and its run time, on
// a fixed set of scenes, with the platform floor timed in the same run (docs/ACCURACY.md).
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace nephele {

struct BenchCommandOptions {
  bool quick = false;               // small images, few repeats: under two minutes
  std::string size;                 // WxH; default 640x480 (quick: 200x150)
  int repeats = 0;                  // timed frames per setting; default 7 (quick: 3)
  int samples = 0;                  // reference supersampling per axis; default 4 (quick: 2)
  std::vector<std::string> scenes;  // a subset of the scene names; empty: all
  std::string output_dir = "bench-results";
  std::string gl_backend = "auto";
};

void addBenchCommand(CLI::App& app, BenchCommandOptions& options);

// Runs the sweep; returns the process exit code (0 ok, 2 bad input, 1 failure).
int runBenchCommand(const BenchCommandOptions& options);

}  // namespace nephele
