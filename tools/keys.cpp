// SPDX-License-Identifier: Apache-2.0
// keys: the team's keys and missions (installed as elaslam-keys; docs/security.md
// "Keys and missions").
//   keys new FILE                         a node's new secret key; prints its public key
//   keys public FILE                      the public key of a secret key file
//   keys mission                          a new mission id
//   keys team DIR --robots 1,2,3 [--tool] [--roster FILE]
//                                         a team's keys: DIR/main.key, DIR/simulator.key,
//                                         DIR/robot_<r>.key (DIR/tool.key), and the
//                                         roster DIR/team.yaml (or FILE, mode 0644): the
//                                         config's team: section with their public keys
//                                         and a new mission
// A secret key file is 64 hexadecimal characters and a newline, mode 0600, written to
// a temporary file that is then linked to FILE: an existing FILE (or a symbolic link
// there) is never overwritten or followed (exit 1). Exit 2 on bad arguments.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <sodium.h>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/transport/keys.hpp"

namespace {

using namespace elaslam;
using transport::PublicKey;
using transport::SigningKey;

/// Write `text` to a new file at `path` (mode 0600, or `mode`), never replacing anything there.
bool write_new_file(const std::string& path, const std::string& text, std::string* why, mode_t mode = 0600) {
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

/// A new key at `path`; its public key in *pub.
bool new_key(const std::string& path, PublicKey* pub, std::string* why) {
  std::array<std::uint8_t, transport::kKeyBytes> seed{};
  randombytes_buf(seed.data(), seed.size());
  std::string text = transport::to_hex(seed.data(), seed.size()) + "\n";
  const SigningKey key(seed);
  sodium_memzero(seed.data(), seed.size());
  const bool ok = write_new_file(path, text, why);
  sodium_memzero(text.data(), text.size());
  *pub = key.public_key();
  return ok;
}

std::string hex(const PublicKey& k) { return transport::to_hex(k.data(), k.size()); }

std::string new_mission() {
  std::uint64_t m = 0;
  while (m == 0) randombytes_buf(&m, sizeof m);
  return transport::mission_text(m);
}

int cmd_new(const std::string& path) {
  PublicKey pub{};
  std::string why;
  if (!new_key(path, &pub, &why)) {
    std::fprintf(stderr, "keys: %s\n", why.c_str());
    return 1;
  }
  std::printf("%s\n", hex(pub).c_str());
  return 0;
}

int cmd_public(const std::string& path) {
  SigningKey key;
  std::string why;
  if (!SigningKey::load(path, &key, &why)) {
    std::fprintf(stderr, "keys: %s\n", why.c_str());
    return 2;
  }
  std::printf("%s\n", hex(key.public_key()).c_str());
  return 0;
}

int cmd_team(const std::string& dir, const std::vector<int>& robots, bool tool, const std::string& roster) {
  std::vector<std::int16_t> senders{transport::kSenderMain, transport::kSenderSimulator};
  for (int r : robots) {
    if (r < 1 || r > contract::kMaxRobots) {
      std::fprintf(stderr, "keys: --robots: %d is not a robot id (1..%d)\n", r, contract::kMaxRobots);
      return 2;
    }
    senders.push_back(static_cast<std::int16_t>(r));
  }
  if (tool) senders.push_back(transport::kSenderTool);
  if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST) {
    std::fprintf(stderr, "keys: cannot create %s: %s\n", dir.c_str(), std::strerror(errno));
    return 1;
  }
  std::string yaml = "team:\n  mission: \"" + new_mission() + "\"\n  public_keys:\n";
  for (const std::int16_t s : senders) {
    const std::string name = transport::sender_name(s);
    PublicKey pub{};
    std::string why;
    if (!new_key(dir + "/" + name + ".key", &pub, &why)) {
      std::fprintf(stderr, "keys: %s\n", why.c_str());
      return 1;
    }
    yaml += "    " + name + ": \"" + hex(pub) + "\"\n";
  }
  std::string why;
  // The roster is public: readable by every service (whose dynamic users cannot read the keys).
  if (!write_new_file(roster.empty() ? dir + "/team.yaml" : roster, yaml, &why, 0644)) {
    std::fprintf(stderr, "keys: %s\n", why.c_str());
    return 1;
  }
  std::printf("%s", yaml.c_str());
  return 0;
}

int keys_main(int argc, char** argv) {
  if (sodium_init() < 0) {
    std::fprintf(stderr, "keys: libsodium could not be initialised\n");
    return 1;
  }
  CLI::App app{"elaslam keys: a node's key pair, a team's keys and roster, a mission id"};
  cli::add_version_flag(app, "keys");
  app.require_subcommand(1);
  std::string path, dir, roster;
  std::vector<int> robots;
  bool tool = false;
  auto* n = app.add_subcommand("new", "a new secret key in FILE (mode 0600, never overwrites); prints its public key");
  n->add_option("FILE", path, "the key file to make")->required();
  auto* p = app.add_subcommand("public", "print the public key of the secret key FILE");
  p->add_option("FILE", path, "a secret key file")->required();
  auto* m = app.add_subcommand("mission", "print a new mission id (16 hexadecimal digits)");
  auto* t = app.add_subcommand("team", "a team's keys in DIR and DIR/team.yaml, the config's team: section");
  t->add_option("DIR", dir, "the directory for the keys (made with mode 0700)")->required();
  t->add_option("--robots", robots, "the robots' ids, e.g. 1,2,3")->required()->delimiter(',');
  t->add_flag("--tool", tool, "a key for a publishing tool too (sender 'tool')");
  t->add_option("--roster", roster, "write the roster here instead of DIR/team.yaml");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  if (n->parsed()) return cmd_new(path);
  if (p->parsed()) return cmd_public(path);
  if (m->parsed()) return std::printf("%s\n", new_mission().c_str()) > 0 ? 0 : 1;
  return cmd_team(dir, robots, tool, roster);
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("keys", [&] { return keys_main(argc, argv); });
}
