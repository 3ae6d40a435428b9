#pragma once
// Typed, range-checked reading of TOML tables, shared by scene files and daemon configs.
// Every error names the file, the line, the key and what is allowed.
#include <toml++/toml.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "world/limits.h"

namespace nephele {

struct Camera;

int nameIndex(const std::vector<std::string>& names, std::string_view name);

namespace config_detail {

// Thrown by TableReader and caught at the edge of each file parser; never escapes config/.
struct SceneError {
  std::string message;
};

inline std::string formatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

inline std::string joinKeys(const std::vector<std::string>& keys) {
  std::string out;
  for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
  return out;
}

// Reads one TOML table; every key must be consumed by exactly one typed getter, and
// finish() reports whatever is left as unknown.
class TableReader {
 public:
  TableReader(const toml::table& table, std::string path, const std::string& file)
      : table_(table), path_(std::move(path)), file_(file) {}

  bool has(std::string_view key) const { return table_.contains(key); }

  void number(std::string_view key, double& out, Range range) {
    number(key, out, range.lo, range.hi);
  }
  void number(std::string_view key, double& out, double lo, double hi) {
    const toml::node* node = take(key);
    if (!node) return;
    out = toNumber(*node, key, lo, hi);
  }

  void integer(std::string_view key, int& out, int lo, int hi) {
    const toml::node* node = take(key);
    if (!node) return;
    out = int(toInteger(*node, key, lo, hi));
  }

  void seed(std::string_view key, std::uint64_t& out) {
    const toml::node* node = take(key);
    if (!node) return;
    out = std::uint64_t(toInteger(*node, key, 0, std::numeric_limits<std::int64_t>::max()));
  }

  void boolean(std::string_view key, bool& out) {
    const toml::node* node = take(key);
    if (!node) return;
    if (!node->is_boolean()) fail(*node, key, "must be true or false");
    out = node->value<bool>().value();
  }

  // A string that must be one of `allowed`; returns its index.
  int choice(std::string_view key, const std::vector<std::string>& allowed, int current) {
    const toml::node* node = take(key);
    if (!node) return current;
    if (!node->is_string())
      fail(*node, key, "must be a string (one of: " + joinKeys(allowed) + ")");
    const std::string value = node->value<std::string>().value();
    if (const int index = nameIndex(allowed, value); index >= 0) return index;
    fail(*node, key, "\"" + value + "\" is not allowed (one of: " + joinKeys(allowed) + ")");
  }

  void string(std::string_view key, std::string& out) {
    const toml::node* node = take(key);
    if (!node) return;
    if (!node->is_string()) fail(*node, key, "must be a string");
    out = node->value<std::string>().value();
  }

  // A name, by the one name rule (world/limits.h).
  void name(std::string_view key, std::string& out) {
    const toml::node* node = take(key);
    if (!node) return;
    if (!node->is_string()) fail(*node, key, "must be a string of " + std::string(kNameRule));
    std::string value = node->value<std::string>().value();
    if (std::string e = nameError(value); !e.empty()) fail(*node, key, e);
    out = std::move(value);
  }

  template <int N>
  void vector(std::string_view key, glm::vec<N, double>& out, Range range) {
    vector(key, out, range.lo, range.hi);
  }
  template <int N>
  void vector(std::string_view key, glm::vec<N, double>& out, double lo, double hi) {
    const toml::node* node = take(key);
    if (!node) return;
    const toml::array* array = node->as_array();
    if (!array || array->size() != std::size_t(N))
      fail(*node, key, "must be an array of " + std::to_string(N) + " numbers");
    for (int i = 0; i < N; ++i) out[i] = toNumber(*array->get(std::size_t(i)), key, lo, hi);
  }

  // An array of numbers, each in [lo, hi], of at most `max_count` entries.
  void numbers(std::string_view key, std::vector<double>& out, double lo, double hi,
               std::size_t max_count) {
    const toml::node* node = take(key);
    if (!node) return;
    const toml::array* array = node->as_array();
    if (!array || array->empty() || array->size() > max_count)
      fail(*node, key, "must be an array of 1 to " + std::to_string(max_count) + " numbers");
    out.clear();
    for (const toml::node& v : *array) out.push_back(toNumber(v, key, lo, hi));
  }

