// SPDX-License-Identifier: Apache-2.0
// robot_node's last words at exit (robot_ports.hpp, final_summary).
#include <cstdio>
#include <string>

#include "elaslam/robot_node/robot_ports.hpp"

namespace elaslam {
namespace {

// A histogram as "p50/p99/max" [us].
std::string p50_p99_max(const DurationHistogram& h) {
  return std::to_string(h.quantile(0.5)) + "/" + std::to_string(h.quantile(0.99)) + "/" + std::to_string(h.max());
}

}  // namespace

std::string final_summary(const RobotNode& node, const FrameStages& st) {
  const auto& c = node.counters();
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "robot_node %d: frames=%lld gaps=%lld duplicates=%lld out_of_order=%lld rejected=%lld "
                "decode_errors=%lld filter_faults=%lld events=%lld notices_applied=%lld notices_stale=%lld landmarks=%d "
                "evictions=%lld restored=%lld frame_us p50=%lld p99=%lld max=%lld\n",
                node.robot_id(), (long long)c.frames, (long long)c.frames_gap, (long long)c.frames_duplicate,
                (long long)c.frames_out_of_order, (long long)c.rejected_inputs, (long long)c.decode_errors,
                (long long)c.filter_faults, (long long)c.events_sent, (long long)c.notices_applied,
                (long long)c.notices_stale, node.robot().filter().num_landmarks(), (long long)c.evictions,
                (long long)c.restored, (long long)node.processing().quantile(0.5),
                (long long)node.processing().quantile(0.99), (long long)node.processing().max());
  std::string out = buf;
  // Where the frames' time went (FrameStages; receive needs the sender's clock).
  out += "robot_node " + std::to_string(node.robot_id()) + ": stages_us p50/p99/max receive=" +
         p50_p99_max(st.receive) + " frame=" + p50_p99_max(st.frame) + " outputs=" + p50_p99_max(st.outputs) +
         " pose=" + p50_p99_max(st.pose) + "\n";
  if (const TrackCounters& k = node.robot().tracks().counters(); k.started > 0) {  // movers were tracked
    std::snprintf(buf, sizeof buf,
                  "robot_node %d: tracks started=%lld returned=%lld lost=%lld ended=%lld full=%lld "
                  "omitted_from_messages=%lld\n",
                  node.robot_id(), (long long)k.started, (long long)k.returned, (long long)k.lost, (long long)k.ended,
                  (long long)k.full, (long long)c.tracks_omitted);
    out += buf;
  }
  if (node.robot().options().team_map_fuse) {  // robot.team_map: what the other robots' map did
    const TeamCounters& t = node.robot().team_counters();
    std::snprintf(buf, sizeof buf,
                  "robot_node %d: team_map chunks=%lld stale=%lld offered=%lld fused=%lld gated=%lld refused=%lld "
                  "mean_nis=%.2f lost=%lld relocalised=%lld\n",
                  node.robot_id(), (long long)c.team_map_chunks, (long long)c.team_map_stale, (long long)t.offered,
                  (long long)t.fused, (long long)t.gated, (long long)t.refused,
                  t.fused > 0 ? t.nis_sum / static_cast<double>(t.fused) : 0.0, (long long)t.lost,
                  (long long)t.relocalised);
    out += buf;
  }
  return out;
}

}  // namespace elaslam
