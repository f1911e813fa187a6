// SPDX-License-Identifier: Apache-2.0
// FilterHistory: a lagged copy of the filter and the operations since (filter_history.hpp).
#include "elaslam/robot_node/filter_history.hpp"

#include <algorithm>

namespace elaslam {

FilterHistory::FilterHistory(const EkfOptions& options, int window_frames, int max_ops)
    : window_(std::max(0, window_frames)) {
  if (window_ == 0) return;
  lagged_.emplace(options);
  ops_.resize(static_cast<std::size_t>(std::max(1, max_ops)));
}

namespace {

FilterHistory::Op op_of(FilterHistory::Kind kind, int frame, int id) {
  FilterHistory::Op op;
  op.kind = kind;
  op.frame = frame;
  op.id = id;
  return op;
}

FilterHistory::Op sighting(FilterHistory::Kind kind, int frame, int id, const RangeBearing& z) {
  FilterHistory::Op op = op_of(kind, frame, id);
  op.z = z;
  return op;
}

}  // namespace

FilterHistory::Op FilterHistory::predict(int frame, const Pose2& increment, const Eigen::Matrix3d& U, double dt) {
  Op op = op_of(Kind::kPredict, frame, -1);
  op.increment = increment;
  op.U = U;
  op.dt = dt;
  return op;
}
FilterHistory::Op FilterHistory::update(int frame, int id, const RangeBearing& z) {
  return sighting(Kind::kUpdate, frame, id, z);
}
FilterHistory::Op FilterHistory::update_landmark_only(int frame, int id, const RangeBearing& z) {
  return sighting(Kind::kLandmarkOnly, frame, id, z);
}
FilterHistory::Op FilterHistory::update_position(int frame, int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) {
  Op op = op_of(Kind::kPosition, frame, id);
  op.p = z;
  op.R = R;
  return op;
}
FilterHistory::Op FilterHistory::held_position(int frame, int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) {
  Op op = update_position(frame, id, z, R);
  op.kind = Kind::kHeldPosition;
  return op;
}
FilterHistory::Op FilterHistory::add(int frame, int id, const RangeBearing& z) { return sighting(Kind::kAdd, frame, id, z); }
FilterHistory::Op FilterHistory::remove(int frame, int id) { return op_of(Kind::kRemove, frame, id); }
FilterHistory::Op FilterHistory::move(int frame, int id, const Eigen::Vector2d& delta, const Eigen::Matrix2d& Q) {
  Op op = update_position(frame, id, delta, Q);
  op.kind = Kind::kMove;
  return op;
}

void FilterHistory::record(const Op& op) {
  if (!enabled()) return;
  if (count_ == static_cast<int>(ops_.size())) commit_oldest();
  at(count_++) = op;
}

bool FilterHistory::apply_and_record(const Op& op, EkfSlam* f) {
  if (!apply(op, f)) return false;
  record(op);
  return true;
}

void FilterHistory::restart(const EkfSlam& current) {
  if (!enabled()) return;
  lagged_->assign(current);
  head_ = 0;
  count_ = 0;
  dirty_ = false;
}

int FilterHistory::upgrade(int id, Op* position) {
  int n = 0;
  for (int k = 0; k < count_; ++k) {
    Op& op = at(k);
    if (op.kind == Kind::kLandmarkOnly && op.id == id) {
      op.kind = Kind::kUpdate;
      ++n;
    }
  }
  // The newest held team increment since the candidate's last add.
  for (int k = count_ - 1; k >= 0; --k) {
    Op& op = at(k);
    if (op.id != id) continue;
    if (op.kind == Kind::kAdd) break;
    if (op.kind != Kind::kHeldPosition) continue;
    op.kind = Kind::kPosition;
    if (position != nullptr) *position = op;
    ++n;
    break;
  }
  if (n > 0) dirty_ = true;
  upgraded_ += n;
  return n;
}

const char* FilterHistory::to_string(Kind k) {
  switch (k) {
    case Kind::kPredict: return "predict";
    case Kind::kUpdate: return "update";
    case Kind::kLandmarkOnly: return "landmark_only";
    case Kind::kPosition: return "position";
    case Kind::kAdd: return "add";
    case Kind::kRemove: return "remove";
    case Kind::kHeldPosition: return "held_position";
    case Kind::kMove: return "move";
  }
  return "?";
}

EkfStatus FilterHistory::restore(const Eigen::VectorXd& x, const Eigen::MatrixXd& P, const std::vector<int>& slot_ids,
                                 const std::vector<Op>& ops) {
  if (!enabled()) return EkfStatus::kBadInput;
  const EkfStatus st = lagged_->restore(x, P, slot_ids);
  if (st != EkfStatus::kOk) return st;
  // More than the ring holds (saved with a longer window): the oldest go into the
  // lagged filter now, as they would have had the ring been this size.
  const std::size_t excess = ops.size() > ops_.size() ? ops.size() - ops_.size() : 0;
  for (std::size_t k = 0; k < excess; ++k) apply(ops[k], &*lagged_);
  head_ = 0;
  count_ = static_cast<int>(ops.size() - excess);
  std::copy(ops.begin() + static_cast<std::ptrdiff_t>(excess), ops.end(), ops_.begin());
  dirty_ = false;
  return EkfStatus::kOk;
}

bool FilterHistory::apply(const Op& op, EkfSlam* f) {
  switch (op.kind) {
    case Kind::kPredict: return f->predict(op.increment, op.U, op.dt) == EkfStatus::kOk;
    case Kind::kUpdate: return f->update(op.id, op.z, false).status == EkfStatus::kOk;
    case Kind::kLandmarkOnly: return f->update_landmark_only(op.id, op.z).status == EkfStatus::kOk;
    case Kind::kPosition: return f->update_position(op.id, op.p, op.R).status == EkfStatus::kOk;
    case Kind::kAdd: return f->add_landmark(op.id, op.z) == EkfStatus::kOk;
    case Kind::kRemove: return f->remove_landmark(op.id) == EkfStatus::kOk;
    case Kind::kHeldPosition: return true;  // nothing until the candidate is confirmed (upgrade)
    case Kind::kMove: return f->move_landmark(op.id, op.p, op.R) == EkfStatus::kOk;
  }
  return false;
}

void FilterHistory::commit_oldest() {
  apply(at(0), &*lagged_);  // a refusal leaves the lagged filter as it was, as it left the current one
  head_ = (head_ + 1) % static_cast<int>(ops_.size());
  --count_;
}

int FilterHistory::end_frame(int frame, EkfSlam* current) {
  if (!enabled()) return 0;
  while (count_ > 0 && at(0).frame <= frame - window_) commit_oldest();
  if (!dirty_) return 0;
  dirty_ = false;
  ++rebuilds_;
  current->assign(*lagged_);
  int refused = 0;
  for (int k = 0; k < count_; ++k)
    if (!apply(at(k), current)) ++refused;
  return refused;
}

}  // namespace elaslam
