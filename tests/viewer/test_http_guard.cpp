// SPDX-License-Identifier: Apache-2.0
// HeadScan, ConnectionCaps and the address rules: what the viewer takes of a request
// before httplib parses it, and how many connections a peer may hold.
#include <string>

#include <gtest/gtest.h>

#include "elaslam/viewer/http_guard.hpp"

namespace elaslam::viewer {
namespace {

using Kind = HeadVerdict::Kind;

std::string request(const std::string& extra_headers = "", const std::string& target = "/state.json") {
  return "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1:8765\r\n" + extra_headers + "\r\n";
}

std::string header_lines(int n, std::size_t value_bytes = 8) {
  std::string h;
  for (int i = 0; i < n; ++i) h += "X-" + std::to_string(i) + ": " + std::string(value_bytes, 'v') + "\r\n";
  return h;
}

HeadVerdict scan_whole(const std::string& data, const HttpLimits& limits = {}) {
  HeadScan s(limits);
  return s.scan(data);
}

/// The data given a byte at a time, as a slow client sends it: the first verdict
/// that is not kMore, and how many bytes it took.
HeadVerdict scan_bytewise(const std::string& data, std::size_t* used, const HttpLimits& limits = {}) {
  HeadScan s(limits);
  for (std::size_t n = 1; n <= data.size(); ++n) {
    const HeadVerdict v = s.scan(std::string_view(data).substr(0, n));
    if (v.kind != Kind::kMore) {
      *used = n;
      return v;
    }
  }
  *used = data.size();
  return {};
}

TEST(HeadScan, TakesABrowsersRequestWholeOrByteByByte) {
  // GIVEN a request as a browser sends it, with a Content-Length 0
  const std::string r = request("Accept: text/event-stream\r\nContent-Length: 0\r\n");
  // THEN it is complete at its last byte, however it arrives
  const HeadVerdict whole = scan_whole(r);
  ASSERT_EQ(whole.kind, Kind::kComplete);
  EXPECT_EQ(whole.request_bytes, r.size());
  std::size_t used = 0;
  const HeadVerdict bytewise = scan_bytewise(r, &used);
  ASSERT_EQ(bytewise.kind, Kind::kComplete);
  EXPECT_EQ(used, r.size());
  EXPECT_EQ(bytewise.request_bytes, r.size());
}

TEST(HeadScan, WaitsForTheEndOfTheHead) {
  const std::string r = request();
  EXPECT_EQ(scan_whole(r.substr(0, r.size() - 1)).kind, Kind::kMore);
  EXPECT_EQ(scan_whole("").kind, Kind::kMore);
}

TEST(HeadScan, HeaderLinesUpToTheLimitAreTakenOneMoreIsRefused431) {
  const HttpLimits l;
  // Host is one header line: the request has 1 + extra lines.
  EXPECT_EQ(scan_whole(request(header_lines(l.max_header_lines - 1))).kind, Kind::kComplete);
  const HeadVerdict v = scan_whole(request(header_lines(l.max_header_lines)));
  EXPECT_EQ(v.kind, Kind::kRefuse);
  EXPECT_EQ(v.status, 431);
}

TEST(HeadScan, AFloodOfHeaderLinesIsRefusedWithinTheHeadBound) {
  // GIVEN the attack that grew httplib 0.11.4 to 2.5 GB: 8 KB header lines without end
  const HttpLimits l;
  std::string flood = "GET / HTTP/1.1\r\n";
  while (flood.size() < 1024 * 1024) flood += "X-Flood: " + std::string(8000, 'a') + "\r\n";
  // WHEN it arrives a byte at a time
  std::size_t used = 0;
  const HeadVerdict v = scan_bytewise(flood, &used);
  // THEN it is refused before more than the head's bound (and one byte) was received
  EXPECT_EQ(v.kind, Kind::kRefuse);
  EXPECT_EQ(v.status, 431);
  EXPECT_LE(used, l.max_head_bytes + 1);
}

TEST(HeadScan, ShortLinesBeyondTheHeadSizeAreRefused431) {
  // 90 lines (under the count) of 200 bytes: 18 KB, over 16 KiB.
  const HeadVerdict v = scan_whole(request(header_lines(90, 200)));
  EXPECT_EQ(v.kind, Kind::kRefuse);
  EXPECT_EQ(v.status, 431);
}

TEST(HeadScan, AnEndlessLineIsRefusedBeforeItEnds) {
  std::size_t used = 0;
  const HeadVerdict v = scan_bytewise("GET / HTTP/1.1\r\nX-Long: " + std::string(64 * 1024, 'a'), &used);
  EXPECT_EQ(v.status, 431);
  EXPECT_LE(used, HttpLimits{}.max_head_bytes + 1);
}

TEST(HeadScan, ARequestLineOverItsBoundIsRefused414WholeOrPartial) {
  const HttpLimits l;
  const std::string at_bound = "GET /" + std::string(l.max_request_line - 14, 'a') + " HTTP/1.1";  // exactly the bound
  ASSERT_EQ(at_bound.size(), l.max_request_line);
  EXPECT_EQ(scan_whole(at_bound + "\r\nHost: x\r\n\r\n").kind, Kind::kComplete);
  const std::string over = "GET /" + std::string(l.max_request_line, 'a') + " HTTP/1.1\r\n\r\n";
  EXPECT_EQ(scan_whole(over).status, 414);
  std::size_t used = 0;
  EXPECT_EQ(scan_bytewise("GET /" + std::string(100000, 'a'), &used).status, 414);
  EXPECT_LE(used, l.max_request_line + 3);
}

TEST(HeadScan, LinesMustEndInCrlf) {
  EXPECT_EQ(scan_whole("GET / HTTP/1.1\nHost: x\n\n").status, 400);
  EXPECT_EQ(scan_whole("GET / HTTP/1.1\r\nHost: x\n\r\n").status, 400);
  EXPECT_EQ(scan_whole("\r\nGET / HTTP/1.1\r\n\r\n").status, 400);
  EXPECT_EQ(scan_whole("GET / HTTP/1.1\r\nno colon here\r\n\r\n").status, 400);
}

TEST(HeadScan, ABodyIsTakenWithItsContentLengthUpToTheBound) {
  const std::string head = request("Content-Length: 10\r\n");
  EXPECT_EQ(scan_whole(head + "12345").kind, Kind::kMore);  // the body is awaited
  const HeadVerdict v = scan_whole(head + "0123456789");
  ASSERT_EQ(v.kind, Kind::kComplete);
  EXPECT_EQ(v.request_bytes, head.size() + 10);
  const std::size_t max = HttpLimits{}.max_body_bytes;
  EXPECT_EQ(scan_whole(request("content-length: " + std::to_string(max) + "\r\n") + std::string(max, 'b')).kind,
            Kind::kComplete);
  EXPECT_EQ(scan_whole(request("Content-Length: " + std::to_string(max + 1) + "\r\n")).status, 413);
  // A number past any integer is refused as too large, not wrapped.
  EXPECT_EQ(scan_whole(request("Content-Length: 99999999999999999999999999999999\r\n")).status, 413);
}

TEST(HeadScan, BodiesWithoutALengthOrWithTwoAreRefused) {
  EXPECT_EQ(scan_whole(request("Transfer-Encoding: chunked\r\n")).status, 411);
  EXPECT_EQ(scan_whole(request("Content-Length: 1\r\nContent-Length: 1\r\n")).status, 400);
  EXPECT_EQ(scan_whole(request("Content-Length: -1\r\n")).status, 400);
  EXPECT_EQ(scan_whole(request("Content-Length: 1e3\r\n")).status, 400);
  EXPECT_EQ(scan_whole(request("Content-Length:\r\n")).status, 400);
}

TEST(HeadScan, PipelinedRequestsAreTakenOneAtATime) {
  const std::string first = request(), second = request("", "/");
  HeadScan s(HttpLimits{});
  const std::string both = first + second;
  const HeadVerdict v1 = s.scan(both);
  ASSERT_EQ(v1.kind, Kind::kComplete);
  EXPECT_EQ(v1.request_bytes, first.size());
  s.reset();
  const HeadVerdict v2 = s.scan(std::string_view(both).substr(first.size()));
  ASSERT_EQ(v2.kind, Kind::kComplete);
  EXPECT_EQ(v2.request_bytes, second.size());
}

TEST(HeadScan, TheLimitsAreTheOnesGiven) {
  HttpLimits l;
  l.max_header_lines = 2;
  EXPECT_EQ(scan_whole(request(header_lines(1)), l).kind, Kind::kComplete);
  EXPECT_EQ(scan_whole(request(header_lines(2)), l).status, 431);
}

TEST(ConnectionCaps, CountsPerAddressAndInAll) {
  ConnectionCaps caps(5, 3);
  EXPECT_TRUE(caps.admit("10.0.0.1"));
  EXPECT_TRUE(caps.admit("10.0.0.1"));
  EXPECT_TRUE(caps.admit("10.0.0.1"));
  EXPECT_FALSE(caps.admit("10.0.0.1"));  // its own cap
  EXPECT_TRUE(caps.admit("10.0.0.2"));
  EXPECT_TRUE(caps.admit("10.0.0.3"));
  EXPECT_FALSE(caps.admit("10.0.0.4"));  // the total
  EXPECT_EQ(caps.open(), 5);
  EXPECT_EQ(caps.open_from("10.0.0.1"), 3);
  caps.release("10.0.0.1");
  EXPECT_TRUE(caps.admit("10.0.0.4"));
  EXPECT_FALSE(caps.admit("10.0.0.1"));
  for (const char* a : {"10.0.0.1", "10.0.0.1", "10.0.0.2", "10.0.0.3", "10.0.0.4"}) caps.release(a);
  EXPECT_EQ(caps.open(), 0);
  EXPECT_EQ(caps.open_from("10.0.0.1"), 0);
  caps.release("10.0.0.9");  // never admitted: nothing changes
  EXPECT_EQ(caps.open(), 0);
}

TEST(Addresses, LoopbackIs127Slash8AndColonColon1) {
  for (const char* a : {"127.0.0.1", "127.0.0.2", "127.255.255.254", "::1", "::ffff:127.0.0.1"}) {
    EXPECT_TRUE(is_loopback_address(a)) << a;
  }
  for (const char* a : {"0.0.0.0", "::", "10.200.0.1", "128.0.0.1", "192.168.1.7", "::ffff:10.0.0.1", "fe80::1",
                        "localhost", "", "127.0.0.1 ", "127.1"}) {
    EXPECT_FALSE(is_loopback_address(a)) << a;
  }
}

TEST(Addresses, BindTakesNumericAddressesOnly) {
  for (const char* a : {"127.0.0.1", "0.0.0.0", "::", "::1", "10.200.0.1"}) EXPECT_TRUE(is_ip_address(a)) << a;
  for (const char* a : {"localhost", "", "1.2.3", "300.0.0.1", "[::1]"}) EXPECT_FALSE(is_ip_address(a)) << a;
}

}  // namespace
}  // namespace elaslam::viewer
