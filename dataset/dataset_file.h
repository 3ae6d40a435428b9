#pragma once
// Dataset descriptions (TOML, docs/DATASETS.md) to a DatasetSpec. Every error names the file,
// the line, the key and what is allowed; nothing is drawn from a description that fails.
#include <string>
#include <string_view>

#include "dataset/dataset.h"

namespace nephele {

// Empty on success, else "FILE:LINE: key: what is wrong (allowed: ...)". Mesh paths are
// relative to the description's directory.
std::string parseDatasetText(std::string_view text, const std::string& source_name,
                             DatasetSpec& out);
std::string loadDatasetFile(const std::string& path, DatasetSpec& out);

}  // namespace nephele
