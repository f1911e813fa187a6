// SPDX-License-Identifier: Apache-2.0
// The viewer's command line (the usage comment of viewer/src/main.cpp lists it) and
// the access token it asks for (access_token.hpp, docs/security.md, "The viewer as an HTTP service").
#pragma once

#include <string>

#include "elaslam/transport/process.hpp"

namespace elaslam::viewer {

struct ViewerOptions {
  transport::TransportArgs transport;
  std::string config;
  std::string bind = "127.0.0.1";  ///< the HTTP socket's address
  std::string http_netns;          ///< open the HTTP socket in this network namespace
  std::string token_file;          ///< --token-file: the access token for peers that are not loopback
  std::string make_token;          ///< --make-token: write a new token file here and exit
  int port = 8765;
  int max_clients = 8;             ///< event streams at once
  double rate_hz = 20.0;           ///< states pushed per second
};

/// Parses the command line: -1 to go on, else the exit code after saying why (0 after
/// --help, --version or --make-token FILE made; 1: the token file could not be made;
/// 2: a bad command line, a --bind that is no IP address).
int parse_viewer_options(int argc, char** argv, ViewerOptions* o);

/// The access token of --token-file into *token ("" without one): -1 to go on, else
/// exit code 2 after saying why: the file fails load_access_token's checks, or --bind
/// is not a loopback address and no token was given.
int load_viewer_token(const ViewerOptions& o, std::string* token);

}  // namespace elaslam::viewer
