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

/// The area of a face on a B-spline surface that covers the surface's whole parameter rectangle
/// (one wire, every pcurve an iso-line on the rectangle's border, together once round it): the
/// integral of |Su x Sv| over each knot span by tensor Gauss rules of degree + 4 and degree + 8
/// points each way, the span quartered where they differ by more than 1e-9 of it. The torus as
/// a rational B-spline reads 4 pi^2 R r within 2e-16 (BRepGProp's default rule 0.5% short);
/// KiCad's beaded test loops (two such faces of degree 6 x 9) 4x faster than BRepGProp. Nothing
/// for other faces, for faces placed with a scale, and where the rules would take more than
/// 40,000 points.
std::optional<double> NaturalPatchArea(const TopoDS_Face& face);

}  // namespace rdmesh
