#include "elaslam/robot_node/lmap.hpp"

#include <algorithm>

namespace elaslam {

const char* to_string(LandmarkStatus s) {
  switch (s) {
    case LandmarkStatus::kUnknown: return "unknown";
    case LandmarkStatus::kCandidate: return "candidate";
    case LandmarkStatus::kStatic: return "static";
    case LandmarkStatus::kMoving: return "moving";
  }
  return "?";
}

LMap::LMap(int max_landmark_id) : entries_(static_cast<std::size_t>(std::max(max_landmark_id, 0))) {}

void LMap::clear() { std::fill(entries_.begin(), entries_.end(), LMapEntry{}); }

void LMap::set_status(int id, LandmarkStatus s, int frame) {
  LMapEntry& e = (*this)[id];
  if (e.status != s) e.status_frame = frame;
  e.status = s;
}

int LMap::count(LandmarkStatus s) const {
  return static_cast<int>(std::count_if(entries_.begin(), entries_.end(),
                                        [s](const LMapEntry& e) { return e.status == s; }));
}

}  // namespace elaslam
