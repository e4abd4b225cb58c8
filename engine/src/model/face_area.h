#pragma once
// Face areas in closed form where the surface allows it (model.cpp's ComputeFaceAreas).
#include <TopoDS_Face.hxx>
#include <optional>

namespace rdmesh {

/// The area of a face on a plane or a cylinder whose pcurves are all lines and circles, in
/// closed form: such a surface's area element is constant (1 on a plane, the radius on a
/// cylinder), and the area of its (u, v) domain is the sum over the pcurves of the integral of
/// (p - o) x dp / 2, exact for lines and circular arcs, taken about the first end o (so that a
/// face far from the surface's origin loses no digits). Nothing for other faces, and for faces
/// placed with a scale.
std::optional<double> ClosedFormFaceArea(const TopoDS_Face& face);

}  // namespace rdmesh
