#pragma once
// Exact volumes of sphere pieces used by the analysis (docs/model.md, "Interpenetration",
// "Solid fraction", "Solid-fraction profiles and their fit"): spherical segments
// (a sphere cut by two parallel planes) and lenses (the intersection of two spheres).
//
// These are closed forms, not sampling. Polyhedra use collision/polyhedron_clip.hpp instead.

namespace confpack::analysis {

/// Volume of the part of a sphere (radius r, centre coordinate c along some axis) lying between
/// the planes t = lo and t = hi of that axis (a spherical segment) [d_L^3]. Returns 0 when
/// hi <= lo.
///
/// With u = t - c clamped to [-r, r], the volume below the plane is
///   V_below(u) = pi (r^2 u - u^3/3 + 2 r^3/3)
/// (integral of the disc area pi (r^2 - s^2) for s from -r to u), so the segment is
/// V_below(hi - c) - V_below(lo - c).
double sphereSlabVolume(double radius, double centre, double lo, double hi);

/// Volume of the intersection of two spheres of radii r1, r2 whose centres are `distance` apart
/// [d_L^3]: 0 when separated, the smaller sphere when one contains the other, else the lens
///   V = pi (r1 + r2 - d)^2 (d^2 + 2 d (r1 + r2) - 3 (r1 - r2)^2) / (12 d),
/// the sum of the two spherical caps cut by the radical plane.
double sphereLensVolume(double r1, double r2, double distance);

/// Volume of a sphere of radius r [d_L^3].
double sphereVolume(double radius);

}  // namespace confpack::analysis
