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
#include <cstdio>
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

  // A number (an integer where `integer`) for the caller's own check; absent: nothing.
  // `allowed` completes the message of a value of another type.
  std::optional<double> numberToCheck(std::string_view key, bool integer,
                                      const std::string& allowed) {
    const toml::node* node = take(key);
    if (!node) return std::nullopt;
    if (integer ? !node->is_integer() : !node->is_number())
      fail(*node, key,
           std::string(integer ? "must be an integer" : "must be a number") +
               " (allowed: " + allowed + ")");
    if (const auto* i = node->as_integer()) {
      if (!heldExactly(i->get()))
        fail(*node, key,
             std::to_string(i->get()) + " cannot be held exactly (allowed: " + allowed + ")");
      return double(i->get());
    }
    return node->as_floating_point()->get();
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
    out = node->as_boolean()->get();
  }

  // A string that must be one of `allowed`; returns its index.
  int choice(std::string_view key, const std::vector<std::string>& allowed, int current) {
    const toml::node* node = take(key);
    if (!node) return current;
    if (!node->is_string())
      fail(*node, key, "must be a string (one of: " + joinKeys(allowed) + ")");
    const std::string& value = node->as_string()->get();
    if (const int index = nameIndex(allowed, value); index >= 0) return index;
    fail(*node, key, "\"" + value + "\" is not allowed (one of: " + joinKeys(allowed) + ")");
  }

  void string(std::string_view key, std::string& out) {
    const toml::node* node = take(key);
    if (!node) return;
    if (!node->is_string()) fail(*node, key, "must be a string");
    out = node->as_string()->get();
  }

  // A name, by the one name rule (world/limits.h).
  void name(std::string_view key, std::string& out) {
    const toml::node* node = take(key);
    if (!node) return;
    if (!node->is_string()) fail(*node, key, "must be a string of " + std::string(kNameRule));
    std::string value = node->as_string()->get();
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
    for (const toml::node& v : *array) out.push_back(v.as_string()->get());
  }

  // A range to draw from: a number (fixed) or [low, high], each in `range`, low <= high.
  void span(std::string_view key, double& lo, double& hi, Range range) {
    const toml::node* node = take(key);
    if (!node) return;
    if (node->is_number()) {
      lo = hi = toNumber(*node, key, range.lo, range.hi);
      return;
    }
    const toml::array* array = node->as_array();
    if (!array || array->size() != 2)
      fail(*node, key,
           "must be a number or an array [low, high] (each " + formatNumber(range.lo) + " to " +
               formatNumber(range.hi) + ")");
    const double a = toNumber(*array->get(0), key, range.lo, range.hi);
    const double b = toNumber(*array->get(1), key, range.lo, range.hi);
    if (a > b)
      fail(*node, key,
           "the low end " + formatNumber(a) + " is above the high end " + formatNumber(b));
    lo = a, hi = b;
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
    if (const auto* integer = node.as_integer(); integer && !heldExactly(integer->get()))
      fail(node, key,
           std::to_string(integer->get()) + " cannot be held exactly (allowed: " +
               formatNumber(lo) + " to " + formatNumber(hi) + ")");
    const double v =
        node.is_integer() ? double(node.as_integer()->get()) : node.as_floating_point()->get();
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
    if (!node.is_integer())
      fail(
          node, key,
          "must be an integer (allowed: " + std::to_string(lo) + " to " + std::to_string(hi) + ")");
    const std::int64_t v = node.as_integer()->get();
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

// toml++ 3.3, the version Debian 12 ships, reaches a __builtin_unreachable (undefined
// behaviour) when it asks whether a character in U+00A1-U+0499, U+2C5E-U+2FFF, U+3001-U+3057 or
// U+FB26-U+FEFE is whitespace: a gap in its generated table. It asks that of every character
// it meets outside strings and comments (also while reading ahead through a malformed token,
// quotes included), and inside a multi-line basic string of the first character after a
// line-ending backslash. parseToml below (its steps in toml_gap) keeps every such character
// from reaching those questions, with the parser itself, not a second grammar, deciding what is
// inside a string:
//   1. Text that is all ASCII is parsed directly.
//   2. Otherwise a copy with each character beyond ASCII replaced by '@' is parsed. '@' is
//      valid TOML only inside strings and comments, so if the copy parses, every such
//      character of the original lies inside a string or a comment, and the document is
//      valid TOML. If the copy fails, its error is the original's, reported with the
//      character it names.
//   3. In the now valid document, a character of the gap straight after a line-ending
//      backslash (and the whitespace it skips) is refused: write it as \uXXXX there.
//   4. The original is parsed.
namespace toml_gap {

[[noreturn]] inline void failAt(const std::string& file, int line, const std::string& what) {
  throw SceneError{file + ":" + std::to_string(line) + ": " + what};
}

[[noreturn]] inline void failInvalid(const std::string& file, const toml::parse_error& e) {
  failAt(file, int(e.source().begin.line), "not valid TOML: " + std::string(e.description()));
}

// Decodes one UTF-8 sequence at text[i]; 0 and length 1 for a malformed one, which is left
// for toml++ to report.
inline char32_t decodeUtf8(std::string_view text, std::size_t i, std::size_t& length) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b0 = byte(i);
  length = b0 >= 0xF0 ? 4 : b0 >= 0xE0 ? 3 : b0 >= 0xC0 ? 2 : 1;
  if (length == 1 || i + length > text.size()) return length = 1, 0;
  char32_t c = b0 & (0x7F >> length);
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return length = 1, 0;
    c = (c << 6) | (byte(i + k) & 0x3F);
  }
  return c;
}

