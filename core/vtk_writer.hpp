#pragma once
// ParaView output (docs/model.md, "ParaView"; README, "ParaView"): VTK XML PolyData (.vtp)
// frames and .pvd time collections.
//
// Hand-written rather than through libvtk: Debian's libvtk9-dev pulls in hundreds of packages
// (Qt, MPI, ...) for what is a few hundred lines of well-specified XML. The files are ASCII
// (human-readable, diffable; size is not a concern at these grain counts) and follow the
// "VTK XML formats" specification: VTKFile type="PolyData" version="1.0" byte_order="LittleEndian",
// one Piece with Points, Verts / Lines / Polys (connectivity + offsets) and Point/CellData.
//
// Per frame k, in the series directory:
//   <base>_grains_<k>.vtp    spheres as vertices (point data: diameter, id, velocity) and pinacoids
//                           as world-space polygon faces (cell data: id, diameter)
//   <base>_contacts_<k>.vtp  one line per contact, from the centre of grain a to the centre of b
//                           (nearest periodic image) or to the contact point on a wall
//                           (cell data: normal_force, type 0/1/2 = simple/double/triple, normal,
//                           wall 0/1)
//   <base>_grains.pvd, <base>_contacts.pvd   the collections with the frame times
// In ParaView: open the .pvd; for spheres apply Glyph (Sphere, Scale Array = diameter, scale
// factor 1, Glyph Mode = All Points).
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "core/packing.hpp"

namespace confpack::core {

/// Counts written into one frame (what a reader will find in the Pieces).
struct VtkFrameCounts {
  int grainPoints = 0;  ///< points of the grains file (sphere centres + pinacoid vertices)
  int verts = 0;        ///< vertex cells (one per sphere)
  int polys = 0;        ///< polygon cells (one per pinacoid face)
  int lines = 0;        ///< contact lines (0 when the packing has no contacts)
};

/// Writes the grains of a packing as one .vtp file (returns what it wrote). `velocities` is
/// empty or one per grain.
VtkFrameCounts writeGrainsVtp(const Packing& packing, const std::filesystem::path& path,
                              std::span<const Vec3> velocities = {});
/// Writes the contacts of a packing (none if it has no contact list) as one .vtp file of lines.
int writeContactsVtp(const Packing& packing, const std::filesystem::path& path);

/// A time series of frames with its .pvd collections. Every file is written atomically and the
/// .pvd is rewritten after each frame, so a run that stops early still leaves a valid series.
class VtkSeries {
 public:
  /// Creates `directory` if needed. File names start with `basename`.
  VtkSeries(std::filesystem::path directory, std::string basename);

  /// Writes frame number frameCount() at `time` [t0]: grains, and contacts when the packing has a
  /// contact list. `velocities`: empty, or one per grain [sqrt(g d_L)].
  VtkFrameCounts addFrame(double time, const Packing& packing, std::span<const Vec3> velocities = {});
  /// Writes the .pvd collections (also done after every frame; call once at the end).
  void finish();

  int frameCount() const { return static_cast<int>(grainFrames_.size()); }
  std::filesystem::path grainsCollection() const { return directory_ / (basename_ + "_grains.pvd"); }
  std::filesystem::path contactsCollection() const { return directory_ / (basename_ + "_contacts.pvd"); }

 private:
  struct Entry {
    double time;
    std::string file;  ///< relative to the directory, so the series can be moved
  };
  std::filesystem::path directory_;
  std::string basename_;
  std::vector<Entry> grainFrames_;
  std::vector<Entry> contactFrames_;
};

}  // namespace confpack::core
