#pragma once
// Deposits on disk, so that a sweep computes the pile of one (configuration, seed) once and every
// backend (and every wall friction, which deposition does not see) compacts exactly the same
// grains, even when the runs are spread over restarts or cluster tasks.
//
// File format ("confpack-deposit", version 1):
//   { "format": "confpack-deposit", "version": 1,
//     "packing": <a confpack-packing document: box and grains after substitution>,
//     "placeholders": [[x, y, z], ...],          same order as packing.grains
//     "placeholder_diameter", "pile_height", "placeholder_solid_fraction", "solid_fraction",
//     "seconds" }
// Doubles are written in their shortest round-trip form, so a deposit read back is bit-identical.
#include <filesystem>
#include <nlohmann/json.hpp>

#include "compaction/deposition.hpp"
#include "core/box.hpp"

namespace confpack::study {

/// The deposit as a JSON document (see the format above). `box` is the box it was made for.
nlohmann::json depositToJson(const compaction::Deposit& deposit, const core::BoxDef& box);

/// Parses a deposit document; throws std::invalid_argument naming `source` and the bad field.
compaction::Deposit depositFromJson(const nlohmann::json& j, std::string_view source = "deposit");

/// Writes the deposit atomically (temporary file + rename): the file exists only when complete.
void writeDeposit(const compaction::Deposit& deposit, const core::BoxDef& box, const std::filesystem::path& path);

/// Reads a deposit file written by writeDeposit.
compaction::Deposit readDeposit(const std::filesystem::path& path);

}  // namespace confpack::study
