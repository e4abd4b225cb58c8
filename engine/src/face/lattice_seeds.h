#pragma once
// Interior seeds for a sphere or torus face at a given deviation, laid out as a triangular
// lattice whose triangles stand just within the deviation: a closed sphere takes a geodesic
// lattice (an icosahedron's faces divided in the Goldberg-Coxeter way, relaxed to equal
// edges), a partial one rings of latitude, a torus rows about its axis spaced by its two
// curvatures. Refinement starts from there instead of splitting
// its way down from a coarse triangulation and then collapsing most of what it made: the
// interpolating minimum is a mesh of equal equilateral triangles, which such a lattice comes
// close to.

#include <vector>

#include "boundary/face_domain.h"
#include "core/geom.h"
#include "geometry/surface.h"

namespace rdmesh {

/// Lattice seeds for a face whose surface is a sphere in OCCT's parameters (u the longitude,
/// v the latitude in [-pi/2, pi/2]) on `surface`, for triangles within `max_deviation`. A face
/// whose domain spans every longitude and latitude takes the geodesic lattice of the coarsest
/// class whose equal triangles stand within 0.95 of it; others take rings of latitude at 0.85
/// of it. Seeds lie inside the domain and clear of its boundary by 0.4 of a lattice edge in 3D.
/// Empty when a lattice edge would turn more than pi/8 (a coarse request: the grid of
/// SeedPoints serves) or when it would need more than `max_seeds` seeds.
std::vector<Vec2> SphereLatticeSeeds(const FaceDomain& domain, Surface& surface,
                                     double max_deviation, size_t max_seeds);

/// Lattice seeds for a face whose surface is a torus in OCCT's parameters (u about the axis, v
/// about the tube) on `surface`: rows of constant v one lattice row apart, each with the points
/// its curvature along the row allows, for triangles within kTorusFill of `max_deviation` (a
/// triangle equilateral in the metric of the principal curvatures; on the inner, saddle half,
/// longer along the rows). Empty for a self-intersecting torus, a coarse request (0.9 x the
/// deviation at a quarter of the tube's radius or more) or more than `max_seeds` seeds.
std::vector<Vec2> TorusLatticeSeeds(const FaceDomain& domain, Surface& surface,
                                    double max_deviation, size_t max_seeds);

}  // namespace rdmesh
