// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/key_files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <sodium.h>

#include "elaslam/common/contract.hpp"

namespace elaslam::transport {
namespace {

void init_sodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
}

std::string hex(const PublicKey& k) { return to_hex(k.data(), k.size()); }

}  // namespace

bool write_new_file(const std::string& path, const std::string& text, std::string* why, mode_t mode) {
  const std::size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  std::string tmp = dir + "/.elaslam-key-XXXXXX";
  const mode_t old = umask(077);
  const int fd = mkstemp(tmp.data());
  umask(old);
  if (fd < 0) {
    *why = "cannot create a file in " + dir + ": " + std::strerror(errno);
    return false;
  }
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) &&
                       fchmod(fd, mode) == 0 && fsync(fd) == 0;
  const int err = errno;
  ::close(fd);
  // link(2) fails when anything (a file, a symbolic link) is at `path`: nothing is replaced or followed.
  const bool linked = written && ::link(tmp.c_str(), path.c_str()) == 0;
  const int link_err = errno;
  ::unlink(tmp.c_str());
  if (!written) {
    *why = std::string("cannot write ") + tmp + ": " + std::strerror(err);
    return false;
  }
  if (!linked) {
    *why = path + ": " + (link_err == EEXIST ? "exists (a key is never overwritten)" : std::strerror(link_err));
    return false;
  }
  return true;
}

bool make_key_file(const std::string& path, PublicKey* pub, std::string* why) {
  init_sodium();
  std::array<std::uint8_t, kKeyBytes> seed{};
  randombytes_buf(seed.data(), seed.size());
  std::string text = to_hex(seed.data(), seed.size()) + "\n";
  const SigningKey key(seed);
  sodium_memzero(seed.data(), seed.size());
  const bool ok = write_new_file(path, text, why);
  sodium_memzero(text.data(), text.size());
  *pub = key.public_key();
  return ok;
}

std::string new_mission() {
  init_sodium();
  std::uint64_t m = 0;
  while (m == 0) randombytes_buf(&m, sizeof m);
  return mission_text(m);
}

bool team_senders(const std::vector<int>& robots, bool tool, std::vector<std::int16_t>* senders, std::string* why) {
  *senders = {kSenderMain, kSenderSimulator};
  for (int r : robots) {
    if (r < 1 || r > contract::kMaxRobots) {
      *why = std::to_string(r) + " is not a robot id (1.." + std::to_string(contract::kMaxRobots) + ")";
      return false;
    }
    senders->push_back(static_cast<std::int16_t>(r));
  }
  if (tool) senders->push_back(kSenderTool);
  return true;
}

bool make_team_keys(const std::string& dir, const std::vector<std::int16_t>& senders, const std::string& roster_path,
                    std::string* yaml, std::string* why) {
  if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST) {
    *why = "cannot create " + dir + ": " + std::strerror(errno);
    return false;
  }
  *yaml = "team:\n  mission: \"" + new_mission() + "\"\n  public_keys:\n";
  for (const std::int16_t s : senders) {
    const std::string name = sender_name(s);
    PublicKey pub{};
    if (!make_key_file(dir + "/" + name + ".key", &pub, why)) return false;
    *yaml += "    " + name + ": \"" + hex(pub) + "\"\n";
  }
  // The roster is public: readable by every service (whose dynamic users cannot read the keys).
  return write_new_file(roster_path, *yaml, why, 0644);
}

}  // namespace elaslam::transport
