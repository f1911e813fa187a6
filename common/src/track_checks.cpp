// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/track_checks.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"

namespace elaslam {
namespace {

// The fields track_t and global_track_t share.
template <class T>
std::string check_common(const T& t, const MessageLimits& l, int max_landmark_id, Refusal* reason) {
  *reason = Refusal::kMalformed;
  if (t.id < 0 || t.id >= max_landmark_id) return contract::got("track landmark id outside [0, max_landmark_id)", t.id);
  // Named in a refusal only: a valid track builds no string (main's frame path allocates nothing).
  const auto who = [&t] { return "track of landmark " + std::to_string(t.id) + ": "; };
  bool finite = std::isfinite(t.vx) && std::isfinite(t.vy);
  for (float c : t.cov) finite = finite && std::isfinite(c);
  for (float p : t.probabilities) finite = finite && std::isfinite(p);
  if (!finite) return who() + "velocity, covariance or probabilities not finite";
  if (t.likeliest < track_t::STATIC || t.likeliest > track_t::CONSTANT_VELOCITY)
    return who() + contract::got("likeliest is not a model", static_cast<int>(t.likeliest));
  if (t.stopped != 0 && t.stopped != 1) return who() + contract::got("stopped is not 0 or 1", static_cast<int>(t.stopped));
  double sum = 0.0;
  for (float p : t.probabilities) {
    if (p < 0.0f || p > 1.0f) return who() + contract::got("a model probability outside [0, 1]", p);
    sum += p;
  }
  if (std::fabs(sum - 1.0) > 1e-3) return who() + contract::got("model probabilities do not sum to 1", sum);
  *reason = Refusal::kImplausible;
  if (std::string p = check_position(t.x, t.y, l, "position"); !p.empty()) return who() + p;
  if (std::fabs(t.vx) > l.world_bound || std::fabs(t.vy) > l.world_bound)
    return who() + contract::got("speed beyond limits.world_bound_m per second", std::hypot(t.vx, t.vy));
  const Eigen::Matrix4d C = read_cov_upper(t.cov);
  if (C.diagonal().maxCoeff() > l.cov_ceiling) return who() + contract::got("a variance above limits.cov_ceiling_m2", C.diagonal().maxCoeff());
  if (std::string p = check_cov2(Eigen::Matrix2d(C.topLeftCorner<2, 2>()), l, "position covariance"); !p.empty()) return who() + p;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(C, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues()(0), hi = eig.eigenvalues()(3);
  if (!(lo >= -1e-6 * hi)) return who() + contract::got("covariance not positive semi-definite, smallest eigenvalue", lo);
  return "";
}

}  // namespace

std::string check_track(const track_t& t, const MessageLimits& l, int max_landmark_id, Refusal* reason) {
  if (std::string p = check_common(t, l, max_landmark_id, reason); !p.empty()) return p;
  *reason = Refusal::kMalformed;
  if (t.validated != 0 && t.validated != 1) return contract::got("track validated is not 0 or 1", static_cast<int>(t.validated));
  if (t.sightings < 0) return contract::got("track sightings negative", t.sightings);
  return "";
}

std::string check_track(const global_track_t& t, const MessageLimits& l, int max_landmark_id, Refusal* reason) {
  if (std::string p = check_common(t, l, max_landmark_id, reason); !p.empty()) return p;
  *reason = Refusal::kOutsideTeam;
  if (t.contributors == 0 || (t.contributors & ~l.team_mask) != 0)
    return contract::got("fused track contributors not a non-empty set of the team's robots", t.contributors);
  return "";
}

std::string check_chunk(int chunk, int num_chunks) {
  if (num_chunks < 1 || num_chunks > contract::kMaxTrackChunks)
    return contract::got(contract::outside("num_chunks", 1, contract::kMaxTrackChunks), num_chunks);
  if (chunk < 0 || chunk >= num_chunks) return contract::got(contract::outside("chunk", 0, num_chunks - 1), chunk);
  return "";
}

std::string check_track_list(const track_list_t& m, const MessageLimits& l, int max_landmark_id, Refusal* reason) {
  *reason = Refusal::kMalformed;
  if (m.robot_id < 1 || m.robot_id > contract::kMaxRobots)
    return contract::got(contract::outside("robot_id", 1, contract::kMaxRobots), m.robot_id);
  if (m.incarnation < 0) return contract::got("incarnation is negative", m.incarnation);
  if (m.frame < 0) return contract::got("frame is negative", m.frame);
  if (std::string p = check_chunk(m.chunk, m.num_chunks); !p.empty()) return p;
  if (m.num_tracks < 0 || m.num_tracks > contract::kMaxTracks)
    return contract::got(contract::count_outside("num_tracks", contract::kMaxTracks), m.num_tracks);
  if (!contract::count_fits(m.tracks, m.num_tracks)) return contract::got("num_tracks does not match the array", m.num_tracks);
  if (m.num_omitted < 0) return contract::got("num_omitted is negative", m.num_omitted);
  for (int k = 0; k < m.num_tracks; ++k) {
    const track_t& t = m.tracks[static_cast<std::size_t>(k)];
    for (int j = 0; j < k; ++j)
      if (m.tracks[static_cast<std::size_t>(j)].id == t.id)
        return *reason = Refusal::kDuplicateId, contract::got("track landmark id listed twice", t.id);
    if (std::string p = check_track(t, l, max_landmark_id, reason); !p.empty()) return p;
  }
  return "";
}

std::string check_global_tracks(const global_tracks_t& m, const MessageLimits& l, int max_landmark_id, Refusal* reason) {
  *reason = Refusal::kMalformed;
  if (m.incarnation < 0) return contract::got("incarnation is negative", m.incarnation);
  if (m.frame < -1) return contract::got("frame below -1", m.frame);
  if (std::string p = check_chunk(m.chunk, m.num_chunks); !p.empty()) return p;
  if (m.num_tracks < 0 || m.num_tracks > contract::kMaxGlobalTracks)
    return contract::got(contract::count_outside("num_tracks", contract::kMaxGlobalTracks), m.num_tracks);
  if (!contract::count_fits(m.tracks, m.num_tracks)) return contract::got("num_tracks does not match the array", m.num_tracks);
  if (m.num_omitted < 0) return contract::got("num_omitted is negative", m.num_omitted);
  int previous = -1;
  for (int k = 0; k < m.num_tracks; ++k) {
    const global_track_t& t = m.tracks[static_cast<std::size_t>(k)];
    *reason = Refusal::kMalformed;
    if (t.id == previous) return *reason = Refusal::kDuplicateId, contract::got("fused track landmark id listed twice", t.id);
    if (t.id < previous) return contract::got("fused track ids not ascending, id", t.id);
    previous = t.id;
    if (std::string p = check_track(t, l, max_landmark_id, reason); !p.empty()) return p;
  }
  return "";
}

}  // namespace elaslam
