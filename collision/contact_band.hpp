#pragma once
// Contact type by a distance band (docs/model.md, "Two readings of a packing"): the reading
// of a contact's type by LMGC90's points, beside the exact classifier of polyhedron_contact.hpp.
//
// Contact plane. n is the unit normal from a to b (pairs: the narrow phase's, pairNormal; a wall:
// into the wall), and the plane lies midway between the two bodies' support planes,
//     c = (max_{x in a} n.x + min_{x in b} n.x) / 2     (a wall: min_{x in b} n.x = n.(wall point)).
// Touching vertices. Every vertex of a with n.x >= c - w and every vertex of b with n.x <= c + w:
// within the band width w of the plane, or past it (an overlapping pair, an inflated packing). The
// caller gives w = B x (the pair's smaller size, or the grain's size for a wall).
// Region. The touching vertices of each body, projected on the plane, span a convex hull H_a, H_b
// (a point, a segment or a polygon); the touching region is H_a ∩ H_b (a wall's hull is the whole
// plane), whose vertices are the distinct positions at which the bodies touch:
//     1 position -> Simple,  2, or more on one line -> Double,  3 or more not on a line -> Triple.
// A pair whose hulls do not meet (a vertex beside an edge, off by less than w in height) touches
// at one position: Simple. Positions closer than kRelativeLengthTol x (R_a + R_b) are one.
//
// Against the exact rule (contact_region.hpp): both read the dimension of the region where the
// bodies touch; the exact rule takes each body's vertices within sin(1e-3) x 2R of its own support
// plane (a face counts as one only when it lies flat to a milliradian), the band within w of the
// common plane, so that a face tilted by up to about w / (its width) still reads as a face.
#include "collision/polyhedron_contact.hpp"

namespace confpack::collision {

/// Type of the contact of a and b by the band of width `width` [d_L] (> 0, finite) about their
/// contact plane, the normal computed by the narrow phase as classifyContact does (any gap).
ContactType classifyContactBand(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double width);

/// The same with an imposed unit normal from a towards b.
ContactType classifyContactBand(const PlacedPolyhedron& a, const PlacedPolyhedron& b, const Vec3& normal, double width);

/// Type of the contact of a with the flat wall {x : inwardNormal.(x - planePoint) >= 0}: the hull
/// of a's touching vertices alone (a wall touches wherever a does).
ContactType classifyPlaneContactBand(const PlacedPolyhedron& a, const Vec3& planePoint, const Vec3& inwardNormal,
                                     double width);

}  // namespace confpack::collision
