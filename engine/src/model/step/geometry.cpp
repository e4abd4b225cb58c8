#include "model/step/geometry.h"

#include <ElCLib.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_Circle.hxx>
#include <Geom2d_Ellipse.hxx>
#include <Geom2d_Hyperbola.hxx>
#include <Geom2d_Line.hxx>
#include <Geom2d_Parabola.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <GeomAbs_Shape.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Circle.hxx>
#include <Geom_ConicalSurface.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Ellipse.hxx>
#include <Geom_Hyperbola.hxx>
#include <Geom_Line.hxx>
#include <Geom_OffsetSurface.hxx>
#include <Geom_Parabola.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SphericalSurface.hxx>
#include <Geom_SurfaceOfLinearExtrusion.hxx>
#include <Geom_SurfaceOfRevolution.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <Precision.hxx>
#include <ShapeAnalysis_Curve.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <TColgp_Array1OfPnt2d.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <cmath>
#include <gp.hxx>
#include <gp_Ax22d.hxx>
#include <gp_Ax3.hxx>
#include <gp_Lin.hxx>
#include <gp_Vec.hxx>
#include <gp_Vec2d.hxx>
#include <string>
#include <vector>

namespace rdmesh::step {

namespace {

// Multiplicities above this are refused before any arithmetic on them: a B-spline's are at most
// its degree + 1 (26), and larger values from a hostile file would overflow the sums.
constexpr int64_t kMaxMultiplicity = 1000;

[[noreturn]] void NotBuilt(const Entity& entity, const std::string& why) {
  ThrowUnsupported(entity.Name() + ": " + why);
}

const Instance& Checked(const Entities& entities, uint64_t id, uint64_t from, int depth) {
  if (depth > kMaxGeometryDepth)
    ThrowBroken("#" + std::to_string(from) + ": geometry references nested deeper than " +
                std::to_string(kMaxGeometryDepth) + " (a reference cycle)");
  return entities.Get(id, from);
}

Entity Expect(const Entities& entities, const Instance& instance, std::string_view type) {
  if (entities.SimpleType(instance) != type)
    ThrowUnsupported(entities.Describe(instance) + " where " + std::string(type) + " was expected");
  return entities.Simple(instance);
}

// Whether a TRIMMING_SELECT item is a parameter: OCCT reads any real there, typed or not, as
// its PARAMETER_VALUE member (StepGeom_TrimmingMember).
bool IsParameterValue(const Entity& e, const Param& param) {
  if (param.kind == ParamKind::kReal) return true;
  if (param.kind == ParamKind::kTyped) {
    const Param* inner = e.file().Item(param, 0);
    return inner != nullptr && inner->kind == ParamKind::kReal;
  }
  if (param.kind == ParamKind::kInteger) ThrowUnsupported(e.Name() + ": an integer trimming");
  return false;
}

double ParameterValue(const Entity& e, const Param& param) {
  return param.kind == ParamKind::kReal ? param.value.real : e.RealItem(param, 0);
}

}  // namespace

gp_Pnt Geometry::Point(uint64_t id, uint64_t from, const UnitFactors& units) const {
  const Instance& instance = entities_.Get(id, from);
  Entity point = Expect(entities_, instance, "CARTESIAN_POINT");
  const Param& coordinates = point.List(1);
  if (coordinates.count != 3) NotBuilt(point, "a 3D point without three coordinates");
  const double lf = units.length;
  return gp_Pnt(point.RealItem(coordinates, 0) * lf, point.RealItem(coordinates, 1) * lf,
                point.RealItem(coordinates, 2) * lf);
}

gp_Pnt2d Geometry::Point2d(uint64_t id, uint64_t from) const {
  const Instance& instance = entities_.Get(id, from);
  Entity point = Expect(entities_, instance, "CARTESIAN_POINT");
  const Param& coordinates = point.List(1);
  if (coordinates.count != 2) NotBuilt(point, "a 2D point without two coordinates");
  return gp_Pnt2d(point.RealItem(coordinates, 0), point.RealItem(coordinates, 1));
}

std::optional<gp_Dir> Geometry::Direction(uint64_t id, uint64_t from) const {
  const Instance& instance = entities_.Get(id, from);
  Entity direction = Expect(entities_, instance, "DIRECTION");
  const Param& ratios = direction.List(1);
  if (ratios.count < 3) return std::nullopt;
  const double x = direction.RealItem(ratios, 0);
  const double y = direction.RealItem(ratios, 1);
  const double z = direction.RealItem(ratios, 2);
  if (Precision::IsInfinite(x) || Precision::IsInfinite(y) || Precision::IsInfinite(z))
    return std::nullopt;
  if (!(gp_XYZ(x, y, z).SquareModulus() > gp::Resolution() * gp::Resolution())) return std::nullopt;
  // As StepToGeom's Geom_Direction: normalised once when made, once more by Dir().
  const double d = sqrt(x * x + y * y + z * z);
  if (d <= gp::Resolution()) return std::nullopt;
  return gp_Dir(gp_Vec(x / d, y / d, z / d));
}

std::optional<gp_Dir2d> Geometry::Direction2d(uint64_t id, uint64_t from) const {
  const Instance& instance = entities_.Get(id, from);
  Entity direction = Expect(entities_, instance, "DIRECTION");
  const Param& ratios = direction.List(1);
  if (ratios.count < 2) return std::nullopt;
  const double x = direction.RealItem(ratios, 0);
  const double y = direction.RealItem(ratios, 1);
  if (!(gp_XY(x, y).SquareModulus() > gp::Resolution() * gp::Resolution())) return std::nullopt;
  const double d = sqrt(x * x + y * y);
  if (d <= gp::Resolution()) return std::nullopt;
  return gp_Dir2d(gp_Vec2d(x / d, y / d));  // as Geom2d_Direction: normalised twice
}

gp_Ax2 Geometry::Axis2Placement(uint64_t id, uint64_t from, const UnitFactors& units) const {
  const Instance& instance = entities_.Get(id, from);
  Entity placement = Expect(entities_, instance, "AXIS2_PLACEMENT_3D");
  const gp_Pnt origin = Point(placement.Ref(1), id, units);
  gp_Dir normal(0., 0., 1.);
  if (!placement.IsUnset(2)) {
    std::optional<gp_Dir> axis = Direction(placement.Ref(2), id);
    if (axis) normal = *axis;
  }
  gp_Ax2 axes(origin, normal);
  if (!placement.IsUnset(3)) {
    std::optional<gp_Dir> x_direction = Direction(placement.Ref(3), id);
    if (x_direction && !normal.IsParallel(*x_direction, Precision::Angular()))
      axes = gp_Ax2(origin, normal, *x_direction);
  }
  // StepToGeom hands the placement over as a Geom_Axis2Placement, whose Ax2() builds the axes
  // once more from their location, direction and X direction: the same rounding here.
  return gp_Ax2(axes.Location(), axes.Direction(), axes.XDirection());
}

gp_Ax1 Geometry::Axis1Placement(uint64_t id, uint64_t from, const UnitFactors& units) const {
  const Instance& instance = entities_.Get(id, from);
  Entity placement = Expect(entities_, instance, "AXIS1_PLACEMENT");
  const gp_Pnt origin = Point(placement.Ref(1), id, units);
  gp_Dir axis(0., 0., 1.);
  if (!placement.IsUnset(2)) {
    std::optional<gp_Dir> direction = Direction(placement.Ref(2), id);
    if (direction) axis = *direction;
  }
  return gp_Ax1(origin, axis);
}

gp_Ax2d Geometry::Axis2Placement2d(uint64_t id, uint64_t from) const {
  const Instance& instance = entities_.Get(id, from);
  Entity placement = Expect(entities_, instance, "AXIS2_PLACEMENT_2D");
  const gp_Pnt2d origin = Point2d(placement.Ref(1), id);
  gp_Dir2d x_direction(1., 0.);
  if (!placement.IsUnset(2)) {
    std::optional<gp_Dir2d> direction = Direction2d(placement.Ref(2), id);
    if (direction) x_direction = *direction;
  }
  return gp_Ax2d(origin, x_direction);
}

gp_Trsf Geometry::Transformation(uint64_t id, uint64_t from, const UnitFactors& units) const {
  const Instance& instance = entities_.Get(id, from);
  std::string_view type = entities_.SimpleType(instance);
  if (type != "CARTESIAN_TRANSFORMATION_OPERATOR_3D")
    ThrowUnsupported(entities_.Describe(instance) + " as a transformation");
  // (name, axis1, axis2, local_origin, scale, axis3)
  Entity op = entities_.Simple(instance);
  if (!op.IsUnset(4) && op.Real(4) != 1.0) NotBuilt(op, "a scaled transformation");
  const gp_Pnt origin = Point(op.Ref(3), id, units);
  gp_Dir d1(1., 0., 0.), d2(0., 1., 0.), d3;
  if (!op.IsUnset(1))
    if (std::optional<gp_Dir> d = Direction(op.Ref(1), id)) d1 = *d;
  if (!op.IsUnset(2))
    if (std::optional<gp_Dir> d = Direction(op.Ref(2), id)) d2 = *d;
  bool default_d3 = true;
  if (op.size() > 5 && !op.IsUnset(5)) {
    if (std::optional<gp_Dir> d = Direction(op.Ref(5), id)) {
      d3 = *d;
      default_d3 = false;
    }
  }
  if (default_d3) d3 = d1.Crossed(d2);
  gp_Trsf trsf;
  trsf.SetTransformation(gp_Ax3(origin, d3, d1));
  return trsf.Inverted();
}

// ---------------------------------------------------------------------------------------------
// Curves

namespace {

// The knots and multiplicities of a B-spline as StepToGeom merges them: knots closer than
// Epsilon of the previous one are one knot, their multiplicities summed.
struct MergedKnots {
  std::vector<double> knots;
  std::vector<int> mults;
};

MergedKnots MergeKnots(const Entity& e, const Param& mults, const Param& knots) {
  if (mults.count != knots.count || knots.count == 0)
    NotBuilt(e, "knot and multiplicity lists of different lengths");
  MergedKnots merged;
  double last = RealFirst();
  for (uint32_t i = 0; i < knots.count; ++i) {
    const double knot = e.RealItem(knots, i);
    const int64_t mult = e.IntegerItem(mults, i);
    if (mult < 1 || mult > kMaxMultiplicity) NotBuilt(e, "a knot multiplicity out of range");
    if (i == 0 || knot - last > Epsilon(Abs(last))) {
      merged.knots.push_back(knot);
      merged.mults.push_back(static_cast<int>(mult));
      last = knot;
    } else {
      merged.mults.back() += static_cast<int>(mult);
    }
  }
  return merged;
}

// The parts of a B-spline curve entity, simple or rational complex.
struct BSplineCurveParts {
  Entity curve;   // degree, control points, form, closed, self_intersect from index `base`
  uint32_t base;  // index of the degree in `curve`
  Entity knots;   // multiplicities, knots from index `knot_base`
  uint32_t knot_base;
  std::optional<Entity> rational;  // weights at 0
};

BSplineCurveParts CurveParts(const Entities& entities, const Instance& instance) {
  if (!entities.IsComplex(instance)) {
    Entity e = entities.Simple(instance);
    return {e, 1, e, 6, std::nullopt};
  }
  if (instance.record_count != 7 || !entities.HasPart(instance, "RATIONAL_B_SPLINE_CURVE") ||
      !entities.HasPart(instance, "B_SPLINE_CURVE_WITH_KNOTS"))
    ThrowUnsupported(entities.Describe(instance));
  return {entities.Part(instance, "B_SPLINE_CURVE"), 0,
          entities.Part(instance, "B_SPLINE_CURVE_WITH_KNOTS"), 0,
          entities.Part(instance, "RATIONAL_B_SPLINE_CURVE")};
}

// StepData_Logical as StepToGeom tests it: .F. is false, .T. and .U. are true.
bool LogicalSet(const Entity& e, uint32_t i) {
  std::string_view value = e.Enum(i);
  if (value == "F") return false;
  if (value == "T" || value == "U") return true;
  e.Fail(i, "a logical");
}

// MakeBSplineCurveCommon of StepToGeom, for 3D and 2D poles.
template <class Poles, class Curve, class PointOf>
Handle(Curve)
    MakeBSplineCurve(const Entities& entities, const Instance& instance, PointOf point_of) {
  BSplineCurveParts parts = CurveParts(entities, instance);
  const Entity& c = parts.curve;
  const int64_t degree = c.Integer(parts.base);
  if (degree < 1 || degree > Curve::MaxDegree()) NotBuilt(c, "a B-spline degree out of range");
  const Param& points = c.List(parts.base + 1);
  const bool closed_curve = LogicalSet(c, parts.base + 3);
  MergedKnots merged = MergeKnots(parts.knots, parts.knots.List(parts.knot_base),
                                  parts.knots.List(parts.knot_base + 1));
  const int nb_unique = static_cast<int>(merged.knots.size());
  if (nb_unique <= 1) NotBuilt(c, "a B-spline with a single knot");
  const int nb_poles = static_cast<int>(points.count);
  int first_diff = 0, last_diff = 0;
  for (int i = 0; i < nb_unique; ++i) {
    int value = merged.mults[i];
    if (value > degree + 1) {
      if (i == 0) first_diff = value - static_cast<int>(degree) - 1;
      if (i == nb_unique - 1) last_diff = value - static_cast<int>(degree) - 1;
      value = static_cast<int>(degree) + 1;
    }
    merged.mults[i] = value;
  }
  const int nb_kept = nb_poles - first_diff - last_diff;
  if (nb_kept <= 0) NotBuilt(c, "a B-spline without poles");
  Poles poles(1, nb_kept);
  for (int i = 1 + first_diff; i <= nb_poles - last_diff; ++i)
    poles.SetValue(i - first_diff, point_of(c.RefItem(points, i - 1)));
  int sum = 0;
  for (int m : merged.mults) sum += m;
  bool periodic = false;
  if (sum == nb_poles + degree + 1) {
    periodic = false;
  } else if (merged.mults.front() == merged.mults.back() &&
             sum - merged.mults.front() == nb_poles) {
    periodic = true;
  }
  TColStd_Array1OfReal knots(1, nb_unique);
  TColStd_Array1OfInteger mults(1, nb_unique);
  for (int i = 0; i < nb_unique; ++i) {
    knots.SetValue(i + 1, merged.knots[i]);
    mults.SetValue(i + 1, merged.mults[i]);
  }
  Handle(Curve) curve;
  if (parts.rational) {
    const Param& weights = parts.rational->List(0);
    if (static_cast<int>(weights.count) != nb_poles) NotBuilt(c, "weights do not match the poles");
    TColStd_Array1OfReal kept(1, nb_kept);
    for (int i = 1 + first_diff; i <= nb_poles - last_diff; ++i)
      kept.SetValue(i - first_diff, parts.rational->RealItem(weights, i - 1));
    curve = new Curve(poles, kept, knots, mults, static_cast<int>(degree), periodic);
  } else {
    curve = new Curve(poles, knots, mults, static_cast<int>(degree), periodic);
  }
  if (closed_curve && curve->Degree() > 1 && curve->IsClosed()) curve->SetPeriodic();
  return curve;
}

}  // namespace

Handle(Geom_Curve) Geometry::BSplineCurve(const Instance& instance,
                                          const UnitFactors& units) const {
  const uint64_t id = instance.id;
  return MakeBSplineCurve<TColgp_Array1OfPnt, Geom_BSplineCurve>(
      entities_, instance, [&](uint64_t ref) { return Point(ref, id, units); });
}

Handle(Geom2d_Curve) Geometry::BSplineCurve2d(const Instance& instance) const {
  const uint64_t id = instance.id;
  return MakeBSplineCurve<TColgp_Array1OfPnt2d, Geom2d_BSplineCurve>(
      entities_, instance, [&](uint64_t ref) { return Point2d(ref, id); });
}

namespace {

// ExtractParameter of StepToGeom: a trimming parameter from a PARAMETER_VALUE or a point.
bool ExtractParameter(const Geometry& geometry, const Entity& e, const Handle(Geom_Curve) & curve,
                      const Param& select, int master, double factor, double shift,
                      const UnitFactors& units, double* parameter) {
  auto project = [&](const Param& item) {
    gp_Pnt point = geometry.Point(item.value.ref, e.id(), units);
    gp_Pnt projected;
    ShapeAnalysis_Curve().Project(curve, point, Precision::Confusion(), projected, *parameter);
  };
  for (uint32_t i = 0; i < select.count; ++i) {
    const Param& item = e.Item(select, i);
    if (master == 2 && IsParameterValue(e, item)) {
      *parameter = shift + factor * ParameterValue(e, item);
      return true;
    }
    if (master == 1 && item.kind == ParamKind::kRef) {
      project(item);
      return true;
    }
  }
  for (uint32_t i = 0; i < select.count; ++i) {
    const Param& item = e.Item(select, i);
    if (IsParameterValue(e, item)) {
      *parameter = shift + factor * ParameterValue(e, item);
      return true;
    }
  }
  for (uint32_t i = 0; i < select.count; ++i) {
    const Param& item = e.Item(select, i);
    if (item.kind == ParamKind::kRef) {
      project(item);
      return true;
    }
  }
  return false;
}

}  // namespace

Handle(Geom_Curve) Geometry::TrimmedCurve(const Instance& instance, const UnitFactors& units,
                                          int depth) const {
  // (name, basis_curve, trim_1, trim_2, sense_agreement, master_representation)
  Entity e = entities_.Simple(instance);
  const uint64_t basis_id = e.Ref(1);
  const Instance& basis = Checked(entities_, basis_id, e.id(), depth + 1);
  Handle(Geom_Curve) curve = CurveOf(basis, units, depth + 1);
  const Param& trim1 = e.List(2);
  const Param& trim2 = e.List(3);
  const bool sense = e.Logical(4);
  std::string_view master_text = e.Enum(5);
  int master = master_text == "CARTESIAN" ? 1 : master_text == "PARAMETER" ? 2 : 0;
  bool is_point = false;
  if (master == 0 || (master == 2 && trim1.count > 1 && trim2.count > 1)) {
    for (uint32_t i = 0; i < trim1.count; ++i) {
      if (e.Item(trim1, i).kind == ParamKind::kRef) {
        for (uint32_t j = 0; j < trim2.count; ++j) {
          if (e.Item(trim2, j).kind == ParamKind::kRef) {
            is_point = true;
            break;
          }
        }
        break;
      }
    }
  }
  double factor = 1., shift = 0.;
  std::string_view basis_type = entities_.SimpleType(basis);
  if (basis_type == "LINE") {
    Entity line = entities_.Simple(basis);
    Entity vector = Expect(entities_, entities_.Get(line.Ref(2), basis.id), "VECTOR");
    factor = vector.Real(2) * units.length;
  } else if (basis_type == "CIRCLE" || basis_type == "ELLIPSE") {
    factor = units.plane_angle;
    Entity conic = entities_.Simple(basis);
    if (basis_type == "ELLIPSE" && conic.Real(2) - conic.Real(3) < 0.) shift = 0.5 * M_PI;
    if (master != 1) {
      const Instance& position = entities_.Get(conic.Ref(1), basis.id);
      if (entities_.SimpleType(position) == "AXIS2_PLACEMENT_3D" &&
          entities_.Simple(position).IsUnset(3)) {
        if (is_point) {
          master = 1;
        } else {
          if (sense) return new Geom_TrimmedCurve(curve, 0., 2. * M_PI, Standard_True);
          return new Geom_TrimmedCurve(curve, 2. * M_PI, 0., Standard_False);
        }
      }
    }
  }
  double t1 = 0., t2 = 0.;
  const bool found1 = ExtractParameter(*this, e, curve, trim1, master, factor, shift, units, &t1);
  const bool found2 = ExtractParameter(*this, e, curve, trim2, master, factor, shift, units, &t2);
  if (!found1 || !found2) NotBuilt(e, "a trimming without parameters");
  const double cf = curve->FirstParameter();
  const double cl = curve->LastParameter();
  if (!curve->IsPeriodic()) {
    if (t1 < cf)
      t1 = cf;
    else if (t1 > cl)
      t1 = cl;
    if (t2 < cf)
      t2 = cf;
    else if (t2 > cl)
      t2 = cl;
  }
  if (Abs(t1 - t2) < Precision::PConfusion()) {
    if (curve->IsPeriodic()) {
      ElCLib::AdjustPeriodic(cf, cl, Precision::PConfusion(), t1, t2);
    } else if (curve->IsClosed()) {
      if (Abs(t1 - cf) < Precision::PConfusion())
        t2 += cl;
      else
        t1 -= cl;
    } else {
      NotBuilt(e, "a trimming of zero length");
    }
  }
  if (sense) return new Geom_TrimmedCurve(curve, t1, t2, Standard_True);
  return new Geom_TrimmedCurve(curve, t2, t1, Standard_False);
}

Handle(Geom_Curve) Geometry::CurveOf(const Instance& instance, const UnitFactors& units,
                                     int depth) const {
  const uint64_t id = instance.id;
  if (entities_.IsComplex(instance)) return BSplineCurve(instance, units);
  std::string_view type = entities_.SimpleType(instance);
  Entity e = entities_.Simple(instance);
  if (type == "LINE") {
    // (name, pnt, dir)
    const gp_Pnt point = Point(e.Ref(1), id, units);
    Entity vector = Expect(entities_, entities_.Get(e.Ref(2), id), "VECTOR");
    std::optional<gp_Dir> direction = Direction(vector.Ref(1), vector.id());
    if (!direction) NotBuilt(e, "a line without direction");
    const gp_Vec v(direction->XYZ() * vector.Real(2) * units.length);
    if (v.SquareMagnitude() < Precision::Confusion() * Precision::Confusion())
      NotBuilt(e, "a line with a zero vector");
    return new Geom_Line(point, gp_Dir(v));
  }
  if (type == "CIRCLE" || type == "ELLIPSE" || type == "HYPERBOLA" || type == "PARABOLA") {
    const Instance& position = entities_.Get(e.Ref(1), id);
    if (entities_.SimpleType(position) != "AXIS2_PLACEMENT_3D")
      NotBuilt(e, "a 3D conic without a 3D placement");
    gp_Ax2 axes = Axis2Placement(position.id, id, units);
    const double lf = units.length;
    if (type == "CIRCLE") return new Geom_Circle(axes, e.Real(2) * lf);
    if (type == "ELLIPSE") {
      const double major = e.Real(2) * lf;
      const double minor = e.Real(3) * lf;
      if (major - minor >= 0.) return new Geom_Ellipse(axes, major, minor);
      axes.SetXDirection(axes.XDirection() ^ axes.Direction());
      return new Geom_Ellipse(axes, minor, major);
    }
    if (type == "HYPERBOLA") return new Geom_Hyperbola(axes, e.Real(2) * lf, e.Real(3) * lf);
    return new Geom_Parabola(axes, e.Real(2) * lf);
  }
  if (type == "B_SPLINE_CURVE_WITH_KNOTS") return BSplineCurve(instance, units);
  if (type == "TRIMMED_CURVE") return TrimmedCurve(instance, units, depth);
  if (type == "POLYLINE") {
    const Param& points = e.List(1);
    if (points.count < 2) NotBuilt(e, "a polyline of fewer than two points");
    const int n = static_cast<int>(points.count);
    TColgp_Array1OfPnt poles(1, n);
    TColStd_Array1OfReal knots(1, n);
    TColStd_Array1OfInteger mults(1, n);
    for (int i = 1; i <= n; ++i) {
      poles.SetValue(i, Point(e.RefItem(points, i - 1), id, units));
      knots.SetValue(i, static_cast<double>(i - 1));
      mults.SetValue(i, 1);
    }
    mults.SetValue(1, 2);
    mults.SetValue(n, 2);
    return new Geom_BSplineCurve(poles, knots, mults, 1);
  }
  if (type == "SURFACE_CURVE" || type == "SEAM_CURVE" || type == "INTERSECTION_CURVE") {
    const Instance& curve3d = Checked(entities_, e.Ref(1), id, depth + 1);
    return CurveOf(curve3d, units, depth + 1);
  }
  ThrowUnsupported(entities_.Describe(instance));
}

Handle(Geom_Curve) Geometry::Curve(uint64_t id, uint64_t from, const UnitFactors& units,
                                   int depth) const {
  const Instance& instance = Checked(entities_, id, from, depth);
  try {
    return CurveOf(instance, units, depth);
  } catch (const Standard_Failure& failure) {
    ThrowUnsupported(entities_.Describe(instance) + ": OCCT cannot build it (" +
                     failure.DynamicType()->Name() + ")");
  }
}

Handle(Geom_Curve) Geometry::SharedCurve(uint64_t id, uint64_t from, const UnitFactors& units) {
  auto found = shared_curves_.find(id);
  if (found != shared_curves_.end()) return found->second;
  Handle(Geom_Curve) curve = Curve(id, from, units);
  shared_curves_.emplace(id, curve);
  return curve;
}

Handle(Geom2d_Curve) Geometry::TrimmedCurve2d(const Instance& instance, const UnitFactors& units,
                                              int depth) const {
  Entity e = entities_.Simple(instance);
  const Instance& basis = Checked(entities_, e.Ref(1), e.id(), depth + 1);
  Handle(Geom2d_Curve) curve = Curve2dOf(basis, units, depth + 1);
  if (curve.IsNull()) return curve;
  if (curve->IsKind(STANDARD_TYPE(Geom2d_BSplineCurve))) return curve;
  const Param& trim1 = e.List(2);
  const Param& trim2 = e.List(3);
  if (trim1.count != 1 || trim2.count != 1 || !IsParameterValue(e, e.Item(trim1, 0)) ||
      !IsParameterValue(e, e.Item(trim2, 0)))
    return Handle(Geom2d_Curve)();
  const double u1 = ParameterValue(e, e.Item(trim1, 0));
  const double u2 = ParameterValue(e, e.Item(trim2, 0));
  double factor = 1., shift = 0.;
  std::string_view basis_type = entities_.SimpleType(basis);
  Entity b = entities_.Simple(basis);
  if (basis_type == "LINE") {
    factor = Expect(entities_, entities_.Get(b.Ref(2), basis.id), "VECTOR").Real(2);
  } else if (basis_type == "CIRCLE" || basis_type == "ELLIPSE") {
    factor = units.plane_angle;
    if (basis_type == "ELLIPSE" && b.Real(2) - b.Real(3) < 0.) shift = 0.5 * M_PI;
  }
  const bool sense = e.Logical(4);
  Handle(Geom2d_TrimmedCurve) trimmed =
      new Geom2d_TrimmedCurve(curve, shift + u1 * factor, shift + u2 * factor, sense);
  return Geom2dConvert::CurveToBSplineCurve(trimmed);
}

Handle(Geom2d_Curve) Geometry::Curve2dOf(const Instance& instance, const UnitFactors& units,
                                         int depth) const {
  const uint64_t id = instance.id;
  if (entities_.IsComplex(instance)) return BSplineCurve2d(instance);
  std::string_view type = entities_.SimpleType(instance);
  Entity e = entities_.Simple(instance);
  if (type == "LINE") {
    const gp_Pnt2d point = Point2d(e.Ref(1), id);
    Entity vector = Expect(entities_, entities_.Get(e.Ref(2), id), "VECTOR");
    std::optional<gp_Dir2d> direction = Direction2d(vector.Ref(1), vector.id());
    if (!direction) return Handle(Geom2d_Curve)();
    const gp_Vec2d v(direction->XY() * vector.Real(2));
    return new Geom2d_Line(point, gp_Dir2d(v));
  }
  if (type == "CIRCLE" || type == "ELLIPSE" || type == "HYPERBOLA" || type == "PARABOLA") {
    const Instance& position = entities_.Get(e.Ref(1), id);
    if (entities_.SimpleType(position) != "AXIS2_PLACEMENT_2D") return Handle(Geom2d_Curve)();
    const gp_Ax2d axis = Axis2Placement2d(position.id, id);
    if (type == "CIRCLE") return new Geom2d_Circle(axis, e.Real(2));
    gp_Ax22d axes(axis);
    if (type == "ELLIPSE") {
      const double major = e.Real(2);
      const double minor = e.Real(3);
      if (major - minor >= 0.) return new Geom2d_Ellipse(axes, major, minor);
      const gp_Dir2d x = axes.XDirection();
      axes.SetXDirection(gp_Dir2d(x.X(), -x.Y()));
      return new Geom2d_Ellipse(axes, minor, major);
    }
    if (type == "HYPERBOLA") return new Geom2d_Hyperbola(axes, e.Real(2), e.Real(3));
    return new Geom2d_Parabola(axes, e.Real(2));
  }
  if (type == "B_SPLINE_CURVE_WITH_KNOTS") return BSplineCurve2d(instance);
  if (type == "TRIMMED_CURVE") return TrimmedCurve2d(instance, units, depth);
  if (type == "POLYLINE") {
    const Param& points = e.List(1);
    if (points.count < 2) return Handle(Geom2d_Curve)();
    const int n = static_cast<int>(points.count);
    TColgp_Array1OfPnt2d poles(1, n);
    TColStd_Array1OfReal knots(1, n);
    TColStd_Array1OfInteger mults(1, n);
    for (int i = 1; i <= n; ++i) {
      poles.SetValue(i, Point2d(e.RefItem(points, i - 1), id));
      knots.SetValue(i, static_cast<double>(i - 1));
      mults.SetValue(i, 1);
    }
    mults.SetValue(1, 2);
    mults.SetValue(n, 2);
    return new Geom2d_BSplineCurve(poles, knots, mults, 1);
  }
  ThrowUnsupported(entities_.Describe(instance) + " as a pcurve");
}

Handle(Geom2d_Curve) Geometry::Curve2d(uint64_t id, uint64_t from, const UnitFactors& units,
                                       int depth) const {
  const Instance& instance = Checked(entities_, id, from, depth);
  try {
    return Curve2dOf(instance, units, depth);
  } catch (const Standard_Failure&) {
    return Handle(Geom2d_Curve)();  // StepToTopoDS_TranslateEdge::MakePCurve: no pcurve
  }
}

// ---------------------------------------------------------------------------------------------
// Surfaces

Handle(Geom_Surface) Geometry::BSplineSurface(const Instance& instance,
                                              const UnitFactors& units) const {
  const uint64_t id = instance.id;
  Entity s = entities_.Simple(instance);
  uint32_t base = 1;  // u_degree in `s`
  Entity k = s;
  uint32_t knot_base = 8;  // u_multiplicities in `k`
  std::optional<Entity> rational;
  if (entities_.IsComplex(instance)) {
    if (instance.record_count != 7 || !entities_.HasPart(instance, "RATIONAL_B_SPLINE_SURFACE") ||
        !entities_.HasPart(instance, "B_SPLINE_SURFACE_WITH_KNOTS"))
      ThrowUnsupported(entities_.Describe(instance));
    s = entities_.Part(instance, "B_SPLINE_SURFACE");
    base = 0;
    k = entities_.Part(instance, "B_SPLINE_SURFACE_WITH_KNOTS");
    knot_base = 0;
    rational = entities_.Part(instance, "RATIONAL_B_SPLINE_SURFACE");
  }
  const int64_t udeg = s.Integer(base);
  const int64_t vdeg = s.Integer(base + 1);
  if (udeg < 1 || udeg > Geom_BSplineSurface::MaxDegree() || vdeg < 1 ||
      vdeg > Geom_BSplineSurface::MaxDegree())
    NotBuilt(s, "a B-spline degree out of range");
  const Param& rows = s.List(base + 2);
  const int nu = static_cast<int>(rows.count);
  if (nu < 1) NotBuilt(s, "no control points");
  const int nv = static_cast<int>(s.ListItem(rows, 0).count);
  if (nv < 1) NotBuilt(s, "no control points");
  TColgp_Array2OfPnt poles(1, nu, 1, nv);
  for (int i = 0; i < nu; ++i) {
    const Param& row = s.ListItem(rows, static_cast<uint32_t>(i));
    if (static_cast<int>(row.count) != nv) NotBuilt(s, "rows of control points of unequal length");
    for (int j = 0; j < nv; ++j)
      poles.SetValue(i + 1, j + 1, Point(s.RefItem(row, static_cast<uint32_t>(j)), id, units));
  }
  MergedKnots u = MergeKnots(k, k.List(knot_base), k.List(knot_base + 2));
  MergedKnots v = MergeKnots(k, k.List(knot_base + 1), k.List(knot_base + 3));
  auto periodic = [](const MergedKnots& m, int poles_count, int64_t degree) {
    int sum = 0;
    for (int x : m.mults) sum += x;
    if (sum == poles_count + degree + 1) return false;
    return m.mults.front() == m.mults.back() && sum - m.mults.front() == poles_count;
  };
  const bool uperiodic = periodic(u, nu, udeg);
  const bool vperiodic = periodic(v, nv, vdeg);
  auto array = [](const MergedKnots& m, TColStd_Array1OfReal* knots,
                  TColStd_Array1OfInteger* mults) {
    for (size_t i = 0; i < m.knots.size(); ++i) {
      knots->SetValue(static_cast<int>(i) + 1, m.knots[i]);
      mults->SetValue(static_cast<int>(i) + 1, m.mults[i]);
    }
  };
  TColStd_Array1OfReal uknots(1, static_cast<int>(u.knots.size()));
  TColStd_Array1OfInteger umults(1, static_cast<int>(u.knots.size()));
  TColStd_Array1OfReal vknots(1, static_cast<int>(v.knots.size()));
  TColStd_Array1OfInteger vmults(1, static_cast<int>(v.knots.size()));
  array(u, &uknots, &umults);
  array(v, &vknots, &vmults);
  if (rational) {
    const Param& weight_rows = rational->List(0);
    if (static_cast<int>(weight_rows.count) != nu) NotBuilt(s, "weights do not match the poles");
    TColStd_Array2OfReal weights(1, nu, 1, nv);
    for (int i = 0; i < nu; ++i) {
      const Param& row = rational->ListItem(weight_rows, static_cast<uint32_t>(i));
      if (static_cast<int>(row.count) != nv) NotBuilt(s, "weights do not match the poles");
      for (int j = 0; j < nv; ++j)
        weights.SetValue(i + 1, j + 1, rational->RealItem(row, static_cast<uint32_t>(j)));
    }
    return new Geom_BSplineSurface(poles, weights, uknots, vknots, umults, vmults,
                                   static_cast<int>(udeg), static_cast<int>(vdeg), uperiodic,
                                   vperiodic);
  }
  return new Geom_BSplineSurface(poles, uknots, vknots, umults, vmults, static_cast<int>(udeg),
                                 static_cast<int>(vdeg), uperiodic, vperiodic);
}

Handle(Geom_Surface) Geometry::SurfaceOf(const Instance& instance, const UnitFactors& units,
                                         int depth) const {
  const uint64_t id = instance.id;
  if (entities_.IsComplex(instance)) return BSplineSurface(instance, units);
  std::string_view type = entities_.SimpleType(instance);
  Entity e = entities_.Simple(instance);
  const double lf = units.length;
  if (type == "PLANE" || type == "CYLINDRICAL_SURFACE" || type == "CONICAL_SURFACE" ||
      type == "SPHERICAL_SURFACE" || type == "TOROIDAL_SURFACE" ||
      type == "DEGENERATE_TOROIDAL_SURFACE") {
    if (e.IsUnset(1)) NotBuilt(e, "no position");
    const gp_Ax2 axes = Axis2Placement(e.Ref(1), id, units);
    if (type == "PLANE") return new Geom_Plane(axes);
    if (type == "CYLINDRICAL_SURFACE") return new Geom_CylindricalSurface(axes, e.Real(2) * lf);
    if (type == "CONICAL_SURFACE") {
      const double radius = e.Real(2) * lf;
      const double angle = e.Real(3) * units.plane_angle;
      return new Geom_ConicalSurface(axes, Max(angle, Precision::Angular()), radius);
    }
    if (type == "SPHERICAL_SURFACE") return new Geom_SphericalSurface(axes, e.Real(2) * lf);
    return new Geom_ToroidalSurface(axes, Abs(e.Real(2) * lf), Abs(e.Real(3) * lf));
  }
  if (type == "B_SPLINE_SURFACE_WITH_KNOTS") return BSplineSurface(instance, units);
  if (type == "SURFACE_OF_LINEAR_EXTRUSION") {
    // (name, swept_curve, extrusion_axis)
    Handle(Geom_Curve) curve =
        CurveOf(Checked(entities_, e.Ref(1), id, depth + 1), units, depth + 1);
    Entity vector = Expect(entities_, entities_.Get(e.Ref(2), id), "VECTOR");
    std::optional<gp_Dir> direction = Direction(vector.Ref(1), vector.id());
    if (!direction) NotBuilt(e, "an extrusion without direction");
    const gp_Dir d(gp_Vec(direction->XYZ() * vector.Real(2) * lf));
    Handle(Geom_Line) line = Handle(Geom_Line)::DownCast(curve);
    if (!line.IsNull() && line->Lin().Direction().IsParallel(d, Precision::Angular()))
      NotBuilt(e, "a line extruded along itself");
    return new Geom_SurfaceOfLinearExtrusion(curve, d);
  }
  if (type == "SURFACE_OF_REVOLUTION") {
    // (name, swept_curve, axis_position)
    Handle(Geom_Curve) curve =
        CurveOf(Checked(entities_, e.Ref(1), id, depth + 1), units, depth + 1);
    const gp_Ax1 axis = Axis1Placement(e.Ref(2), id, units);
    if (curve->IsKind(STANDARD_TYPE(Geom_Circle)) || curve->IsKind(STANDARD_TYPE(Geom_Ellipse))) {
      Handle(Geom_Conic) conic = Handle(Geom_Conic)::DownCast(curve);
      const gp_Pnt center = conic->Location();
      const gp_Lin line(axis);
      if (line.Distance(center) < Precision::Confusion()) {
        const gp_Dir along = axis.Direction();
        const gp_Dir normal = conic->Axis().Direction();
        const gp_Dir x_axis = conic->XAxis().Direction();
        if (along.IsNormal(normal, Precision::Angular()) &&
            (along.IsParallel(x_axis, Precision::Angular()) ||
             curve->IsKind(STANDARD_TYPE(Geom_Circle)))) {
          conic->SetPosition(gp_Ax2(center, normal, along.Reversed()));
          curve = new Geom_TrimmedCurve(conic, 0., M_PI);
        }
      }
    }
    return new Geom_SurfaceOfRevolution(curve, axis);
  }
  if (type == "OFFSET_SURFACE") {
    // (name, basis_surface, distance, self_intersect)
    Handle(Geom_Surface) basis =
        SurfaceOf(Checked(entities_, e.Ref(1), id, depth + 1), units, depth + 1);
    const double offset = e.Real(2) * lf;
    if (basis->Continuity() == GeomAbs_C0) NotBuilt(e, "an offset of a C0 surface");
    return new Geom_OffsetSurface(basis, offset);
  }
  if (type == "RECTANGULAR_TRIMMED_SURFACE") {
    // (name, basis_surface, u1, u2, v1, v2, usense, vsense)
    Handle(Geom_Surface) basis =
        SurfaceOf(Checked(entities_, e.Ref(1), id, depth + 1), units, depth + 1);
    double ufact = 1., vfact = 1.;
    const double af = units.plane_angle;
    if (basis->IsKind(STANDARD_TYPE(Geom_SphericalSurface)) ||
        basis->IsKind(STANDARD_TYPE(Geom_ToroidalSurface))) {
      ufact = vfact = af;
    } else if (basis->IsKind(STANDARD_TYPE(Geom_CylindricalSurface))) {
      ufact = af;
      vfact = lf;
    } else if (basis->IsKind(STANDARD_TYPE(Geom_SurfaceOfRevolution))) {
      ufact = af;
    } else if (basis->IsKind(STANDARD_TYPE(Geom_ConicalSurface))) {
      Handle(Geom_ConicalSurface) cone = Handle(Geom_ConicalSurface)::DownCast(basis);
      ufact = af;
      vfact = lf / Cos(cone->SemiAngle());
    } else if (basis->IsKind(STANDARD_TYPE(Geom_Plane))) {
      ufact = vfact = lf;
    }
    return new Geom_RectangularTrimmedSurface(basis, e.Real(2) * ufact, e.Real(3) * ufact,
                                              e.Real(4) * vfact, e.Real(5) * vfact, e.Logical(6),
                                              e.Logical(7));
  }
  ThrowUnsupported(entities_.Describe(instance));
}

Handle(Geom_Surface) Geometry::Surface(uint64_t id, uint64_t from, const UnitFactors& units,
                                       int depth) const {
  const Instance& instance = Checked(entities_, id, from, depth);
  try {
    return SurfaceOf(instance, units, depth);
  } catch (const Standard_Failure& failure) {
    ThrowUnsupported(entities_.Describe(instance) + ": OCCT cannot build it (" +
                     failure.DynamicType()->Name() + ")");
  }
}

}  // namespace rdmesh::step
