#pragma once
// STEP geometry (ISO 10303-42 entities) to OCCT Geom objects, built as OCCT 7.6's StepToGeom
// builds them: the same constructors on the same numbers, the same defaults for missing
// directions, the same knot merging and periodicity guesses for B-splines, so parameterisations
// match OCCT's reader exactly. Where StepToGeom returns no object (and OCCT's reader then drops
// an edge or a face) these throw Unsupported; a dangling reference throws Broken.
#include <Geom2d_Curve.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <gp_Ax1.hxx>
#include <gp_Ax2.hxx>
#include <gp_Ax2d.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Trsf.hxx>
#include <optional>
#include <unordered_map>

#include "model/step/entities.h"

namespace rdmesh::step {

/// The unit context geometry is read in (STEPControl_ActorRead::PrepareUnits): lengths in the
/// file's unit times `length` give millimetres, angles times `plane_angle` give radians.
struct UnitFactors {
  double length = 1.0;
  double plane_angle = 1.0;
  double precision = 1e-3;     ///< the file's uncertainty in mm (OCCT's "preci")
  double max_tolerance = 1.0;  ///< read.maxprecision.val, at least `precision`
};

class Geometry {
 public:
  explicit Geometry(const Entities& entities) : entities_(entities) {}

  /// A CARTESIAN_POINT with three coordinates, scaled.
  gp_Pnt Point(uint64_t id, uint64_t from, const UnitFactors& units) const;
  gp_Pnt2d Point2d(uint64_t id, uint64_t from) const;
  /// A DIRECTION with at least three ratios; nullopt where StepToGeom makes none (zero or
  /// infinite ratios).
  std::optional<gp_Dir> Direction(uint64_t id, uint64_t from) const;
  std::optional<gp_Dir2d> Direction2d(uint64_t id, uint64_t from) const;
  gp_Ax2 Axis2Placement(uint64_t id, uint64_t from, const UnitFactors& units) const;
  gp_Ax1 Axis1Placement(uint64_t id, uint64_t from, const UnitFactors& units) const;
  gp_Ax2d Axis2Placement2d(uint64_t id, uint64_t from) const;
  /// A CARTESIAN_TRANSFORMATION_OPERATOR_3D as StepToGeom::MakeTransformation3d reads it.
  gp_Trsf Transformation(uint64_t id, uint64_t from, const UnitFactors& units) const;

  /// A 3D curve, new. `depth` guards against reference cycles.
  Handle(Geom_Curve)
      Curve(uint64_t id, uint64_t from, const UnitFactors& units, int depth = 0) const;
  /// The 3D curve of an edge: built once per curve entity and shared by every edge on it, as
  /// OCCT's reader binds it in its transfer process.
  Handle(Geom_Curve) SharedCurve(uint64_t id, uint64_t from, const UnitFactors& units);
  /// A 2D curve (of a PCURVE's definitional representation), new; null where StepToGeom makes
  /// none (the reader then computes that pcurve).
  /// `units.plane_angle` trims 2D circles as StepToGeom does with the global angle factor.
  Handle(Geom2d_Curve)
      Curve2d(uint64_t id, uint64_t from, const UnitFactors& units, int depth = 0) const;
  /// A surface, new (OCCT builds one per face, never shared).
  Handle(Geom_Surface)
      Surface(uint64_t id, uint64_t from, const UnitFactors& units, int depth = 0) const;

  const Entities& entities() const { return entities_; }

 private:
  Handle(Geom_Curve) CurveOf(const Instance& instance, const UnitFactors& units, int depth) const;
  Handle(Geom2d_Curve)
      Curve2dOf(const Instance& instance, const UnitFactors& units, int depth) const;
  Handle(Geom_Surface)
      SurfaceOf(const Instance& instance, const UnitFactors& units, int depth) const;
  Handle(Geom_Curve) BSplineCurve(const Instance& instance, const UnitFactors& units) const;
  Handle(Geom2d_Curve) BSplineCurve2d(const Instance& instance) const;
  Handle(Geom_Surface) BSplineSurface(const Instance& instance, const UnitFactors& units) const;
  Handle(Geom_Curve)
      TrimmedCurve(const Instance& instance, const UnitFactors& units, int depth) const;
  Handle(Geom2d_Curve)
      TrimmedCurve2d(const Instance& instance, const UnitFactors& units, int depth) const;

  const Entities& entities_;
  std::unordered_map<uint64_t, Handle(Geom_Curve)> shared_curves_;
};

/// Reference chains deeper than this are taken for cycles (Broken): real files nest geometry a
/// few levels (a trimmed curve of a surface curve of a line).
constexpr int kMaxGeometryDepth = 32;

}  // namespace rdmesh::step