  // An array of at most `max_count` strings.
  void strings(std::string_view key, std::vector<std::string>& out, std::size_t max_count) {
    const toml::node* node = take(key);
    if (!node) return;
    const toml::array* array = node->as_array();
    if (!array || array->size() > max_count || !array->is_homogeneous(toml::node_type::string))
      fail(*node, key, "must be an array of at most " + std::to_string(max_count) + " strings");
    out.clear();
    for (const toml::node& v : *array) out.push_back(v.value<std::string>().value());
  }

  // Three integers, each in [lo, hi].
  void integers3(std::string_view key, int (&out)[3], int lo, int hi) {
    const toml::node* node = take(key);
    if (!node) return;
    const toml::array* array = node->as_array();
    if (!array || array->size() != 3) fail(*node, key, "must be an array of 3 integers");
    for (int i = 0; i < 3; ++i) out[i] = int(toInteger(*array->get(std::size_t(i)), key, lo, hi));
  }

  // A sub-table (absent: null). Its reader must be finished by the caller.
  std::optional<TableReader> table(std::string_view key) {
    const toml::node* node = take(key);
    if (!node) return std::nullopt;
    if (!node->is_table()) fail(*node, key, "must be a table");
    return TableReader(*node->as_table(), qualified(key), file_);
  }

  // An array of tables ([[key]]).
  std::vector<TableReader> tables(std::string_view key) {
    std::vector<TableReader> out;
    const toml::node* node = take(key);
    if (!node) return out;
    const toml::array* array = node->as_array();
    if (!array || !array->is_array_of_tables())
      fail(*node, key, "must be an array of tables, written [[" + std::string(key) + "]]");
    for (std::size_t i = 0; i < array->size(); ++i)
      out.emplace_back(*array->get(i)->as_table(), qualified(key) + "[" + std::to_string(i) + "]",
                       file_);
    return out;
  }

  // Rejects a key that is present but does not apply here.
  void forbid(std::string_view key, const std::string& why) {
    if (const toml::node* node = table_.get(key)) fail(*node, key, why);
  }

  void finish() const {
    for (auto&& [key, node] : table_) {
      if (taken_.count(std::string(key.str()))) continue;
      fail(node, key.str(), "unknown key (allowed here: " + joinKeys(allowed_) + ")");
    }
  }

  // Declares the keys this table accepts, for the unknown-key message.
  void allow(std::vector<std::string> keys) { allowed_ = std::move(keys); }

  [[noreturn]] void failAt(std::string_view key, const std::string& what) const {
    fail(*table_.get(key), key, what);
  }

  // An error about the table as a whole (a missing key, a missing part).
  [[noreturn]] void failHere(const std::string& what) const {
    throw SceneError{file_ + ":" + std::to_string(table_.source().begin.line) + ": " +
                     (path_.empty() ? std::string("scene") : path_) + ": " + what};
  }

  [[noreturn]] void fail(const toml::node& node, std::string_view key,
                         const std::string& what) const {
    throw SceneError{file_ + ":" + std::to_string(node.source().begin.line) + ": " +
                     qualified(key) + ": " + what};
  }

 private:
  const toml::node* take(std::string_view key) {
    taken_.insert(std::string(key));
    return table_.get(key);
  }

  std::string qualified(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  }

  double toNumber(const toml::node& node, std::string_view key, double lo, double hi) const {
    if (!node.is_number()) fail(node, key, "must be a number");
    const double v = node.value<double>().value();
    if (!std::isfinite(v))
      fail(node, key,
           formatNumber(v) + " is not a finite number (allowed: " + formatNumber(lo) + " to " +
               formatNumber(hi) + ")");
    if (v < lo || v > hi)
      fail(node, key,
           formatNumber(v) + " is out of range (allowed: " + formatNumber(lo) + " to " +
               formatNumber(hi) + ")");
    return v;
  }

  std::int64_t toInteger(const toml::node& node, std::string_view key, std::int64_t lo,
                         std::int64_t hi) const {
    if (!node.is_integer()) fail(node, key, "must be an integer");
    const std::int64_t v = node.value<std::int64_t>().value();
    if (v < lo || v > hi)
      fail(node, key,
           std::to_string(v) + " is out of range (allowed: " + std::to_string(lo) + " to " +
               std::to_string(hi) + ")");
    return v;
  }

