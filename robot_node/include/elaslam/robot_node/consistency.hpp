// SPDX-License-Identifier: Apache-2.0
// The filter's consistency monitor (a robot that is lost says so and
// recovers). A Kalman filter's sequential innovations are independent with known
// covariances, so the sum of their normalised squares (NIS, d2 each with 2 dof) over
// a window of frames is chi-square with twice the number of corrections as degrees
// of freedom. A robot whose pose estimate has gone wrong while it believes itself
// certain (a heading error after a bad turn, a map that has slipped) produces
// innovations far beyond their covariance frame after frame; the ELA gate does not
// stop them, because eq 16 cancels the robot's own pose error. When the window's
// NIS exceeds its quantile the robot is `inconsistent`.
//
// Fixed memory (a ring of window_frames entries, allocated at construction);
// O(1) per frame: the quantile is Wilson-Hilferty's approximation (accurate to
// about 1 % of the value from 20 dof), with the normal quantile computed once.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace elaslam {

class ConsistencyMonitor {
 public:
  /// `window_frames` 0: off (never inconsistent). `probability`: the test's
  /// quantile (a consistent filter is found inconsistent with 1 - probability per
  /// independent window). `min_dof`: fewer degrees of freedom in the window: no verdict.
  ConsistencyMonitor(int window_frames, double probability, int min_dof = 20);

  /// One correction of this frame: its innovation's d2 (2 dof).
  void add(double d2) {
    frame_nis_ += d2;
    frame_dof_ += 2;
  }
  /// End of a frame: the window moves on; returns the verdict (true: inconsistent).
  bool end_frame();
  /// Empty the window (after a recovery: the old innovations say nothing of the new state).
  void restart();

  /// The window's frames, oldest first: (NIS, dof) each (the robot's state file
  /// keeps them; allocates, not for the frame's path).
  std::vector<std::pair<double, int>> window() const;
  /// Empty the window and refill it with `frames`, oldest first, as end_frame would
  /// (the verdict is recomputed); beyond window_frames only the newest are kept.
  void restore(const std::vector<std::pair<double, int>>& frames);
  int window_frames() const { return static_cast<int>(ring_.size()); }

  bool inconsistent() const { return inconsistent_; }
  /// The last ended frame's NIS and degrees of freedom (0 and 0 without a correction).
  double frame_nis() const { return last_nis_; }
  int frame_dof() const { return last_dof_; }
  double window_nis() const { return nis_; }
  int window_dof() const { return dof_; }
  /// The threshold of the window's NIS for `dof` degrees of freedom.
  double threshold(int dof) const;

 private:
  struct Entry {
    double nis = 0.0;
    int dof = 0;
  };
  std::vector<Entry> ring_;
  std::size_t next_ = 0;
  std::size_t filled_ = 0;
  double z_ = 0.0;  // standard normal quantile of `probability`
  int min_dof_;
  double frame_nis_ = 0.0;
  int frame_dof_ = 0;
  double last_nis_ = 0.0;
  int last_dof_ = 0;
  double nis_ = 0.0;
  int dof_ = 0;
  bool inconsistent_ = false;
};

}  // namespace elaslam
