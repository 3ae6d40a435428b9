#pragma once
// `nephele dataset SPEC -o DIR`: a labelled cloud-clutter dataset (docs/DATASETS.md).
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "image/image_encoding.h"

namespace nephele {

struct DatasetCommandOptions {
  std::string spec_path;
  std::string output_dir;
  std::string renderer = "gl";  // or "reference"
  std::string gl_backend = "auto";
  bool resume = false;
  std::string shard;          // "I/N"
  std::optional<int> shards;  // N, with I from JOB_COMPLETION_INDEX or SLURM_ARRAY_TASK_ID
  bool merge_only = false;    // build annotations.json and manifest.jsonl, render nothing
  std::vector<int> only;      // render just these sample indices
  int channel_divisor = 1;    // cloud depth traced per N x N block
  EncodeOptions encode{1};    // PNG zlib level 1: about 25 % faster than 6
};

void addDatasetCommand(CLI::App& app, DatasetCommandOptions& options);
int runDatasetCommand(const DatasetCommandOptions& options);

}  // namespace nephele
