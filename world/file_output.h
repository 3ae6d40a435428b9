#pragma once
// Writing a whole file so that readers see either the old file or the complete new one:
// the bytes go to a temporary beside the target, are flushed to the disk, and only then
// renamed into place. On any failure (a full disk, a read-only directory, a file-size limit)
// the temporary is removed and the error names the path and the cause.
#include <cstdint>
#include <functional>
#include <span>
#include <string>

namespace nephele {

// Returns "" on success, else the error (starting with `what`, e.g. "snapshot"). `verify`, if
// given, reads the flushed temporary (its path is the argument) before it is renamed into place
// and returns "" or why it does not read back; then the temporary is removed and `path` keeps
// what it held.
std::string writeFileAtomically(
    const std::string& path, std::span<const std::uint8_t> bytes, const std::string& what,
    const std::function<std::string(const std::string& temporary)>& verify = {});

}  // namespace nephele
