#include "geometry/surface.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <BSplCLib_CacheParams.hxx>
#include <BSplSLib.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_Surface.hxx>
#include <Geom_SurfaceOfRevolution.hxx>
#include <Precision.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <gp_Cone.hxx>
#include <gp_Cylinder.hxx>
#include <gp_Pln.hxx>
#include <gp_Pnt.hxx>
#include <gp_Sphere.hxx>
#include <gp_Torus.hxx>
#include <gp_Trsf.hxx>
#include <gp_Vec.hxx>
#include <memory>
#include <unordered_map>
#include <vector>

#include "geometry/bspline_spans.h"

namespace rdmesh {

Vec3 Surface::Normal(double u, double v) {
  // Central differences with a step of 1e-5 of the parameter range, nudged inside the bounds;
  // at a pole, average the normals of four points around it.
  double du = 1e-5 * std::max(umax - umin, 1e-12), dv = 1e-5 * std::max(vmax - vmin, 1e-12);
  auto normal_at = [&](double uu, double vv) {
    double u0 = std::max(uu - du, umin), u1 = std::min(uu + du, umax);
    double v0 = std::max(vv - dv, vmin), v1 = std::min(vv + dv, vmax);
    Vec3 su = Point(u1, vv) - Point(u0, vv);
    Vec3 sv = Point(uu, v1) - Point(uu, v0);
    return Cross(su, sv);
  };
  Vec3 n = normal_at(u, v);
  double scale = Norm(Point(std::min(u + du, umax), v) - Point(u, v)) +
                 Norm(Point(u, std::min(v + dv, vmax)) - Point(u, v));
  if (Norm(n) > 1e-6 * scale * scale) return Normalized(n);
  Vec3 sum;
  for (double s : {-1.0, 1.0}) {
    for (double t : {-1.0, 1.0}) {
      double uu = std::clamp(u + s * 1e3 * du, umin, umax);
      double vv = std::clamp(v + t * 1e3 * dv, vmin, vmax);
      sum = sum + Normalized(normal_at(uu, vv));
    }
  }
  return Normalized(sum);
}

namespace {

// Direct-mapped: slot = hash of the bits of (u, v); a new value overwrites the slot. The table
// starts small (most faces are) and grows while it keeps missing, up to kMaxBits.
class CachedSurface final : public Surface {
 public:
  explicit CachedSurface(std::unique_ptr<Surface> inner) : inner_(std::move(inner)) {
    umin = inner_->umin, umax = inner_->umax, vmin = inner_->vmin, vmax = inner_->vmax;
    uknots = inner_->uknots, vknots = inner_->vknots;
    quadric = inner_->quadric;
    planar = inner_->planar;
    Resize(kMinBits);
  }
  Vec3 Point(double u, double v) override {
    uint64_t ku, kv;
    std::memcpy(&ku, &u, sizeof(u));
    std::memcpy(&kv, &v, sizeof(v));
    uint64_t h =
        (ku * 0x9E3779B97F4A7C15ull) ^ ((kv + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full);
    Entry& e = table_[h >> (64 - bits_)];
    if (e.filled && e.u == ku && e.v == kv) return e.point;
    Vec3 p = inner_->Point(u, v);
    if (++misses_ > 4 * table_.size() && bits_ < kMaxBits) {
      Resize(bits_ + 2);
      return p;
    }
    e = {ku, kv, true, p};
    return p;
  }
  Vec3 Normal(double u, double v) override { return inner_->Normal(u, v); }

 private:
  static constexpr int kMinBits = 8, kMaxBits = 12;
  struct Entry {
    uint64_t u = 0, v = 0;
    bool filled = false;
    Vec3 point;
  };
  void Resize(int bits) {
    bits_ = bits;
    table_.assign(size_t{1} << bits, Entry{});
    misses_ = 0;
  }
  std::unique_ptr<Surface> inner_;
  std::vector<Entry> table_;
  int bits_ = 0;
  size_t misses_ = 0;
};

Vec3 ToVec(const gp_Pnt& p) { return {p.X(), p.Y(), p.Z()}; }
Vec3 ToVec(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

// OCCT evaluator, with speed-ups that keep OCCT's values bit for bit. B-spline points come from
// each knot span's polynomial, built once (SpanPolynomials). B-spline normals come from a few
// adaptors, each kept on the span it last served: an adaptor evaluates through a polynomial cache
// of one span and rebuilds it whenever a point falls in another; the cache content depends only
// on the span, so the values are the same. Planes, cylinders, cones and spheres skip the
// adaptor's dispatch.
class OcctSurface final : public Surface {
 public:
  explicit OcctSurface(const Handle(Geom_Surface) & surface) : adaptor_(surface) {
    auto frame = [&](const gp_Ax3& pos) {
      frame_ = {pos.XDirection().XYZ(), pos.YDirection().XYZ(), pos.Direction().XYZ(),
                pos.Location().XYZ()};
    };
    switch (adaptor_.GetType()) {
      case GeomAbs_Plane:
        frame(adaptor_.Plane().Position());
        kind_ = Kind::kPlane;
        planar = true;
        break;
      case GeomAbs_Cylinder:
        frame(adaptor_.Cylinder().Position());
        radius_ = adaptor_.Cylinder().Radius();
        kind_ = Kind::kCylinder;
        quadric = {Quadric::Kind::kCylinder, ToVec(frame_[3]), ToVec(frame_[2]), radius_};
        break;
      case GeomAbs_Cone: {
        gp_Cone cone = adaptor_.Cone();
        frame(cone.Position());
        radius_ = cone.RefRadius();
        // ElSLib::ConeD0 takes the sine and cosine of the semi-angle at every call: the same
        // values each time.
        cone_sin_ = std::sin(cone.SemiAngle());
        cone_cos_ = std::cos(cone.SemiAngle());
        kind_ = Kind::kCone;
        quadric = {Quadric::Kind::kCone,
                   ToVec(frame_[3]),
                   ToVec(frame_[2]),
                   radius_,
                   cone_sin_,
                   cone_cos_};
        break;
      }
      case GeomAbs_Sphere:
        frame(adaptor_.Sphere().Position());
        radius_ = adaptor_.Sphere().Radius();
        kind_ = Kind::kSphere;
        quadric = {Quadric::Kind::kSphere, ToVec(frame_[3]), ToVec(frame_[2]), radius_};
        v_trig_.resize(size_t{1} << kTrigBits);
        break;
      case GeomAbs_Torus: {
        gp_Torus torus = adaptor_.Torus();
        frame(torus.Position());
        radius_ = torus.MajorRadius();
        minor_radius_ = torus.MinorRadius();
        torus_zero_ = 10. * (minor_radius_ + radius_) * RealEpsilon();
        kind_ = Kind::kTorus;
        v_trig_.resize(size_t{1} << kTrigBits);
        break;
      }
      case GeomAbs_SurfaceOfRevolution: {
        Handle(Geom_SurfaceOfRevolution) revolution =
            Handle(Geom_SurfaceOfRevolution)::DownCast(adaptor_.Surface());
        if (revolution.IsNull()) break;
        // As GeomAdaptor_Surface builds its evaluator: the axis from the location and direction.
        const gp_Ax1 axis(revolution->Location(), revolution->Direction());
        origin_ = axis.Location().XYZ();
        // gp_Mat::SetRotation's parts that do not depend on the angle: the cross-product matrix
        // of the normalised direction, and its square as it writes it.
        const gp_XYZ d = axis.Direction().XYZ().Normalized();
        const double a = d.X(), b = d.Y(), c = d.Z();
        const double cross[3][3] = {{0.0, -c, b}, {c, 0.0, -a}, {-b, a, 0.0}};
        const double square[3][3] = {{-c * c - b * b, a * b, a * c},
                                     {a * b, -a * a - c * c, b * c},
                                     {a * c, b * c, -a * a - b * b}};
        std::memcpy(cross_, cross, sizeof(cross_));
        std::memcpy(square_, square, sizeof(square_));
        profile_.Load(revolution->BasisCurve());
        profile_points_.resize(size_t{1} << kTrigBits);
        kind_ = Kind::kRevolution;
        break;
      }
      default:
        break;
    }
    if (kind_ != Kind::kPlane && kind_ != Kind::kOther) u_trig_.resize(size_t{1} << kTrigBits);
    if (adaptor_.GetType() != GeomAbs_BSplineSurface) return;
    Handle(Geom_BSplineSurface) bspline = adaptor_.BSpline();
    for (int i = 1; i <= bspline->NbUKnots(); ++i) uknots.at.push_back(bspline->UKnot(i));
    for (int i = 1; i <= bspline->NbVKnots(); ++i) vknots.at.push_back(bspline->VKnot(i));
    if (bspline->IsUPeriodic()) uknots.period = uknots.at.back() - uknots.at.front();
    if (bspline->IsVPeriodic()) vknots.period = vknots.at.back() - vknots.at.front();
    bspline_ = bspline;
    spans_.resize(kSpans);
    for (Span& span : spans_) span.adaptor.Load(surface);
    polynomials_ = std::make_unique<SpanPolynomials>(*bspline);
  }
  Vec3 Point(double u, double v) override {
    switch (kind_) {
      case Kind::kPlane:
        return PlanePoint(u, v);
      case Kind::kCylinder:
        return CylinderPoint(u, v);
      case Kind::kCone:
        return ConePoint(u, v);
      case Kind::kSphere:
        return SpherePoint(u, v);
      case Kind::kTorus:
        return TorusPoint(u, v);
      case Kind::kRevolution:
        return RevolutionPoint(u, v);
      case Kind::kOther:
        break;
    }
    if (polynomials_) return polynomials_->Value(*bspline_, uknots.at, vknots.at, u, v);
    return ToVec(adaptor_.Value(u, v));
  }
  Vec3 Normal(double u, double v) override {
    gp_Pnt p;
    gp_Vec su, sv;
    Adaptor(u, v).D1(u, v, p, su, sv);
    gp_Vec n = su.Crossed(sv);
    double scale = su.SquareMagnitude() + sv.SquareMagnitude();
    if (n.SquareMagnitude() > 1e-16 * scale * scale && scale > 0) {
      n.Normalize();
      return {n.X(), n.Y(), n.Z()};
    }
    return Surface::Normal(u, v);  // singular point: average around it
  }

 private:
  // OCCT's evaluations of the elementary surfaces (ElSLib::PlaneD0, CylinderD0, ConeD0,
  // SphereD0) without the adaptor's dispatch: the same arithmetic in the same order, so the same
  // bits (surface_test checks it). The cosine and sine of each angle parameter come from a small
  // table: refinement's probes often share one of u, v (a smoothing probe that moves along u
  // keeps the v of every sample around it).
  Vec3 PlanePoint(double u, double v) const {
    const gp_XYZ &x = frame_[0], &y = frame_[1], &o = frame_[3];
    return {u * x.X() + v * y.X() + o.X(), u * x.Y() + v * y.Y() + o.Y(),
            u * x.Z() + v * y.Z() + o.Z()};
  }
  // a1 x + a2 y + a3 z + o, summed left to right as ElSLib does.
  Vec3 InFrame(double a1, double a2, double a3) const {
    const gp_XYZ &x = frame_[0], &y = frame_[1], &z = frame_[2], &o = frame_[3];
    return {a1 * x.X() + a2 * y.X() + a3 * z.X() + o.X(),
            a1 * x.Y() + a2 * y.Y() + a3 * z.Y() + o.Y(),
            a1 * x.Z() + a2 * y.Z() + a3 * z.Z() + o.Z()};
  }
  Vec3 CylinderPoint(double u, double v) {
    const CosSin& cu = Trig(u, u_trig_);
    double a1 = radius_ * cu.cos;
    double a2 = radius_ * cu.sin;
    return InFrame(a1, a2, v);
  }
  Vec3 ConePoint(double u, double v) {
    const CosSin& cu = Trig(u, u_trig_);
    double r = radius_ + v * cone_sin_;
    double a3 = v * cone_cos_;
    double a1 = r * cu.cos;
    double a2 = r * cu.sin;
    return InFrame(a1, a2, a3);
  }
  Vec3 SpherePoint(double u, double v) {
    const CosSin& cv = Trig(v, v_trig_);
    const CosSin& cu = Trig(u, u_trig_);
    double r = radius_ * cv.cos;
    double a3 = radius_ * cv.sin;
    double a1 = r * cu.cos;
    double a2 = r * cu.sin;
    return InFrame(a1, a2, a3);
  }

  // ElSLib::TorusD0: it rounds a coordinate within 10 ulps of the radii's sum to 0.
  Vec3 TorusPoint(double u, double v) {
    const CosSin& cv = Trig(v, v_trig_);
    const CosSin& cu = Trig(u, u_trig_);
    double r = radius_ + minor_radius_ * cv.cos;
    double a3 = minor_radius_ * cv.sin;
    double a1 = r * cu.cos;
    double a2 = r * cu.sin;
    if (std::abs(a1) <= torus_zero_) a1 = 0.;
    if (std::abs(a2) <= torus_zero_) a2 = 0.;
    if (std::abs(a3) <= torus_zero_) a3 = 0.;
    return InFrame(a1, a2, a3);
  }

  // GeomEvaluator_SurfaceOfRevolution::D0: the profile's point at v (through OCCT's adaptor: it
  // depends on v alone, its cache rebuilt as BSplCLib locates the span) turned about the axis by
  // u, with gp_Trsf::SetRotation's and gp_Pnt::Transform's arithmetic in the same order, so the
  // same bits (SurfaceTest.RevolutionMatchesOcctBitForBit). The profile's points of recent v
  // are remembered, as cos and sin of recent u: the turn was two thirds of a point's cost.
  Vec3 RevolutionPoint(double u, double v) {
    uint64_t kv;
    std::memcpy(&kv, &v, sizeof(v));
    ProfilePoint& c = profile_points_[(kv * 0x9E3779B97F4A7C15ull) >> (64 - kTrigBits)];
    if (!c.filled || c.key != kv) {
      c.key = kv, c.filled = true;
      profile_.D0(v, c.point);
    }
    const CosSin& cu = Trig(u, u_trig_);
    // gp_Mat::SetRotation: (cross matrix x sin + I) + (M M) x (1 - cos), element by element.
    double m[3][3];
    const double one_less = 1.0 - cu.cos;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        m[i][j] = (cross_[i][j] * cu.sin + (i == j ? 1.0 : 0.0)) + square_[i][j] * one_less;
    // gp_Trsf::SetRotation's translation: (-O) M + O; gp_XYZ::Multiply sums left to right.
    auto times = [&m](double x, double y, double z, double out[3]) {
      for (int i = 0; i < 3; ++i) out[i] = m[i][0] * x + m[i][1] * y + m[i][2] * z;
    };
    double loc[3], p[3];
    times(-origin_.X(), -origin_.Y(), -origin_.Z(), loc);
    loc[0] += origin_.X(), loc[1] += origin_.Y(), loc[2] += origin_.Z();
    times(c.point.X(), c.point.Y(), c.point.Z(), p);
    return {p[0] + loc[0], p[1] + loc[1], p[2] + loc[2]};
  }
  struct ProfilePoint {
    uint64_t key = 0;
    bool filled = false;
    gp_Pnt point;
  };

  // std::cos(t), std::sin(t), remembered by the bits of t in a direct-mapped table.
  struct CosSin {
    uint64_t key = 0;
    bool filled = false;
    double cos = 0, sin = 0;
  };
  static constexpr int kTrigBits = 9;
  static const CosSin& Trig(double t, std::vector<CosSin>& table) {
    uint64_t key;
    std::memcpy(&key, &t, sizeof(t));
    CosSin& e = table[(key * 0x9E3779B97F4A7C15ull) >> (64 - kTrigBits)];
    if (!e.filled || e.key != key) e = {key, true, std::cos(t), std::sin(t)};
    return e;
  }

  static constexpr int kSpans = 8;
  struct Span {
    double u0 = 0, u1 = 0, v0 = 0, v1 = 0;  // its knot span: [u0, u1) x [v0, v1)
    uint64_t last_use = 0;
    GeomAdaptor_Surface adaptor;  // for normals
  };
  // The adaptor to evaluate (u, v) with: for a B-spline its span's.
  const GeomAdaptor_Surface& Adaptor(double u, double v) {
    return spans_.empty() ? adaptor_ : SpanOf(u, v).adaptor;
  }
  // A B-spline's span slot for (u, v): the one on its knot span, else the least recently used
  // one, which moves there. A slot's adaptor is put on its span's polynomial (a point in the
  // span's middle) when the slot moves, so that a point takes its span's derivatives whatever the
  // slot served before: an adaptor keeps its cached span for any point within it, and rebuilds at
  // the point otherwise, where a point an ulp below a knot locates the span above.
  Span& SpanOf(double u, double v) {
    ++clock_;
    polynomials_->Normalize(&u, &v);
    Span* last = last_;  // consecutive points mostly share a span: try the last one first
    if (last && last->u0 <= u && u < last->u1 && last->v0 <= v && v < last->v1) {
      last->last_use = clock_;
      return *last;
    }
    Span* oldest = &spans_[0];
    for (Span& span : spans_) {
      if (span.u0 <= u && u < span.u1 && span.v0 <= v && v < span.v1) {
        span.last_use = clock_;
        last_ = &span;
        return span;
      }
      if (span.last_use < oldest->last_use) oldest = &span;
    }
    const int iu = KnotSpan(uknots.at, u, &oldest->u0, &oldest->u1);
    const int iv = KnotSpan(vknots.at, v, &oldest->v0, &oldest->v1);
    gp_Pnt middle;
    oldest->adaptor.D0(0.5 * (uknots.at[iu - 1] + uknots.at[iu]),
                       0.5 * (vknots.at[iv - 1] + vknots.at[iv]), middle);
    oldest->last_use = clock_;
    last_ = oldest;
    return *oldest;
  }

  GeomAdaptor_Surface adaptor_;
  enum class Kind { kOther, kPlane, kCylinder, kCone, kSphere, kTorus, kRevolution };
  Kind kind_ = Kind::kOther;             // which closed form Point() uses, if any
  std::array<gp_XYZ, 4> frame_;          // x, y and z directions and origin of an elementary one
  double radius_ = 0;                    // a cone's reference radius, a torus's major one
  double minor_radius_ = 0;              // a torus's
  double torus_zero_ = 0;                // coordinates this near 0 are 0 (ElSLib::TorusD0)
  double cone_sin_ = 0, cone_cos_ = 0;   // of a cone's semi-angle
  std::vector<CosSin> u_trig_, v_trig_;  // cos and sin of recent angle parameters
  gp_XYZ origin_;                        // a surface of revolution's axis location
  double cross_[3][3] = {}, square_[3][3] = {};   // its rotation's parts (RevolutionPoint)
  GeomAdaptor_Curve profile_;                     // its basis curve
  std::vector<ProfilePoint> profile_points_;      // its profile's points at recent v
  Handle(Geom_BSplineSurface) bspline_;           // null unless B-spline
  std::vector<Span> spans_;                       // empty unless B-spline
  std::unique_ptr<SpanPolynomials> polynomials_;  // B-spline points
  Span* last_ = nullptr;                          // the span slot SpanOf() returned last
  uint64_t clock_ = 0;
};

class OcctCurve final : public Curve {
 public:
  explicit OcctCurve(const TopoDS_Edge& edge) : adaptor_(edge) {
    switch (adaptor_.GetType()) {
      case GeomAbs_Line:
        shape = Shape::kLine;
        break;
      case GeomAbs_Circle:
        shape = Shape::kCircle;
        break;
      default:
        break;
    }
  }
  Vec3 Point(double t) override { return ToVec(adaptor_.Value(t)); }

 private:
  BRepAdaptor_Curve adaptor_;
};

}  // namespace

std::unique_ptr<Surface> WithPointCache(std::unique_ptr<Surface> surface) {
  return std::make_unique<CachedSurface>(std::move(surface));
}

std::unique_ptr<Surface> MakeFaceSurface(const TopoDS_Face& face, bool nurbs) {
  UvBounds bounds;
  BRepTools::UVBounds(face, bounds.umin, bounds.umax, bounds.vmin, bounds.vmax);
  return MakeFaceSurface(face, nurbs, bounds);
}

std::unique_ptr<Surface> MakeFaceSurface(const TopoDS_Face& face, bool nurbs,
                                         const UvBounds& bounds) {
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face);  // location applied
  const double u0 = bounds.umin, u1 = bounds.umax, v0 = bounds.vmin, v1 = bounds.vmax;
  if (nurbs) {
    Handle(Geom_Surface) trimmed = new Geom_RectangularTrimmedSurface(surface, u0, u1, v0, v1);
    surface = GeomConvert::SurfaceToBSplineSurface(trimmed);
  }
  auto s = std::make_unique<OcctSurface>(surface);
  s->umin = u0;
  s->umax = u1;
  s->vmin = v0;
  s->vmax = v1;
  return s;
}

std::unique_ptr<Curve> MakeEdgeCurve(const TopoDS_Edge& edge) {
  if (BRep_Tool::Degenerated(edge)) return nullptr;
  // BRepAdaptor_Curve falls back to the curve on a surface when there is no 3D curve.
  return std::make_unique<OcctCurve>(edge);
}

Vec2 IntoSurfaceRange(const Adaptor3d_Surface& surface, Vec2 uv) {
  auto within = [](double x, double first, double last, bool periodic) {
    if (periodic || Precision::IsInfinite(first) || Precision::IsInfinite(last)) return x;
    return std::clamp(x, first, last);
  };
  return {within(uv.x, surface.FirstUParameter(), surface.LastUParameter(), surface.IsUPeriodic()),
          within(uv.y, surface.FirstVParameter(), surface.LastVParameter(), surface.IsVPeriodic())};
}

}  // namespace rdmesh
