#include "elaslam/team/log_auth.hpp"

#include <memory>

#include "elaslam/common/channels.hpp"
#include "elaslam/transport/process.hpp"

namespace elaslam {

// A reader holds the key but sends nothing: the tools' sender id, incarnation 0.
LogAuth::LogAuth(const transport::TeamKey& key, const std::string& suffix)
    : auth_(key, transport::auth::kSenderTool, 0, suffix), suffix_(suffix) {}

bool LogAuth::admit(LogEvent* ev) {
  // Not the team's (LCM's own LCM_SELF_TEST, a tool's): no node receives it; as is.
  if (!channels::is_team_channel(ev->channel, suffix_)) return true;
  std::size_t payload = 0;
  transport::auth::Sender sender;
  const transport::auth::Verdict v = auth_.open(ev->channel, ev->data.data(), ev->data.size(), &payload, &sender);
  if (v != transport::auth::Verdict::kAccepted) {
    ++refused_[ev->channel][transport::auth::to_string(v)];
    return false;
  }
  ev->data.resize(payload);
  return true;
}

nlohmann::json LogAuth::to_json(const std::string& key_file) const {
  nlohmann::json j;
  j["key_file"] = key_file;
  j["accepted"] = accepted();
  j["refused"] = refused();
  j["refused_by"] = nlohmann::json::object();
  for (const auto& [ch, reasons] : refused_)
    for (const auto& [why, n] : reasons) j["refused_by"][ch][why] = n;
  return j;
}

bool open_log_auth(const std::string& key_file_option, const std::string& config_path, const std::string& suffix,
                   const std::string& who, std::unique_ptr<LogAuth>* auth, std::string* key_file) {
  transport::TransportArgs args;
  args.key_file = key_file_option;
  args.channel_suffix = suffix;
  transport::TeamKey key;
  std::string origin;
  if (!transport::configured_team_key(args, config_path, who, &key, key_file, &origin)) return false;
  auth->reset(key.empty() ? nullptr : new LogAuth(key, suffix));
  return true;
}

}  // namespace elaslam