  const toml::table& table_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> taken_;
  std::vector<std::string> allowed_;
};

// Reads a whole file into `text`; on failure returns "cannot read WHAT 'path': reason".
// TOML (1.0) allows characters beyond ASCII only inside strings and comments. toml++ 3.3,
// the version Debian 12 ships, reaches a __builtin_unreachable (undefined behaviour) when
// classifying some of them elsewhere, so such text is refused here, before it is parsed.
// Returns "" or "LINE: what is wrong".
inline std::string tomlAsciiError(std::string_view text) {
  enum class In { kCode, kComment, kBasic, kLiteral, kMultiBasic, kMultiLiteral } in = In::kCode;
  int line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const std::string_view rest = text.substr(i);
    if (c == '\n') {
      ++line;
      if (in == In::kComment || in == In::kBasic || in == In::kLiteral) in = In::kCode;
      continue;
    }
    switch (in) {
      case In::kCode:
        if (static_cast<unsigned char>(c) >= 0x80)
          return std::to_string(line) +
                 ": a character beyond ASCII outside a string or comment (allowed there: "
                 "ASCII only)";
        if (c == '#') in = In::kComment;
        // A quote opens a string only where a key or value may start; elsewhere (straight
        // after a bare word or number) toml++ reads it as part of a malformed token, reading
        // ahead to the next whitespace, so what follows stays code here too.
        if ((c == '"' || c == '\'') && i > 0 &&
            std::string_view(" \t\r\n=[,{.").find(text[i - 1]) == std::string_view::npos)
          break;
        if (rest.starts_with("\"\"\"")) {
          in = In::kMultiBasic;
          i += 2;
        } else if (rest.starts_with("'''")) {
          in = In::kMultiLiteral;
          i += 2;
        } else if (c == '"') {
          in = In::kBasic;
        } else if (c == '\'') {
          in = In::kLiteral;
        }
        break;
      case In::kComment:
        break;
      case In::kBasic:
        if (c == '\\')
          ++i;
        else if (c == '"')
          in = In::kCode;
        break;
      case In::kLiteral:
        if (c == '\'') in = In::kCode;
        break;
      case In::kMultiBasic:
        if (c == '\\')
          ++i;
        else if (rest.starts_with("\"\"\""))
          in = In::kCode, i += 2;
        break;
      case In::kMultiLiteral:
        if (rest.starts_with("'''")) in = In::kCode, i += 2;
        break;
    }
  }
  return "";
}

// Reads a whole text file: only a regular file (a directory, FIFO or device is refused,
// never waited on) of at most Limits::kMaxTextFileBytes.
inline std::string readTextFile(const std::string& path, const char* what, std::string& text) {
  auto failure = [&](const std::string& why) {
    return std::string("cannot read ") + what + " '" + path + "': " + why;
  };
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return failure(std::strerror(errno));
  struct stat st {};
  std::string error;
  if (::fstat(fd, &st) != 0)
    error = std::strerror(errno);
  else if (!S_ISREG(st.st_mode))
    error = "not a regular file";
  else if (std::uint64_t(st.st_size) > Limits::kMaxTextFileBytes)
    error = std::to_string(st.st_size) + " bytes (allowed: at most " +
            std::to_string(Limits::kMaxTextFileBytes) + ")";
  std::string contents;
  if (error.empty()) {
    contents.resize(std::size_t(st.st_size));
    std::size_t got = 0;
    while (got < contents.size()) {
      const ssize_t n = ::read(fd, contents.data() + got, contents.size() - got);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      got += std::size_t(n);
    }
    if (got != contents.size()) error = "the file changed size while it was read";
  }
  ::close(fd);
  if (!error.empty()) return failure(error);
  text = std::move(contents);
  return "";
}

// The camera keys shared by a scene's [camera] and a daemon's [[view]]: position, heading,
// pitch, roll, vfov.
void readCameraKeys(TableReader& t, Camera& camera);

}  // namespace config_detail
}  // namespace nephele
