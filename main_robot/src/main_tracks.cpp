// SPDX-License-Identifier: Apache-2.0
// MainNode and the robots' mover tracks (docs/tracking.md): a robot's TRACKS_<r>
// checked and handed to the fusion, and the fused tracks written into the
// GLOBAL_TRACKS chunks that go out with every GLOBAL_MAP. The rest of the node is in
// main_node.cpp.
#include <algorithm>
#include <cstdint>
#include <string>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"
#include "elaslam/main_robot/main_node.hpp"

namespace elaslam {

bool MainNode::on_tracks(const track_list_t& m, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  const auto refuse = [&](Refusal r, const std::string& problem) {
    ++counters_.tracks_refused;
    return refused(r, problem, why);
  };
  if (std::string problem = validate(m, &reason); !problem.empty()) return refuse(reason, problem);
  // The incarnation main follows (its POSE went out first), or any while none is
  // known yet; a new incarnation shows first in its POSE, which starts the robot over.
  const std::int64_t followed = map_.stream(m.robot_id).incarnation;
  if (followed != 0 && m.incarnation != followed)
    return refuse(Refusal::kStale, "tracks of incarnation " + std::to_string(m.incarnation) + ", robot " +
                                       std::to_string(m.robot_id) + " is followed at " + std::to_string(followed));
  // A frame far ahead would hold back every later message of the robot as not newer.
  const int last = std::max(map_.stream(m.robot_id).last_frame, completion_.robot_frame(m.robot_id));
  if (last >= 0 && m.frame > last + map_.options().max_frame_gap)
    return refuse(Refusal::kFrameWindow,
                  contract::got("tracks' frame more than max_frame_gap ahead of robot " + std::to_string(m.robot_id) +
                                    "'s last " + std::to_string(last),
                                m.frame));
  std::string problem;
  switch (fusion_.take(m, &problem, &reason)) {
    case TrackFusion::Take::kRefused: return refuse(reason, problem);
    case TrackFusion::Take::kStale: ++counters_.stale_tracks; return true;
    case TrackFusion::Take::kTaken: break;
  }
  ++counters_.tracks;
  return true;
}

int MainNode::make_global_tracks(std::int64_t now_utime, int frame) {
  constexpr int kCapacity = contract::kMaxTrackChunks * contract::kMaxGlobalTracks;
  const std::vector<FusedTrack>& fused = fusion_.fuse(stamp(frame));
  const int total = static_cast<int>(fused.size());
  const int n = std::min(total, kCapacity);
  // Once more, as one empty chunk, when the last fused track has gone.
  if (total == 0 && global_tracks_published_ == 0) return num_global_tracks_chunks_ = 0;
  global_tracks_published_ = total;
  for (int k = 0; k < n; ++k) {
    const FusedTrack& f = fused[static_cast<std::size_t>(k)];
    global_tracks_t& chunk = global_tracks_[static_cast<std::size_t>(k / contract::kMaxGlobalTracks)];
    global_track_t& g = chunk.tracks[static_cast<std::size_t>(k % contract::kMaxGlobalTracks)];
    g.id = f.estimate.id;
    g.x = f.estimate.x(0);
    g.y = f.estimate.x(1);
    g.vx = f.estimate.x(2);
    g.vy = f.estimate.x(3);
    write_cov_upper(g.cov, f.estimate.P);
    for (std::size_t i = 0; i < f.estimate.probabilities.size(); ++i)
      g.probabilities[i] = static_cast<float>(f.estimate.probabilities[i]);
    g.likeliest = static_cast<std::int8_t>(f.likeliest());
    g.stopped = f.stopped() ? 1 : 0;
    g.contributors = static_cast<std::int16_t>(f.contributors);
  }
  const int chunks = std::max(1, (n + contract::kMaxGlobalTracks - 1) / contract::kMaxGlobalTracks);
  const auto omitted = static_cast<std::int16_t>(std::min(total - n, static_cast<int>(INT16_MAX)));
  for (int c = 0; c < chunks; ++c) {
    global_tracks_t& m = global_tracks_[static_cast<std::size_t>(c)];
    m.utime = now_utime;
    m.frame = stamp(frame);
    m.incarnation = incarnation_;
    m.chunk = static_cast<std::int16_t>(c);
    m.num_chunks = static_cast<std::int16_t>(chunks);
    m.num_omitted = omitted;
    m.num_tracks = static_cast<std::int16_t>(std::min(contract::kMaxGlobalTracks, n - c * contract::kMaxGlobalTracks));
  }
  ++counters_.global_tracks_published;
  counters_.global_tracks_omitted += omitted;
  return num_global_tracks_chunks_ = chunks;
}

}  // namespace elaslam
