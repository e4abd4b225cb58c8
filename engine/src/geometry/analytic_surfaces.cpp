// The analytic evaluators of the engine's tests and benches: a plane, a cylinder and a sphere
// about the origin, and a circle (surface.h: MakePlaneSurface, ...). Model faces use OcctSurface
// (surface.cpp), which has its own closed forms for these kinds.
#include <cmath>
#include <memory>

#include "geometry/surface.h"

namespace rdmesh {

namespace {

class PlaneSurface final : public Surface {
 public:
  Vec3 Point(double u, double v) override { return {u, v, 0}; }
  Vec3 Normal(double, double) override { return {0, 0, 1}; }
};

class CylinderSurface final : public Surface {
 public:
  explicit CylinderSurface(double r) : r_(r) {
    quadric = {Quadric::Kind::kCylinder, {0, 0, 0}, {0, 0, 1}, r};
  }
  Vec3 Point(double u, double v) override { return {r_ * std::cos(u), r_ * std::sin(u), v}; }
  Vec3 Normal(double u, double) override { return {std::cos(u), std::sin(u), 0}; }

 private:
  double r_;
};

class SphereSurface final : public Surface {
 public:
  explicit SphereSurface(double r) : r_(r) {
    quadric = {Quadric::Kind::kSphere, {0, 0, 0}, {0, 0, 1}, r};
  }
  Vec3 Point(double u, double v) override {
    return {r_ * std::cos(v) * std::cos(u), r_ * std::cos(v) * std::sin(u), r_ * std::sin(v)};
  }
  Vec3 Normal(double u, double v) override {
    return {std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v)};
  }

 private:
  double r_;
};

class CircleCurve final : public Curve {
 public:
  CircleCurve(double r, double z0) : r_(r), z0_(z0) { shape = Shape::kCircle; }
  Vec3 Point(double t) override { return {r_ * std::cos(t), r_ * std::sin(t), z0_}; }

 private:
  double r_, z0_;
};

}  // namespace

std::unique_ptr<Surface> MakePlaneSurface() { return std::make_unique<PlaneSurface>(); }
std::unique_ptr<Surface> MakeCylinderSurface(double radius) {
  return std::make_unique<CylinderSurface>(radius);
}
std::unique_ptr<Surface> MakeSphereSurface(double radius) {
  return std::make_unique<SphereSurface>(radius);
}
std::unique_ptr<Curve> MakeCircleCurve(double radius, double z0) {
  return std::make_unique<CircleCurve>(radius, z0);
}

}  // namespace rdmesh
