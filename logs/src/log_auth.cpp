// SPDX-License-Identifier: Apache-2.0
#include "elaslam/logs/log_auth.hpp"

#include <memory>

#include "elaslam/common/channels.hpp"
#include "elaslam/transport/process.hpp"

namespace elaslam {

LogAuth::LogAuth(transport::auth::AuthSetup setup) : suffix_(setup.channel_suffix), auth_(std::move(setup)) {}

bool LogAuth::admit(LogEvent* ev) {
  // Not the team's (LCM's own LCM_SELF_TEST, a tool's): no node receives it; as is.
  if (!channels::is_team_channel(ev->channel, suffix_)) return true;
  std::size_t payload = 0;
  transport::auth::Sender sender;
  // The recording's receive times stand for the receiver's clock (the replay windows'
  // quiet time): the log is read as a node read the wire when it was recorded.
  const transport::auth::Verdict v =
      auth_.open(ev->channel, ev->data.data(), ev->data.size(), &payload, &sender, 0, ev->timestamp > 0 ? ev->timestamp : 1);
  if (v != transport::auth::Verdict::kAccepted) {
    ++refused_[ev->channel][transport::auth::key_of(v)];
    return false;
  }
  ev->data.resize(payload);
  return true;
}

nlohmann::json LogAuth::to_json(const std::string& source) const {
  nlohmann::json j;
  j["roster"] = source;
  j["mission"] = transport::mission_text(auth_.mission());
  j["accepted"] = accepted();
  j["refused"] = refused();
  j["refused_by"] = nlohmann::json::object();
  j["refused_by_reason"] = nlohmann::json::object();
  for (const auto& [ch, reasons] : refused_)
    for (const auto& [why, n] : reasons) {
      j["refused_by"][ch][why] = n;
      j["refused_by_reason"][why] = j["refused_by_reason"].value(why, 0) + n;
    }
  return j;
}

bool open_log_auth(const std::string& roster_option, const std::string& mission_option, const std::string& config_path,
                   const std::string& suffix, const std::string& who, std::unique_ptr<LogAuth>* auth,
                   std::string* source) {
  transport::TransportArgs args;
  args.roster = roster_option;
  args.mission = mission_option;
  args.channel_suffix = suffix;
  transport::auth::AuthSetup setup;
  bool on = false;
  if (!transport::configured_auth(args, config_path, who, transport::kSenderTool, false, &setup, &on)) return false;
  *source = !on ? "" : !roster_option.empty() ? "roster " + roster_option : "the team: section of " + config_path;
  setup.channel_suffix = suffix;
  auth->reset(on ? new LogAuth(std::move(setup)) : nullptr);
  return true;
}

}  // namespace elaslam
