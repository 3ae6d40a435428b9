#pragma once
// CHECK for broken invariants (programming errors, not user input): prints the failed
// condition with its operands and aborts.
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

namespace nephele::detail {
[[noreturn]] inline void checkFailed(const char* file, int line, const std::string& what) {
  std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", file, line, what.c_str());
  std::fflush(stderr);
  std::abort();
}
}  // namespace nephele::detail

#define NEPHELE_CHECK(condition, message)                                             \
  do {                                                                                \
    if (!(condition)) {                                                               \
      std::ostringstream nephele_check_stream;                                        \
      nephele_check_stream << #condition << " (" << message << ")";                   \
      ::nephele::detail::checkFailed(__FILE__, __LINE__, nephele_check_stream.str()); \
    }                                                                                 \
  } while (false)
