// SPDX-License-Identifier: Apache-2.0
// The checks of the tracks' messages, TRACKS_<r> (track_list_t) and GLOBAL_TRACKS
// (global_tracks_t), as every receiver applies them (main_robot, the viewer,
// evaluate): the contract's counts and ids, then each track's content. Each returns
// "" when the message is valid, else the problem, with `reason` its kind
// (limits.hpp). Whether the sender is in the team is the caller's.
#pragma once

#include <string>

#include "elaslam/common/limits.hpp"
#include "elaslam/global_tracks_t.hpp"
#include "elaslam/track_list_t.hpp"

namespace elaslam {

/// One track's content: id in [0, max_landmark_id); position within limits; every
/// number finite, speeds at most world_bound per second (a bound on corruption, as
/// world_bound is); the covariance (its upper triangle: symmetric by construction)
/// positive semi-definite (its smallest eigenvalue not below -1e-6 of its largest:
/// float rounding), its position block within check_cov2's limits and its variances
/// at most cov_ceiling; the model probabilities each in [0, 1] summing to 1 within
/// 1e-3; likeliest one of the three models, the flags 0 or 1.
std::string check_track(const track_t& t, const MessageLimits& l, int max_landmark_id, Refusal* reason);
std::string check_track(const global_track_t& t, const MessageLimits& l, int max_landmark_id, Refusal* reason);

/// A chunk's place in its publication: num_chunks in [1, contract::kMaxTrackChunks],
/// chunk in [0, num_chunks). Whether the chunks of one publication agree is the
/// assembler's (TrackChunks).
std::string check_chunk(int chunk, int num_chunks);

/// TRACKS_<r>: robot id within the contract, incarnation and frame not negative, the
/// chunk's place valid (check_chunk), num_tracks in [0, contract::kMaxTracks] and matching the array, num_omitted not
/// negative, each landmark id listed once, each track valid (check_track).
std::string check_track_list(const track_list_t& m, const MessageLimits& l, int max_landmark_id, Refusal* reason);
/// GLOBAL_TRACKS: frame at least -1, incarnation not negative, the chunk's place
/// valid (check_chunk), num_tracks in [0,
/// contract::kMaxGlobalTracks] and matching the array, num_omitted not negative, ids
/// ascending and each once, contributors naming robots of l's team only, each track
/// valid (check_track).
std::string check_global_tracks(const global_tracks_t& m, const MessageLimits& l, int max_landmark_id, Refusal* reason);

}  // namespace elaslam
