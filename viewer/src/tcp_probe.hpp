// SPDX-License-Identifier: Apache-2.0
// What the kernel shows of a TCP socket's send side, for the event streams' stall
// check (ReadProgress, include/elaslam/viewer/stream_slots.hpp). Its own file: the
// kernel's <linux/tcp.h>, whose struct tcp_info has tcpi_bytes_acked, cannot be
// included beside glibc's <netinet/tcp.h> (httplib's).
#pragma once

#include <cstdint>

namespace elaslam::viewer {

struct TcpSendState {
  std::uint64_t unacked = 0;  ///< bytes queued that the peer has not acknowledged (SIOCOUTQ)
  std::uint64_t acked = 0;    ///< bytes the peer has acknowledged since the connection began
};

/// false when the kernel does not say (not a TCP socket; a kernel before 4.1 has no
/// tcpi_bytes_acked: then `acked` stays 0 and only an empty queue counts as progress).
bool probe_tcp_send(int fd, TcpSendState* out);

}  // namespace elaslam::viewer
