#pragma once
// The packing file ("confpack-packing", version 1; docs/packing-format.md) and the atomic file
// writes that every output of the toolkit goes through.
//
// The format is documented in full in README.md ("Packing file"). In short:
//
//   { "format": "confpack-packing", "version": 1,
//     "box": { "length_x", "width", "periodic_y", "wall_friction", "height" },
//     "grains": [ { "shape", "size", "params" (pinacoids only), "position", "orientation" } ],
//     "contacts": [ { "a", "b", "type", "points", "normal", "normal_force",
//                     "point_forces", "point_gaps", "tangent_force", "point_tangent_forces" } ] }
//
// Reading validates everything and refuses a bad file with one std::invalid_argument whose message
// names the file, the element and the field: "packing.json: grains[12].size: must be > 0 (got -1)".
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "core/packing.hpp"

namespace confpack::core {

/// Value of the "format" key of a packing file.
inline constexpr std::string_view kPackingFormat = "confpack-packing";
/// Version written by this build; readers accept exactly this version.
inline constexpr int kPackingVersion = 1;

/// The packing as a JSON document (format, version, box, grains, and contacts when present).
/// Throws std::invalid_argument if the packing would not read back (see validatePacking).
nlohmann::json toJson(const Packing& packing);

/// Parses and validates a packing document. `source` prefixes every error message (a file name).
Packing packingFromJson(const nlohmann::json& j, std::string_view source = "packing");

/// Checks the invariants that a packing file guarantees (finite numbers, positive sizes, grain
/// centres inside the box, unit orientations and normals, contact ids in range). Throws
/// std::invalid_argument naming the element and field; `source` prefixes the message.
void validatePacking(const Packing& packing, std::string_view source = "packing");

/// Writes the packing file atomically (temporary file in the same directory, then rename), so a
/// reader never sees a half-written file. Doubles are written in their shortest round-trip form,
/// so readPacking(writePacking(p)) gives back the same bits.
void writePacking(const Packing& packing, const std::filesystem::path& path);

/// Reads and validates a packing file (errors name the file, element and field).
Packing readPacking(const std::filesystem::path& path);

/// This host's name (gethostname), as private file names and run claims record it.
std::string hostName();

/// A name in `dir` that no other process on any node sharing the folder uses: ".STEM.HOST.PID.N",
/// N counting this process's names (pids repeat from node to node). For a file only this process
/// writes: a temporary before its rename, a program's output.
std::filesystem::path privateFileName(const std::filesystem::path& dir, std::string_view stem);

/// Writes `text` to `path` atomically: a uniquely named temporary file in the same directory is
/// written, flushed and renamed over `path` (rename is atomic within one file system). On any
/// failure the temporary is removed and std::runtime_error is thrown; `path` is then untouched.
void writeFileAtomically(const std::filesystem::path& path, std::string_view text);

/// Fault injection for a test build (tests/support/allocation_fault.hpp): called before each
/// writeFileAtomically with the file's path, a non-zero errno it returns makes that write fail
/// as the system's would (ENOSPC for a full disk, EIO for an I/O error). confpack itself never
/// sets one.
using WriteFault = int (*)(const std::filesystem::path& path);
void setWriteFault(WriteFault fault);

}  // namespace confpack::core
