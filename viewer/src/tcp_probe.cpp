// SPDX-License-Identifier: Apache-2.0
#include "tcp_probe.hpp"

#include <linux/sockios.h>
#include <linux/tcp.h>
#include <netinet/in.h>
#include <sys/ioctl.h>
#include <sys/socket.h>

#include <cstddef>

namespace elaslam::viewer {

bool probe_tcp_send(int fd, TcpSendState* out) {
  int queued = 0;
  if (::ioctl(fd, SIOCOUTQ, &queued) != 0 || queued < 0) return false;
  out->unacked = static_cast<std::uint64_t>(queued);
  tcp_info info{};
  socklen_t len = sizeof info;
  if (::getsockopt(fd, IPPROTO_TCP, TCP_INFO, &info, &len) != 0) return false;
  const bool has_acked = len >= offsetof(tcp_info, tcpi_bytes_acked) + sizeof info.tcpi_bytes_acked;
  out->acked = has_acked ? info.tcpi_bytes_acked : 0;
  return true;
}

}  // namespace elaslam::viewer
