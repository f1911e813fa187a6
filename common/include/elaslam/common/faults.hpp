// SPDX-License-Identifier: Apache-2.0
// The conditions a node flags in its STATUS (node_status_t.fault_flags), by name: one
// place for what the monitor, the viewer and the tools call each bit.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "elaslam/node_status_t.hpp"

namespace elaslam {

/// The names of the FAULT_* bits set in `flags`, in bit order ("duplicate sender",
/// "unrepaired gap", ..., "partition healed"); bits no constant defines are left out.
inline std::vector<std::string> fault_names(std::int32_t flags) {
  struct Bit {
    std::int32_t bit;
    const char* name;
  };
  static constexpr Bit kBits[] = {
      {node_status_t::FAULT_DUPLICATE_SENDER, "duplicate sender"},
      {node_status_t::FAULT_UNREPAIRED_GAP, "unrepaired gap"},
      {node_status_t::FAULT_CAPACITY, "capacity"},
      {node_status_t::FAULT_INCONSISTENT, "inconsistent"},
      {node_status_t::FAULT_FRAMES_LOST, "frames lost"},
      {node_status_t::FAULT_INPUT_REFUSED, "input refused"},
      {node_status_t::FAULT_SAVE_FAILED, "save failed"},
      {node_status_t::FAULT_MAIN_SILENT, "main silent"},
      {node_status_t::FAULT_INCARNATION, "incarnation refused"},
      {node_status_t::FAULT_PARTITION_HEALED, "partition healed"},
      {node_status_t::FAULT_RELOCALISED, "relocalised"},
  };
  std::vector<std::string> out;
  for (const Bit& b : kBits)
    if ((flags & b.bit) != 0) out.emplace_back(b.name);
  return out;
}

}  // namespace elaslam