// The characters toml++ 3.3's whitespace table lacks.
inline bool inGap(char32_t c) {
  return (c >= 0xA1 && c <= 0x499) || (c >= 0x2C5E && c <= 0x2FFF) ||
         (c >= 0x3001 && c <= 0x3057) || (c >= 0xFB26 && c <= 0xFEFE);
}

inline std::string codePoint(char32_t c) {  // "U+00E9"
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "U+%04X", unsigned(c));
  return std::string(buffer);
}

// Step 2's copy, one byte per character: each character beyond ASCII is '@'.
struct AsciiCopy {
  std::string ascii;
  std::vector<std::pair<std::size_t, char32_t>> replaced;  // (offset in ascii, character)
};

inline AsciiCopy asciiCopyOf(std::string_view text) {
  AsciiCopy copy;
  copy.ascii.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    std::size_t length = 1;
    const char32_t c = static_cast<unsigned char>(text[i]) < 0x80 ? 0 : decodeUtf8(text, i, length);
    if (c == 0) {
      copy.ascii += text[i];
    } else {
      copy.replaced.emplace_back(copy.ascii.size(), c);
      copy.ascii += '@';
    }
    i += length;
  }
  return copy;
}

// Step 2: the copy parses, else the original's error, naming the replaced character toml++
// stopped at (by line and column, 1-based, one per byte in the copy) if it is one.
inline void checkAsciiCopy(const AsciiCopy& copy, const std::string& file) {
  try {
    (void)toml::parse(copy.ascii, file);
  } catch (const toml::parse_error& e) {
    std::size_t offset = 0;
    for (std::size_t line = 1; line < e.source().begin.line && offset < copy.ascii.size(); ++offset)
      if (copy.ascii[offset] == '\n') ++line;
    offset += e.source().begin.column - 1;
    for (const auto& [at, c] : copy.replaced)
      if (at == offset)
        failAt(file, int(e.source().begin.line),
               "the character " + codePoint(c) +
                   " is outside a string or comment (TOML allows only ASCII there)");
    failInvalid(file, e);
  }
}

// Step 3, at the backslash ascii[i] of a multi-line basic string followed by whitespace: the
// whitespace skipped (counting its lines), and a character of the gap after it refused.
// Returns the index of the last character skipped.
inline std::size_t skipLineEndingBackslash(const AsciiCopy& copy, std::size_t i, int& line,
                                           const std::string& file) {
  const std::string& ascii = copy.ascii;
  std::size_t k = i + 1;
  for (; k < ascii.size() && std::string_view(" \t\r\n").find(ascii[k]) != std::string_view::npos;
       ++k)
    if (ascii[k] == '\n') ++line;
  for (const auto& [at, cp] : copy.replaced)
    if (at == k && inGap(cp))
      failAt(file, line,
             "the character " + codePoint(cp) +
                 " straight after a line-ending backslash cannot be read by this build's TOML "
                 "parser (toml++ 3.3); write it as \\u" +
                 codePoint(cp).substr(2) + " there");
  return k - 1;
}

// Step 3: a small scanner is enough, the document being valid TOML.
inline void checkLineEndingBackslashes(const AsciiCopy& copy, const std::string& file) {
  const std::string& ascii = copy.ascii;
  int line = 1;
  enum class In { kCode, kComment, kBasic, kLiteral, kMultiBasic, kMultiLiteral } in = In::kCode;
  for (std::size_t i = 0; i < ascii.size(); ++i) {
    const char c = ascii[i];
    const std::string_view rest = std::string_view(ascii).substr(i);
    if (c == '\n') {
      ++line;
      if (in == In::kComment) in = In::kCode;
      continue;
    }
    switch (in) {
      case In::kCode:
        if (c == '#') in = In::kComment;
        if (rest.starts_with("\"\"\"") || rest.starts_with("'''")) {
          in = c == '"' ? In::kMultiBasic : In::kMultiLiteral;
          i += 2;
        } else if (c == '"' || c == '\'') {
          in = c == '"' ? In::kBasic : In::kLiteral;
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
        if (c == '\\' && i + 1 < ascii.size() &&
            std::string_view(" \t\r\n").find(ascii[i + 1]) != std::string_view::npos) {
          i = skipLineEndingBackslash(copy, i, line, file);
        } else if (c == '\\') {
          ++i;
        } else if (rest.starts_with("\"\"\"")) {
          // Up to two more quotes may close the string: """"" ends with the content "".
          while (i + 3 < ascii.size() && ascii[i + 3] == '"') ++i;
          in = In::kCode, i += 2;
        }
        break;
      case In::kMultiLiteral:
        if (rest.starts_with("'''")) {
          while (i + 3 < ascii.size() && ascii[i + 3] == '\'') ++i;
          in = In::kCode, i += 2;
        }
        break;
    }
  }
}

}  // namespace toml_gap

// The table `text` holds, read past toml++ 3.3's gap (above). Throws SceneError
// ("FILE:LINE: what is wrong").
inline toml::table parseToml(std::string_view text, const std::string& file) {
  const toml_gap::AsciiCopy copy = toml_gap::asciiCopyOf(text);
  if (!copy.replaced.empty()) {
    toml_gap::checkAsciiCopy(copy, file);
    toml_gap::checkLineEndingBackslashes(copy, file);
  }
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    toml_gap::failInvalid(file, e);
  }
}

// Reads a whole text file into `text`; on failure returns "cannot read WHAT 'path': reason".
// Only a regular file (a directory, FIFO or device is refused,
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
