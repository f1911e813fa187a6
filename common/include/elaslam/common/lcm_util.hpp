// Small helpers shared by the processes' LCM shells.
#pragma once

#include <atomic>
#include <csignal>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

namespace elaslam {

/// Wall-clock microseconds since the epoch (message utime).
inline std::int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// Set by SIGINT / SIGTERM once install_stop_handlers() ran.
inline std::atomic<bool>& stop_requested() {
  static std::atomic<bool> flag{false};
  return flag;
}

inline void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = [](int) { stop_requested().store(true); };
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

/// Encode and publish a message; false when encoding or sending failed.
template <typename Msg>
bool publish_msg(lcm::LCM& lc, const std::string& channel, const Msg& msg, std::vector<std::uint8_t>* scratch) {
  const int size = msg.getEncodedSize();
  if (size < 0) return false;
  if (scratch->size() < static_cast<std::size_t>(size)) scratch->resize(static_cast<std::size_t>(size));
  if (msg.encode(scratch->data(), 0, size) != size) return false;
  return lc.publish(channel, scratch->data(), static_cast<unsigned int>(size)) == 0;
}

/// Subscribe a member function to raw messages (the handler decodes, so that it can
/// count decode errors). Goes through subscribeFunction: LCM 1.3.1's member-function
/// subscription trips UBSan's vptr check under GCC 12.
template <class Obj, void (Obj::*Method)(const lcm::ReceiveBuffer*, const std::string&)>
lcm::Subscription* subscribe_raw(lcm::LCM& lc, const std::string& channel, Obj* obj) {
  return lc.subscribeFunction(
      channel, +[](const lcm::ReceiveBuffer* rb, const std::string& ch, Obj* o) { (o->*Method)(rb, ch); }, obj);
}

/// The LCM URL to use: the command line's, else LCM_DEFAULT_URL (LCM reads it
/// itself when the URL is empty), else LCM's default.
inline std::string describe_lcm_url(const std::string& url) {
  if (!url.empty()) return url;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return env ? std::string(env) + " (LCM_DEFAULT_URL)" : std::string("LCM default (udpm://239.255.76.67:7667?ttl=0)");
}

}  // namespace elaslam
