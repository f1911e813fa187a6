// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/robot_messages.hpp"

#include <algorithm>
#include <climits>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"

namespace elaslam {
namespace {

// Every robot message's header: when it was sent, the robot's frame, who sent it
// and the incarnation it belongs to.
template <class Message>
void stamp(Message* m, std::int64_t now_utime, int frame, int robot_id, std::int64_t incarnation) {
  m->utime = now_utime;
  m->frame = frame;
  m->robot_id = static_cast<std::int16_t>(robot_id);
  m->incarnation = incarnation;
}

// A snapshot chunk's two kinds of entry (chunks.hpp, prepare_chunks).
void grow_static(lmap_snapshot_t* m, int n) { contract::set_count(&m->landmarks, &m->num_landmarks, n); }
void grow_moving(lmap_snapshot_t* m, int n) {
  contract::set_count(&m->moving_ids, &m->num_moving, n);
  m->moving_frames.resize(static_cast<std::size_t>(n));
}

// track_t's model constants and probabilities are MotionModel's.
static_assert(static_cast<int>(MotionModel::kStatic) == track_t::STATIC &&
              static_cast<int>(MotionModel::kBounded) == track_t::BOUNDED &&
              static_cast<int>(MotionModel::kConstantVelocity) == track_t::CONSTANT_VELOCITY && kMotionModels == 3);

}  // namespace

RobotMessages::RobotMessages(const RobotOptions& options, int robot_id)
    : robot_id_(robot_id), candidates_period_(options.candidates_period_frames) {
  events_.reserve(Robot::event_capacity(options));
  constexpr std::size_t kBatch = contract::kMaxBatchEvents;
  batches_.resize((Robot::event_capacity(options) + kBatch - 1) / kBatch);
  for (auto& b : batches_) b.events.reserve(kBatch);
  // The snapshot's pool fits the largest map: every id static (held in the filter
  // or archived, Robot::make_room).
  const int max_id = options.ekf.max_landmark_id;
  static_ids_.reserve(static_cast<std::size_t>(max_id));
  moving_ids_.reserve(static_cast<std::size_t>(max_id));
  prepare_chunks(grow_static, grow_moving, contract::kMaxChunkBytes, max_id, max_id, &chunk_sizes_, &chunks_);
  spans_.reserve(chunks_.size());
  candidates_.candidates.resize(contract::kMaxCandidates);  // num_candidates says how many count
  // Every chunk a publication can have, each with room for a full chunk's tracks:
  // filling them allocates nothing (num_tracks says how many count).
  track_chunks_.resize(contract::kMaxTrackChunks);
  for (auto& c : track_chunks_) c.tracks.resize(contract::kMaxTracks);
}

void RobotMessages::begin_frame() {
  snapshot_ready_ = false;
  candidates_ready_ = false;
  num_track_chunks_ = 0;
  events_.clear();
  num_batches_ = 0;
}

void RobotMessages::fill_pose(const Robot& robot, const sensor_frame_t& msg, std::int64_t now_utime,
                              const FrameSummary& s, std::int64_t processing_us, std::int64_t frames_this_run) {
  const EkfSlam& f = robot.estimate();  // with the team map: the aided filter
  const Pose2 p = f.pose();
  stamp(&pose_, now_utime, msg.frame, robot_id_, incarnation_);
  pose_.source_utime = msg.utime;
  pose_.x = p.x;
  pose_.y = p.y;
  pose_.theta = p.theta;
  write_cov(pose_.cov, f.pose_cov());
  pose_.processing_us = static_cast<int32_t>(std::min<std::int64_t>(processing_us, INT32_MAX));
  pose_.mean_diag_p = robot.map_mean_diag();
  pose_.num_obs = static_cast<int16_t>(s.num_obs);
  pose_.num_accepted = static_cast<int16_t>(s.num_accepted);
  pose_.num_rejected = static_cast<int16_t>(s.num_rejected);
  pose_.num_landmarks = static_cast<int16_t>(f.num_landmarks());
  pose_.nis = s.nis;
  pose_.nis_dof = static_cast<int16_t>(s.nis_dof);
  pose_.frames_processed = frames_this_run;
  pose_.event_seq = seq_;  // after fill_events: this frame's events included
  pose_.snapshot_chunks = static_cast<int16_t>(snapshot_ready_ ? num_chunks_ : 0);
}

void RobotMessages::fill_events(const Robot& robot, int frame, std::int64_t now_utime) {
  for (const MapEvent& e : robot.events()) {
    landmark_event_t m{};
    stamp(&m, now_utime, e.frame, robot_id_, incarnation_);
    m.seq = ++seq_;
    m.kind = static_cast<int8_t>(e.kind);
    m.landmark_id = e.landmark_id;
    m.x = e.position.x();
    m.y = e.position.y();
    write_cov(m.cov, e.cov);
    events_.push_back(m);
  }
  // The same events in LMAP_EVENTS messages, kMaxBatchEvents at most each.
  const std::size_t n = events_.size(), k = contract::kMaxBatchEvents;
  num_batches_ = static_cast<int>((n + k - 1) / k);
  for (std::size_t b = 0; b < static_cast<std::size_t>(num_batches_); ++b) {
    lmap_events_t& m = batches_[b];
    stamp(&m, now_utime, frame, robot_id_, incarnation_);
    const std::size_t first = b * k, count = std::min(k, n - first);
    contract::set_count(&m.events, &m.num_events, static_cast<int>(count));
    std::copy_n(events_.begin() + static_cast<std::ptrdiff_t>(first), count, m.events.begin());
  }
}

void RobotMessages::stamp_events(std::int64_t utime) {
  for (auto& e : events_) e.utime = utime;
  for (int b = 0; b < num_batches_; ++b) {
    lmap_events_t& m = batches_[static_cast<std::size_t>(b)];
    m.utime = utime;
    for (auto& e : m.events) e.utime = utime;
  }
}

void RobotMessages::fill_candidates(const Robot& robot, int frame, std::int64_t now_utime) {
  if (candidates_period_ <= 0 || frame % candidates_period_ != 0) return;
  const EkfSlam& f = robot.filter();
  const LMap& lm = robot.lmap();
  int n = 0, omitted = 0;
  for (int slot = 0; slot < f.num_landmarks(); ++slot) {
    const int id = f.id_at(slot);
    if (lm[id].status != LandmarkStatus::kCandidate) continue;
    if (n == contract::kMaxCandidates) {
      ++omitted;
      continue;
    }
    landmark_estimate_t& l = candidates_.candidates[static_cast<std::size_t>(n++)];
    l.id = id;
    const Eigen::Vector2d p = f.landmark(id);
    l.x = p.x();
    l.y = p.y();
    write_cov(l.cov, f.landmark_cov(id));
  }
  if (n + omitted == 0 && candidates_.num_candidates + candidates_.num_omitted == 0) return;
  stamp(&candidates_, now_utime, frame, robot_id_, incarnation_);
  candidates_.num_candidates = static_cast<std::int16_t>(n);
  candidates_.num_omitted = static_cast<std::int16_t>(omitted);
  candidates_ready_ = true;
}

void RobotMessages::fill_tracks(const Robot& robot, int frame, std::int64_t now_utime) {
  // Confirmed tracks only: one sighting (a misread, a wrong association) is not a
  // track yet (MoverTrack::confirmed). They go into chunks of contract::kMaxTracks in
  // the order they started; beyond contract::kMaxTrackChunks chunks they are counted.
  constexpr int kCapacity = contract::kMaxTrackChunks * contract::kMaxTracks;
  const MoverTracks& pool = robot.tracks();
  int total = 0, n = 0;
  for (const int id : pool.ids()) {
    const MoverTrack& t = pool.track(id);
    if (!t.confirmed()) continue;
    ++total;
    if (n == kCapacity) continue;
    track_list_t& chunk = track_chunks_[static_cast<std::size_t>(n / contract::kMaxTracks)];
    track_t& m = chunk.tracks[static_cast<std::size_t>(n % contract::kMaxTracks)];
    ++n;
    const TrackVector x = t.mean();
    m.id = id;
    m.x = x(0);
    m.y = x(1);
    m.vx = x(2);
    m.vy = x(3);
    write_cov_upper(m.cov, t.covariance());
    for (int i = 0; i < kMotionModels; ++i)
      m.probabilities[i] = static_cast<float>(t.probabilities()[static_cast<std::size_t>(i)]);
    m.likeliest = static_cast<std::int8_t>(t.likeliest());
    m.stopped = t.stopped() ? 1 : 0;
    m.validated = t.validated() ? 1 : 0;
    m.sightings = static_cast<std::int32_t>(std::min<std::int64_t>(t.sightings(), INT32_MAX));
  }
  // Once more, as one empty chunk, when the last track has ended.
  if (total == 0 && tracks_published_ == 0) return;
  tracks_published_ = total;
  const int chunks = std::max(1, (n + contract::kMaxTracks - 1) / contract::kMaxTracks);
  const auto omitted = static_cast<std::int16_t>(std::min(total - n, static_cast<int>(INT16_MAX)));
  for (int c = 0; c < chunks; ++c) {
    track_list_t& m = track_chunks_[static_cast<std::size_t>(c)];
    stamp(&m, now_utime, frame, robot_id_, incarnation_);
    m.chunk = static_cast<std::int16_t>(c);
    m.num_chunks = static_cast<std::int16_t>(chunks);
    m.num_omitted = omitted;
    m.num_tracks = static_cast<std::int16_t>(std::min(contract::kMaxTracks, n - c * contract::kMaxTracks));
  }
  num_track_chunks_ = chunks;
}

int RobotMessages::make_snapshot(const Robot& robot, int frame, std::int64_t now_utime) {
  const EkfSlam& f = robot.filter();
  const LMap& lm = robot.lmap();
  static_ids_.clear();
  moving_ids_.clear();
  for (int id = 0; id < lm.size(); ++id) {
    const LMapEntry& e = lm[id];
    if (e.status == LandmarkStatus::kStatic && (f.has_landmark(id) || e.archived))
      static_ids_.push_back(id);  // candidates are not the map; archived landmarks are
    else if (e.status == LandmarkStatus::kMoving || (e.status == LandmarkStatus::kCandidate && e.was_moving))
      moving_ids_.push_back(id);
  }
  cut_chunks(static_ids_.data(), static_cast<int>(static_ids_.size()), moving_ids_.data(),
             static_cast<int>(moving_ids_.size()), chunk_sizes_, lm.size(), &spans_);
  num_chunks_ = static_cast<int>(std::min(spans_.size(), chunks_.size()));  // equal: the pool fits the largest map
  for (int k = 0; k < num_chunks_; ++k) {
    const ChunkSpan& sp = spans_[static_cast<std::size_t>(k)];
    lmap_snapshot_t& c = chunks_[static_cast<std::size_t>(k)];
    stamp(&c, now_utime, frame, robot_id_, incarnation_);
    c.seq = seq_;
    c.chunk = static_cast<int16_t>(k);
    c.num_chunks = static_cast<int16_t>(num_chunks_);
    c.id_begin = sp.id_begin;
    c.id_end = sp.id_end;
    grow_static(&c, sp.count_a);
    for (int i = 0; i < sp.count_a; ++i) {
      const int id = static_ids_[static_cast<std::size_t>(sp.first_a + i)];
      landmark_estimate_t& l = c.landmarks[static_cast<std::size_t>(i)];
      l.id = id;
      const LMapEntry& e = lm[id];
      const Eigen::Vector2d p = e.archived ? e.position : f.landmark(id);
      l.x = p.x();
      l.y = p.y();
      write_cov(l.cov, e.archived ? e.cov : f.landmark_cov(id));
    }
    grow_moving(&c, sp.count_b);
    for (int i = 0; i < sp.count_b; ++i) {
      const int id = moving_ids_[static_cast<std::size_t>(sp.first_b + i)];
      c.moving_ids[static_cast<std::size_t>(i)] = id;
      c.moving_frames[static_cast<std::size_t>(i)] = lm[id].moving_frame;
    }
  }
  return num_chunks_;
}

}  // namespace elaslam
