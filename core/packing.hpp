#pragma once
// A packing: the box, the grains and, optionally, their contacts with forces
// (docs/packing-format.md). This is the snapshot that analysis reads and that `confpack analyze`
// loads from a file.
#include <optional>
#include <string>
#include <vector>

#include "core/box.hpp"
#include "core/contact.hpp"
#include "core/grain.hpp"
#include "core/walls.hpp"

namespace confpack::core {

struct Packing {
  BoxDef box;
  WallMaterial walls;  ///< the material of the walls it was made between (the file's box.wall_friction)
  std::vector<Grain> grains;
  /// Contacts with forces, as written by a run; empty optional = file had none (analysis then
  /// uses geometric contacts).
  std::optional<std::vector<Contact>> contacts;
};

}  // namespace confpack::core
