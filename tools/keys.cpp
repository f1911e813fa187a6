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
// there) is never overwritten or followed (exit 1). Exit 2 on bad arguments. The
// files are made by transport/key_files.hpp.
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <sodium.h>

#include "elaslam/common/cli.hpp"
#include "elaslam/transport/key_files.hpp"
#include "elaslam/transport/keys.hpp"

namespace {

using namespace elaslam;
using transport::PublicKey;
using transport::SigningKey;

std::string hex(const PublicKey& k) { return transport::to_hex(k.data(), k.size()); }

int cmd_new(const std::string& path) {
  PublicKey pub{};
  std::string why;
  if (!transport::make_key_file(path, &pub, &why)) {
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
  std::vector<std::int16_t> senders;
  std::string why, yaml;
  if (!transport::team_senders(robots, tool, &senders, &why)) {
    std::fprintf(stderr, "keys: --robots: %s\n", why.c_str());
    return 2;
  }
  if (!transport::make_team_keys(dir, senders, roster.empty() ? dir + "/team.yaml" : roster, &yaml, &why)) {
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
  if (m->parsed()) return std::printf("%s\n", transport::new_mission().c_str()) > 0 ? 0 : 1;
  return cmd_team(dir, robots, tool, roster);
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("keys", [&] { return keys_main(argc, argv); });
}
