// SPDX-License-Identifier: Apache-2.0
// main_robot's state file (--state PATH): the global map, kept across restarts.
// The body is GlobalMap::to_json's document (format key "elaslam.global_map.v1", as
// before); the file seals it (common/state_seal.hpp: format "elaslam.global_map",
// version 2, a BLAKE2b-256 MAC over the whole file, keyed when a state key is given).
// A file that is too large, does not open (damaged, altered, another key) or fails a
// check is moved aside to PATH.corrupt and main starts fresh: the robots' snapshots
// rebuild the map, and a bad file must not keep the team's main down.
// docs/security.md, "main_robot's state file". The process (main_robot/main.cpp) and any in-process
// caller use the same functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "elaslam/common/state_seal.hpp"
#include "elaslam/main_robot/global_map.hpp"

namespace elaslam {

constexpr const char* kMapStateFormat = "elaslam.global_map";
/// 2: the sealed file. (1, a bare JSON document without a seal, is not read.)
constexpr int kMapStateVersion = 2;

// ---- bounds of the file, beyond what from_json checks ------------------------------
/// A robot's event and snapshot seq (and a pending repair's): a robot sends at most a
/// few hundred events a frame (~9 in a real run) and skips 2^24 at each resume from
/// its state file, so 2^40 is decades at 100 Hz (39 years at 9 a frame; a year of the
/// worst case, 328 every frame), or 65,536 resumes. (Messages may say up to 2^62.)
constexpr std::int64_t kMaxStateSeq = std::int64_t{1} << 40;
/// A robot's incarnation (its start, wall-clock microseconds: 2^62 us is 146,000
/// years). 0, "none seen yet", is not written.
constexpr std::int64_t kMaxStateIncarnation = std::int64_t{1} << 62;
/// The most bytes one landmark's record takes in the body: 4,831 with all 16 robots'
/// estimates and the fused one, every number at its longest (24 characters:
/// -1.2345678901234567e-300), every frame 2147483647 and both flags; counted with a
/// margin of 27 % (a longer key, a new optional field).
constexpr std::size_t kMaxLandmarkRecordBytes = 6144;
/// The same for one robot's record: 206 bytes at the most (seq 2^40, incarnation 2^62).
constexpr std::size_t kMaxRobotRecordBytes = 256;
/// The body's own keys and brackets: 162 bytes at the most.
constexpr std::size_t kMaxMapStateFixedBytes = 1024;

/// The largest state file a map of these options can need, and so the largest one
/// read: max_landmark_id x kMaxLandmarkRecordBytes + kMaxTeamRobots x
/// kMaxRobotRecordBytes + kMaxMapStateFixedBytes + the seal (162 bytes:
/// sealed_state_overhead): 1,578,146 bytes for the default 256 ids, 201,890 for 32.
/// Checked before the file is read.
std::size_t max_map_state_bytes(const GlobalMapOptions& o);

/// "" when `map` is within the state file's bounds (kMaxStateSeq,
/// kMaxStateIncarnation), else the first field beyond them. A running map can go
/// beyond them only through messages (which may say seq up to 2^62 and any
/// non-negative incarnation); such a map is not saved (save_map_state).
std::string map_state_out_of_bounds(const GlobalMap& map);

/// The state file's text: GlobalMap::to_json sealed (key nullptr: unkeyed). False with
/// `why` when the map is beyond the file's bounds, or the text beyond
/// max_map_state_bytes (a file the loader would refuse is never written).
bool seal_map_state(const GlobalMap& map, const StateKey* key, std::string* text, std::string* why);

/// A state file's text into `map`: the seal opened (state_seal.hpp), the body parsed
/// and checked (GlobalMap::from_json), the file's bounds checked. False with `why`,
/// `map` unchanged, at the first problem.
bool open_map_state(std::string_view text, const StateKey* key, GlobalMap* map, std::string* why);

/// Seals `map` and writes it to `path` with files::write_atomic (a mkstemp temporary
/// beside it, fsync, rename: never half a file, never through a planted link). False
/// with `why` when it was not written; `path` is then as it was. The caller decides
/// what to say.
bool save_map_state(const std::string& path, const GlobalMap& map, const StateKey* key, std::string* why);

enum class MapStateOutcome {
  kResumed,           // the map is the file's
  kMissing,           // no file at PATH: a first start, the map is empty
  kFreshAfterDamage,  // the file was refused (why), moved aside to PATH.corrupt when it could be: the map is empty
};
const char* to_string(MapStateOutcome o);

struct MapStateLoad {
  MapStateOutcome outcome = MapStateOutcome::kMissing;
  std::string why;    // kFreshAfterDamage: what was wrong with the file
  std::string aside;  // kFreshAfterDamage: where it went; "" when it could not be moved (why_kept)
  std::string why_kept;
  std::string line;   // all of it in one line, for the log (without the program's name)
};

/// Loads `path` into `map` (which the caller made fresh). Missing: kMissing, nothing
/// touched. Larger than max_map_state_bytes(map->options()) (not read at all), not
/// readable, or refused by open_map_state: kFreshAfterDamage, the file renamed to
/// PATH.corrupt (rename(2): a symbolic link at either name is never followed, an
/// existing PATH.corrupt is replaced atomically) and `map` left as it was.
MapStateLoad load_map_state(const std::string& path, const StateKey* key, GlobalMap* map);

}  // namespace elaslam
