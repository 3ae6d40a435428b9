#pragma once
// What a listener can learn of a TCP connection's peer without reading from the socket.
#include <poll.h>

namespace nephele {

// Whether the peer of connection `fd` has closed it, or at least its sending side, or reset
// it: no further request can come. Bytes it sent before may still wait unread (they are not
// looked at). Also true once this side has shut down reading, which callers must tell apart.
inline bool peerHasClosed(int fd) {
  pollfd p{fd, POLLRDHUP, 0};
  return ::poll(&p, 1, 0) > 0 && (p.revents & (POLLRDHUP | POLLHUP | POLLERR)) != 0;
}

}  // namespace nephele
