#include "world/file_output.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace nephele {

std::string writeFileAtomically(
    const std::string& path, std::span<const std::uint8_t> bytes, const std::string& what,
    const std::function<std::string(const std::string& temporary)>& verify) {
  const std::string temporary = path + ".partial";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return what + ": cannot create '" + temporary + "': " + std::strerror(errno);
  auto fail = [&](const char* step) {
    const std::string error =
        what + ": " + step + " '" + path + "' failed: " + std::strerror(errno);
    ::close(fd);
    ::unlink(temporary.c_str());
    return error;
  };
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = ENOSPC;
      return fail("writing");
    }
    written += std::size_t(n);
  }
  // A filesystem that allocates late reports a full disk here rather than in write().
  if (::fdatasync(fd) != 0) return fail("flushing");
  if (::close(fd) != 0) {
    const std::string error = what + ": closing '" + path + "' failed: " + std::strerror(errno);
    ::unlink(temporary.c_str());
    return error;
  }
  if (verify)
    if (std::string error = verify(temporary); !error.empty()) {
      ::unlink(temporary.c_str());
      return what + ": '" + path + "' not replaced: what was written does not read back: " + error;
    }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const std::string error =
        what + ": cannot move '" + temporary + "' into place: " + std::strerror(errno);
    ::unlink(temporary.c_str());
    return error;
  }
  return "";
}

}  // namespace nephele
