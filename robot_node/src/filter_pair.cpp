// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/filter_pair.hpp"

namespace elaslam {

FilterPair::FilterPair(const EkfOptions& options, bool aided, int history_frames, int history_ops)
    : own_(options),
      own_history_(options, history_frames, history_ops),
      aided_history_(options, aided ? history_frames : 0, history_ops) {
  if (aided) aided_.emplace(options);
}

void FilterPair::reset(const Pose2& odometer, const Eigen::Matrix3d& P0) {
  own_.reset(odometer, P0);
  if (aided_) aided_->reset(odometer, P0);
  restart_history();
}

EkfStatus FilterPair::predict(int frame, const Pose2& increment, const Eigen::Matrix3d& U, double dt, int* faults) {
  const FilterHistory::Op op = FilterHistory::predict(frame, increment, U, dt);
  const EkfStatus st = own_.predict(increment, U, dt);
  if (st == EkfStatus::kOk) {
    own_history_.record(op);
  } else {
    ++*faults;
  }
  to_aided(op, faults);
  return st;
}

UpdateReport FilterPair::update(int frame, int id, const RangeBearing& z, bool gate, int* faults) {
  const UpdateReport r = own_.update(id, z, gate);
  if (r.status != EkfStatus::kOk) return r;
  const FilterHistory::Op op = FilterHistory::update(frame, id, z);
  own_history_.record(op);
  to_aided(op, faults);
  return r;
}

EkfStatus FilterPair::move_landmark(int frame, int id, const Eigen::Vector2d& delta, const Eigen::Matrix2d& Q,
                                     int* faults) {
  const EkfStatus st = own_.move_landmark(id, delta, Q);
  if (st != EkfStatus::kOk) return st;
  const FilterHistory::Op op = FilterHistory::move(frame, id, delta, Q);
  own_history_.record(op);
  to_aided(op, faults);
  return st;
}

void FilterPair::update_landmark_only(int frame, int id, const RangeBearing& z, int* faults) {
  const FilterHistory::Op op = FilterHistory::update_landmark_only(frame, id, z);
  if (!own_history_.apply_and_record(op, &own_)) ++*faults;
  to_aided(op, faults);
}

// The team channel is kept (team_aid.hpp): what the team's estimate taught the pose
// and map before the landmark left stays in the aided filter.
EkfStatus FilterPair::add(int frame, int id, const RangeBearing& z, int* faults) {
  const EkfStatus st = own_.add_landmark(id, z);
  if (st != EkfStatus::kOk) return st;
  const FilterHistory::Op op = FilterHistory::add(frame, id, z);
  own_history_.record(op);
  to_aided(op, faults);
  return st;
}

EkfStatus FilterPair::remove(int frame, int id) {
  const FilterHistory::Op op = FilterHistory::remove(frame, id);
  const EkfStatus st = own_.remove_landmark(id);
  if (st == EkfStatus::kOk) own_history_.record(op);
  to_aided(op, nullptr);
  return st;
}

int FilterPair::end_frame(int frame) {
  int refused = own_history_.end_frame(frame, &own_);
  if (aided_) refused += aided_history_.end_frame(frame, &*aided_);
  return refused;
}

void FilterPair::upgrade(int id, FilterHistory::Op* held) {
  own_history_.upgrade(id);
  aided_history_.upgrade(id, held);
}

void FilterPair::restart_history() {
  own_history_.restart(own_);
  if (aided_) aided_history_.restart(*aided_);
}

EkfStatus FilterPair::apply_rigid_motion(double own_rotation, const Eigen::Vector2d& own_translation,
                                         double aided_rotation, const Eigen::Vector2d& aided_translation) {
  const EkfStatus st = own_.apply_rigid_motion(own_rotation, own_translation);
  if (st != EkfStatus::kOk) return st;
  if (aided_) aided_->apply_rigid_motion(aided_rotation, aided_translation);
  return st;
}

UpdateReport FilterPair::update_aided_position(int frame, int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) {
  const UpdateReport r = aided_->update_position(id, z, R);
  if (r.status == EkfStatus::kOk) aided_history_.record(FilterHistory::update_position(frame, id, z, R));
  return r;
}

void FilterPair::hold_aided_position(int frame, int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) {
  aided_history_.record(FilterHistory::held_position(frame, id, z, R));
}

void FilterPair::to_aided(const FilterHistory::Op& op, int* faults) {
  if (aided_ && !aided_history_.apply_and_record(op, &*aided_) && faults != nullptr) ++*faults;
}

}  // namespace elaslam
