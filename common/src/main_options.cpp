// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/main_options.hpp"

#include <string>

#include "elaslam/common/contract.hpp"

namespace elaslam {

void parse(config::Reader& r, GlobalMapOptions* o) {
  r.read("max_landmark_id", &o->max_landmark_id, 1, contract::kMaxLandmarkIdLimit);
  std::string fusion = o->fusion == Fusion::kInformation ? "information" : "covariance_intersection";
  r.read_enum("fusion", &fusion, {"information", "covariance_intersection"});
  o->fusion = fusion == "information" ? Fusion::kInformation : Fusion::kCovarianceIntersection;
  r.read("publish_rate_hz", &o->publish_rate_hz, 0.1, 10000.0);
  r.read("state_save_interval_s", &o->state_save_interval_s, 0.0, 3600.0);
  r.read("resync_interval_frames", &o->resync_interval_frames, 1, 100000);
  r.read_optional("max_frame_gap", &o->max_frame_gap, 1, 100000);
  int seq_jump = static_cast<int>(o->max_seq_jump);
  r.read_optional("max_seq_jump", &seq_jump, 1, 1 << 30);
  o->max_seq_jump = seq_jump;
  r.read_optional("team_map_period_frames", &o->team_map_period_frames, 0, 100000);
  r.read_optional("moving_repeat_s", &o->moving_repeat_s, 0.0, 3600.0);
  r.read_optional("body_radius_m", &o->body_radius_m, 0.0, 10.0);
  r.read_optional("team_map_check_probability", &o->team_map_check_probability, 0.0, 0.999999);
  if (o->team_map_check_probability > 0.0 && o->team_map_check_probability < 0.5)
    r.fail("team_map_check_probability", "must be 0 (off) or at least 0.5 (a gate that refuses most agreeing maps)");
  parse(r, &o->limits);
}

}  // namespace elaslam
