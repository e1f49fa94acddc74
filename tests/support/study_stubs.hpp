#pragma once
// A stand-in depositor for study tests that write their runs' results themselves: one grain in
// the middle of the box, so that the sweep has a deposit to hand each run without depositing.
#include "compaction/deposition.hpp"
#include "core/run_config.hpp"

namespace confpack::testing {

inline compaction::Deposit oneGrainDeposit(const core::RunConfig& cfg) {
  compaction::Deposit d;
  core::Grain g;
  g.position = core::Vec3(1.0, 0.5 * cfg.box.width, 0.5);
  d.grains.push_back(g);
  d.placeholders.push_back(g.position);
  return d;
}

}  // namespace confpack::testing
