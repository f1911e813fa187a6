// SPDX-License-Identifier: Apache-2.0
// LMap: each landmark's lifecycle as named transitions (candidate -> static ->
// moving -> returned), without a filter.
#include "elaslam/robot_node/lmap.hpp"

#include <gtest/gtest.h>

#include "scene.hpp"

namespace elaslam {
namespace {

// The rules of the test robot (test::robot_options): confirm_frames 3, return_frames 6,
// moving_after 2, missing_needed 3.
LifecycleRules rules() { return lifecycle_rules(test::robot_options(Mode::kEla)); }

// Confirm a fresh candidate: anchored at `frame`, then consistent until STATIC.
int sightings_until_confirmed(LMap* m, int id, int frame) {
  m->anchor_candidate(id, frame);
  int n = 1;
  while (!m->candidate_consistent(id)) ++n;
  return n + 1;
}

TEST(LMap, ANewLandmarkIsACandidateUntilConfirmFramesSightings) {
  LMap m(8, rules());
  EXPECT_EQ(m[1].status, LandmarkStatus::kUnknown);
  m.anchor_candidate(1, 10);
  EXPECT_EQ(m[1].status, LandmarkStatus::kCandidate);
  EXPECT_EQ(m[1].status_frame, 10);
  EXPECT_EQ(m[1].consistent_sightings, 1);
  EXPECT_FALSE(m.candidate_consistent(1));  // 2 of 3
  EXPECT_TRUE(m.candidate_consistent(1));   // 3 of 3
  EXPECT_FALSE(m.confirm(1, 12));           // new: an ADD, not a RETURN
  EXPECT_EQ(m[1].status, LandmarkStatus::kStatic);
  EXPECT_EQ(m[1].status_frame, 12);
  EXPECT_EQ(m.count(LandmarkStatus::kStatic), 1);
}

// confirm_frames_few: while the robot has few static landmarks (set by Robot each
// frame) a new candidate needs fewer sightings; one that was moving does not.
TEST(LMap, FewStaticLandmarksConfirmANewCandidateSooner) {
  LifecycleRules r = rules();
  r.confirm_frames_few = 2;
  LMap m(8, r);
  m.anchor_candidate(1, 10);
  m.set_few_static(true);
  EXPECT_TRUE(m.candidate_consistent(1));  // 2 of 2
  m.set_few_static(false);
  m.anchor_candidate(2, 10);
  EXPECT_FALSE(m.candidate_consistent(2));  // 2 of 3
  EXPECT_TRUE(m.candidate_consistent(2));
  LMap off(8, rules());  // confirm_frames_few 0: the rule is off
  off.set_few_static(true);
  off.anchor_candidate(1, 10);
  EXPECT_FALSE(off.candidate_consistent(1));
}

TEST(LMap, AnInconsistentCandidateIsReportedMovingOnceAfterMovingAfter) {
  LMap m(8, rules());
  m.anchor_candidate(2, 0);
  EXPECT_FALSE(m.candidate_inconsistent(2));  // 1 of 2
  m.anchor_candidate(2, 1);
  EXPECT_TRUE(m.candidate_inconsistent(2));   // 2 in a row: report MOVING
  EXPECT_TRUE(m[2].was_moving);
  EXPECT_EQ(m[2].times_moving, 1);
  m.anchor_candidate(2, 2);
  EXPECT_FALSE(m.candidate_inconsistent(2));  // reported already
  EXPECT_EQ(m[2].times_moving, 1);
  // A consistent sighting ends the streak.
  m.anchor_candidate(2, 3);
  m.candidate_consistent(2);
  EXPECT_EQ(m[2].outside_streak, 0);
}

TEST(LMap, AStaticLandmarkFoundMovingIsMovingOrReanchoredAndReturnsAfterReturnFrames) {
  LMap m(8, rules());
  sightings_until_confirmed(&m, 3, 0);
  m.confirm(3, 2);
  EXPECT_FALSE(m.outside_ela(3));
  m.inside_ela(3, false);  // the streak is of consecutive verdicts
  EXPECT_FALSE(m.outside_ela(3));
  EXPECT_TRUE(m.outside_ela(3));
  m.found_moving(3, 5, /*reanchored=*/true);
  EXPECT_EQ(m[3].status, LandmarkStatus::kCandidate);
  EXPECT_EQ(m[3].moved_frame, 5);
  EXPECT_EQ(m[3].consistent_sightings, 1);
  EXPECT_TRUE(m[3].reported_moving);
  EXPECT_EQ(m[3].outside_streak, 0);
  int n = 1;
  while (!m.candidate_consistent(3)) ++n;
  EXPECT_EQ(n + 1, 6);      // return_frames
  EXPECT_TRUE(m.confirm(3, 11));  // a RETURN
  EXPECT_FALSE(m[3].reported_moving);

  sightings_until_confirmed(&m, 4, 0);
  m.confirm(4, 2);
  m.found_moving(4, 7, /*reanchored=*/false);  // missing: not seen, so not re-anchored
  EXPECT_EQ(m[4].status, LandmarkStatus::kMoving);
  EXPECT_EQ(m[4].status_frame, 7);
}

TEST(LMap, ReturnBackoffDoublesReturnFramesEachFurtherTime) {
  LifecycleRules r = rules();
  r.return_backoff = true;
  LMap m(8, r);
  sightings_until_confirmed(&m, 0, 0);
  m.confirm(0, 0);
  for (int expected : {6, 12, 24}) {
    m.found_moving(0, 1, true);
    int n = 1;
    while (!m.candidate_consistent(0)) ++n;
    EXPECT_EQ(n + 1, expected);
    EXPECT_TRUE(m.confirm(0, 2));
  }
}

TEST(LMap, ANoticeRaisesTheBarEvenForALandmarkNotHeld) {
  LMap m(8, rules());
  m.told_moving(5, 3, /*left_filter=*/false);
  EXPECT_EQ(m[5].status, LandmarkStatus::kUnknown);
  EXPECT_TRUE(m[5].was_moving);
  EXPECT_EQ(sightings_until_confirmed(&m, 5, 4), 6);  // return_frames
  EXPECT_TRUE(m.confirm(5, 9));
  m.told_moving(5, 12, /*left_filter=*/true);
  EXPECT_EQ(m[5].status, LandmarkStatus::kMoving);
  EXPECT_EQ(m[5].status_frame, 12);
  EXPECT_EQ(m[5].consistent_sightings, 0);
  EXPECT_EQ(m[5].times_moving, 2);
}

// A notice is another robot's finding. It must not silence this
// robot's own MOVING report (were a notice to set reported_moving, once another
// robot had RETURNed the landmark at main this robot would never report it moving
// again).
TEST(LMap, ANoticeDoesNotSilenceThisRobotsOwnMovingReport) {
  LMap m(8, rules());
  m.told_moving(4, 3, /*left_filter=*/false);  // never held, never reported by this robot
  EXPECT_FALSE(m[4].reported_moving);
  m.anchor_candidate(4, 10);
  EXPECT_FALSE(m.candidate_inconsistent(4));
  m.anchor_candidate(4, 11);
  EXPECT_TRUE(m.candidate_inconsistent(4));  // its own finding: reported (once)
  EXPECT_TRUE(m[4].reported_moving);
  m.anchor_candidate(4, 12);
  EXPECT_FALSE(m.candidate_inconsistent(4));
}

TEST(LMap, MissedCountsExpectedFramesInARow) {
  LMap m(8, rules());
  sightings_until_confirmed(&m, 6, 0);
  m.confirm(6, 2);
  EXPECT_FALSE(m.missed(6, true));
  EXPECT_FALSE(m.missed(6, true));
  EXPECT_FALSE(m.missed(6, false));  // seen (or not expected): the run ends
  EXPECT_FALSE(m.missed(6, true));
  EXPECT_FALSE(m.missed(6, true));
  EXPECT_TRUE(m.missed(6, true));  // missing_needed = 3
}

TEST(LMap, DriftAndInnovationSums) {
  LMap m(8, rules());
  m.add_drift(1, 0.5, Eigen::Vector2d(2.0, 0.0));
  EXPECT_EQ(m.add_drift(1, 0.5, Eigen::Vector2d(0.0, 1.0)), Eigen::Vector2d(1.0, 1.0));
  m.anchor_candidate(2, 0);
  m.add_innovation(2, Eigen::Vector2d(1.0, 2.0));
  const LMapEntry& e = m.add_innovation(2, Eigen::Vector2d(1.0, 0.0));
  EXPECT_EQ(e.innovation_sum, Eigen::Vector2d(2.0, 2.0));
  EXPECT_EQ(e.innovations, 2);
  m.anchor_candidate(2, 1);  // a new streak forgets the sum
  EXPECT_EQ(m[2].innovations, 0);
  EXPECT_EQ(m[2].innovation_sum, Eigen::Vector2d::Zero());
  // Confirmation starts the drift sum afresh.
  m.add_drift(2, 0.5, Eigen::Vector2d(3.0, 0.0));
  while (!m.candidate_consistent(2)) {}
  m.confirm(2, 3);
  EXPECT_EQ(m[2].drift, Eigen::Vector2d::Zero());
}

TEST(LMap, DropAndClear) {
  LMap m(8, rules());
  m.anchor_candidate(3, 0);
  m.candidate_consistent(3);
  m.drop_candidate(3);
  EXPECT_EQ(m[3].consistent_sightings, 0);
  m.seen(3, 4);
  m.reported(3, 4);
  EXPECT_EQ(m[3].last_seen_frame, 4);
  m.clear();
  EXPECT_EQ(m[3].status, LandmarkStatus::kUnknown);
  EXPECT_EQ(m[3].last_seen_frame, -1);
  EXPECT_FALSE(m.valid_id(8));
  EXPECT_TRUE(m.valid_id(7));
}

}  // namespace
}  // namespace elaslam
