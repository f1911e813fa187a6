// SPDX-License-Identifier: Apache-2.0
#include "elaslam/viewer/http_guard.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <cctype>

namespace elaslam::viewer {
namespace {

bool name_is(std::string_view name, std::string_view lower) {
  if (name.size() != lower.size()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(name[i])) != lower[i]) return false;
  }
  return true;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

}  // namespace

HeadVerdict HeadScan::scan(std::string_view data) {
  for (; !head_done_ && seen_ < data.size(); ++seen_) {
    if (data[seen_] != '\n') continue;
    // The head's size is checked line by line, so a head that arrives whole in one
    // read is bounded as one that trickles in.
    if (seen_ + 1 > limits_.max_head_bytes) return refuse(431, "the request head is larger than the viewer takes");
    const HeadVerdict v = on_line(data.substr(line_start_, seen_ + 1 - line_start_));
    line_start_ = seen_ + 1;
    if (v.kind == HeadVerdict::Kind::kRefuse) return v;
    if (head_done_) head_bytes_ = seen_ + 1;
  }
  if (!head_done_) {
    // The line under way, before its end arrives: the request line's own bound (its
    // CRLF not counted), else the head's.
    if (line_start_ == 0 && data.size() > limits_.max_request_line + 2) {
      return refuse(414, "the request line is longer than the viewer takes");
    }
    if (data.size() > limits_.max_head_bytes) return refuse(431, "the request head is larger than the viewer takes");
    return {};
  }
  const std::size_t total = head_bytes_ + content_length_;
  if (data.size() < total) return {};
  return {HeadVerdict::Kind::kComplete, 0, total, ""};
}

HeadVerdict HeadScan::on_line(std::string_view line) {
  if (line.size() < 2 || line[line.size() - 2] != '\r') return refuse(400, "a line of the request ends without CRLF");
  const bool request_line = line_start_ == 0;
  if (request_line) {
    if (line.size() == 2) return refuse(400, "the request begins with an empty line");
    if (line.size() - 2 > limits_.max_request_line) return refuse(414, "the request line is longer than the viewer takes");
    return {};
  }
  if (line.size() == 2) {
    head_done_ = true;
    return {};
  }
  if (++header_lines_ > limits_.max_header_lines) return refuse(431, "the request has more header lines than the viewer takes");
  return on_header(line.substr(0, line.size() - 2));
}

HeadVerdict HeadScan::on_header(std::string_view line) {
  const std::size_t colon = line.find(':');
  if (colon == std::string_view::npos || colon == 0) return refuse(400, "a header line without a name and a colon");
  const std::string_view name = line.substr(0, colon);
  if (name_is(name, "transfer-encoding")) {
    return refuse(411, "a request body needs a Content-Length (the viewer takes no Transfer-Encoding)");
  }
  if (!name_is(name, "content-length")) return {};
  if (has_length_) return refuse(400, "two Content-Length headers");
  has_length_ = true;
  const std::string_view value = trim(line.substr(colon + 1));
  if (value.empty()) return refuse(400, "an empty Content-Length");
  std::size_t n = 0;
  for (const char c : value) {
    if (c < '0' || c > '9') return refuse(400, "a Content-Length that is not a number");
    n = n * 10 + static_cast<std::size_t>(c - '0');
    if (n > limits_.max_body_bytes) return refuse(413, "the request body is larger than the viewer takes");
  }
  content_length_ = n;
  return {};
}

bool ConnectionCaps::admit(const std::string& address) {
  std::lock_guard<std::mutex> l(m_);
  if (total_ >= max_total_) return false;
  auto it = per_address_.find(address);
  if (it != per_address_.end() && it->second >= max_per_address_) return false;
  if (it == per_address_.end()) it = per_address_.emplace(address, 0).first;
  ++it->second;
  ++total_;
  return true;
}

void ConnectionCaps::release(const std::string& address) {
  std::lock_guard<std::mutex> l(m_);
  auto it = per_address_.find(address);
  if (it == per_address_.end()) return;  // a release without its admit: nothing to undo
  --total_;
  if (--it->second == 0) per_address_.erase(it);
}

int ConnectionCaps::open() const {
  std::lock_guard<std::mutex> l(m_);
  return total_;
}

int ConnectionCaps::open_from(const std::string& address) const {
  std::lock_guard<std::mutex> l(m_);
  const auto it = per_address_.find(address);
  return it == per_address_.end() ? 0 : it->second;
}

bool is_loopback_address(std::string_view address) {
  const std::string a(address);
  in_addr v4{};
  if (::inet_pton(AF_INET, a.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (::inet_pton(AF_INET6, a.c_str(), &v6) != 1) return false;
  if (IN6_IS_ADDR_LOOPBACK(&v6)) return true;
  return IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127;
}

bool is_ip_address(std::string_view address) {
  const std::string a(address);
  in6_addr any{};
  return ::inet_pton(AF_INET, a.c_str(), &any) == 1 || ::inet_pton(AF_INET6, a.c_str(), &any) == 1;
}

}  // namespace elaslam::viewer
