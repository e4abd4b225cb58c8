#pragma once
// Boxes of single faces for the model's tight box (model_info.cpp), cheaper than OCCT's
// BRepBndLib::AddOptimal where the surface allows it.

#include <Bnd_Box.hxx>
#include <TopoDS_Face.hxx>

namespace rdmesh {

/// A box that holds a face of revolution or of linear extrusion, from its basis curve's box over
/// the face's parameter range: that box swept around the axis (within the cylinder through its
/// farthest corner) or along the direction. Void when the basis curve's box may not hold it.
Bnd_Box SweptFaceBox(const TopoDS_Face& face);

/// The tight box of a face on a torus or a sphere, without the tolerances, as AddOptimal
/// computes it but in closed form: along each axis, the extremes of the face lie on its boundary
/// (the edges' optimal boxes) or at a critical point of that coordinate on the surface, a few of
/// which each surface has; each is kept when it lies on the face. Void for other surfaces.
Bnd_Box ClosedFormFaceBox(const TopoDS_Face& face);

/// The tight box of a face on any other curved surface (B-spline, Bezier, revolution, extrusion,
/// offset), without the tolerances: the edges' optimal boxes, and each coordinate's interior
/// extremes that lie on the face, found on a grid over the face's (u, v) bounds and polished by
/// Newton's method, each enlarged by Precision::Confusion() as AddOptimal enlarges the surface's.
/// Void when the face has no boundary to start from.
Bnd_Box SampledFaceBox(const TopoDS_Face& face);

}  // namespace rdmesh
