// SPDX-License-Identifier: Apache-2.0
#include "viewer_options.hpp"

#include <cstdio>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/viewer/access_token.hpp"
#include "elaslam/viewer/http_guard.hpp"

namespace elaslam::viewer {
namespace {

int make_token_file(const std::string& path) {
  std::string why;
  if (!make_access_token(path, &why)) {
    std::fprintf(stderr, "viewer: %s\n", why.c_str());
    return cli::kExitFailure;
  }
  std::fprintf(stderr, "viewer: made the token file %s (mode 0600); give it with --token-file %s\n", path.c_str(),
               path.c_str());
  return cli::kExitOk;
}

}  // namespace

int parse_viewer_options(int argc, char** argv, ViewerOptions* o) {
  CLI::App app{"elaslam viewer: the team's map, robots and health in a browser (Server-Sent Events)"};
  cli::add_version_flag(app, "viewer");
  cli::add_config_option(app, &o->config, "its main: section (landmark ids, bounds) and team: section (the team key)");
  transport::add_transport_options(app, &o->transport);
  app.add_option("--port", o->port, "HTTP port (0: any free port)")->capture_default_str()->check(cli::range(0, 65535));
  app.add_option("--bind", o->bind,
                 "address to listen on (127.0.0.1: this machine only; any other needs --token-file)")
      ->capture_default_str();
  app.add_option("--http-netns", o->http_netns,
                 "open the HTTP socket in this network namespace (/run/netns/NAME, /proc/PID/ns/net); LCM stays in the "
                 "process's own");
  app.add_option("--rate", o->rate_hz, "states pushed per second")->capture_default_str()->check(cli::range(1.0, 100.0));
  app.add_option("--max-clients", o->max_clients, "event streams served at once")
      ->capture_default_str()
      ->check(cli::range(1, 64));
  app.add_option("--token-file", o->token_file,
                 "the access token every peer but this machine's loopback must show (Authorization: Bearer TOKEN or "
                 "?token=TOKEN): a file of 64+ hexadecimal digits, mode 0600; needed with a --bind that is not loopback");
  app.add_option("--make-token", o->make_token,
                 "write a new access token to this file (mode 0600; never over an existing file) and exit");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  if (!o->make_token.empty()) return make_token_file(o->make_token);
  if (!is_ip_address(o->bind)) {
    std::fprintf(stderr, "--bind: '%s' is not an IPv4 or IPv6 address\n", o->bind.c_str());
    return cli::kExitBadInput;
  }
  return -1;
}

int load_viewer_token(const ViewerOptions& o, std::string* token) {
  token->clear();
  if (!o.token_file.empty()) {
    std::string why;
    if (!load_access_token(o.token_file, token, &why)) {
      std::fprintf(stderr, "viewer: --token-file: %s\n", why.c_str());
      return cli::kExitBadInput;
    }
  }
  if (token->empty() && !is_loopback_address(o.bind)) {
    std::fprintf(stderr,
                 "viewer: --bind %s is not a loopback address: every computer that reaches it could read the map and "
                 "the ground truth; give an access token with --token-file FILE (make one with viewer --make-token "
                 "FILE), or listen on 127.0.0.1\n",
                 o.bind.c_str());
    return cli::kExitBadInput;
  }
  return -1;
}

}  // namespace elaslam::viewer
