#include "geometry/offset_surface.h"

#include <algorithm>
#include <cmath>

namespace rdmesh {

int BendSide(Surface& s, const std::vector<Vec2>& samples, double hu, double hv, double tolerance) {
  double low = 0, high = 0;  // the smallest and largest principal curvature seen
  for (Vec2 q : samples) {
    const double u = q.x, v = q.y;
    const Vec3 p = s.Point(u, v);
    const Vec3 pu = s.Point(u + hu, v), mu = s.Point(u - hu, v);
    const Vec3 pv = s.Point(u, v + hv), mv = s.Point(u, v - hv);
    const Vec3 su = (0.5 / hu) * (pu - mu), sv = (0.5 / hv) * (pv - mv);
    const Vec3 n = s.Normal(u, v);
    const double e = Dot(su, su), f = Dot(su, sv), g = Dot(sv, sv), det = e * g - f * f;
    if (!(det > 1e-12 * e * g)) continue;  // a pole: the normal's turn is seen around it
    const double l = Dot(pu - 2.0 * p + mu, n) / (hu * hu);
    const double nn = Dot(pv - 2.0 * p + mv, n) / (hv * hv);
    const double m = Dot(s.Point(u + hu, v + hv) - s.Point(u + hu, v - hv) -
                             s.Point(u - hu, v + hv) + s.Point(u - hu, v - hv),
                         n) /
                     (4 * hu * hv);
    // Principal curvatures: the roots of det(II - k I) = 0.
    const double mean = (e * nn - 2 * f * m + g * l) / (2 * det);
    const double gauss = (l * nn - m * m) / det;
    const double root = std::sqrt(std::max(0.0, mean * mean - gauss));
    low = std::min(low, mean - root), high = std::max(high, mean + root);
  }
  const double scale = std::max(-low, high);
  if (!(scale > 0)) return 0;
  if (high <= tolerance * scale) return +1;  // bends toward -normal only
  if (-low <= tolerance * scale) return -1;
  return 0;
}

double UvGrid::At(double u, double v) const {
  if (nu <= 0 || nv <= 0) return values.empty() ? 0.0 : values[0];
  const double x = std::clamp((u - umin) / du, 0.0, static_cast<double>(nu));
  const double y = std::clamp((v - vmin) / dv, 0.0, static_cast<double>(nv));
  const int i = std::min(static_cast<int>(x), nu - 1);
  const int j = std::min(static_cast<int>(y), nv - 1);
  const double a = x - i, b = y - j;
  const int row = nv + 1, k = i * row + j;
  return (1 - a) * ((1 - b) * values[k] + b * values[k + 1]) +
         a * ((1 - b) * values[k + row] + b * values[k + row + 1]);
}

namespace {

class OffsetSurface final : public Surface {
 public:
  OffsetSurface(Surface* base, double distance) : base_(base), distance_(distance) {
    umin = base->umin, umax = base->umax, vmin = base->vmin, vmax = base->vmax;
    uknots = base->uknots, vknots = base->vknots;
    quadric = base->quadric;
    if (quadric.kind != Quadric::Kind::kNone) {
      // Along the normal is away from the centre or axis, or toward it: which, from one point.
      const double u = 0.5 * (umin + umax), v = 0.5 * (vmin + vmax);
      const double along = Dot(base->Normal(u, v), Outward(base->Point(u, v)));
      if (!(std::fabs(along) > 0.5)) {
        quadric.kind = Quadric::Kind::kNone;  // not a quadric's normal: offset by Normal()
      } else {
        outward_distance_ = along > 0 ? distance : -distance;
        quadric.radius += quadric.kind == Quadric::Kind::kCone
                              ? outward_distance_ / quadric.cone_cos
                              : outward_distance_;
      }
    }
  }
  Vec3 Point(double u, double v) override {
    const Vec3 p = base_->Point(u, v);
    if (quadric.kind != Quadric::Kind::kNone) return p + outward_distance_ * Outward(p);
    return p + distance_ * base_->Normal(u, v);
  }
  Vec3 Normal(double u, double v) override { return base_->Normal(u, v); }

 private:
  // The unit normal away from a sphere's centre or a cylinder's or cone's axis, at p on it.
  Vec3 Outward(Vec3 p) const {
    const Vec3 d = p - quadric.center;
    if (quadric.kind == Quadric::Kind::kSphere) return Normalized(d);
    const Vec3 radial = Normalized(d - Dot(d, quadric.axis) * quadric.axis);
    if (quadric.kind == Quadric::Kind::kCylinder) return radial;
    // A cone's radius grows by tan(angle) along the axis: its normal leans back by the angle.
    return quadric.cone_cos * radial - quadric.cone_sin * quadric.axis;
  }

  Surface* base_;
  double distance_;
  double outward_distance_ = 0;
};

class FieldOffsetSurface final : public Surface {
 public:
  FieldOffsetSurface(Surface* base, const UvGrid* offsets) : base_(base), offsets_(offsets) {
    umin = base->umin, umax = base->umax, vmin = base->vmin, vmax = base->vmax;
    uknots = base->uknots, vknots = base->vknots;
  }
  Vec3 Point(double u, double v) override {
    const Vec3 p = base_->Point(u, v);
    const double d = offsets_->At(u, v);
    return d == 0 ? p : p + d * base_->Normal(u, v);
  }
  Vec3 Normal(double u, double v) override { return base_->Normal(u, v); }

 private:
  Surface* base_;
  const UvGrid* offsets_;
};

}  // namespace

std::unique_ptr<Surface> MakeFieldOffsetSurface(Surface* base, const UvGrid* offsets) {
  return std::make_unique<FieldOffsetSurface>(base, offsets);
}

std::unique_ptr<Surface> MakeOffsetSurface(Surface* base, double distance) {
  return std::make_unique<OffsetSurface>(base, distance);
}

}  // namespace rdmesh
