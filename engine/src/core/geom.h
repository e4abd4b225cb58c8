#pragma once
// Small vector math used by every stage: 2D (u,v) and 3D points. Header-only.

#include <algorithm>
#include <cmath>

namespace rdmesh {

struct Vec2 {
  double x = 0, y = 0;
};
struct Vec3 {
  double x = 0, y = 0, z = 0;
};

inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
/// 2D cross product (z of the 3D one): positive when b is counter-clockwise from a.
inline double Cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
/// Twice the signed area of (a, b, c): positive for counter-clockwise.
inline double Orient(Vec2 a, Vec2 b, Vec2 c) { return Cross(b - a, c - a); }

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
inline double Dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 Cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double Norm(Vec3 a) { return std::sqrt(Dot(a, a)); }
inline double Dist(Vec3 a, Vec3 b) { return Norm(a - b); }
inline Vec3 Normalized(Vec3 a) {
  double n = Norm(a);
  return n > 0 ? (1.0 / n) * a : Vec3{};
}
/// Area of the 3D triangle (a, b, c).
inline double Area(Vec3 a, Vec3 b, Vec3 c) { return 0.5 * Norm(Cross(b - a, c - a)); }

/// Distance from p to the segment [a, b].
inline double PointSegmentDistance(Vec3 p, Vec3 a, Vec3 b) {
  Vec3 ab = b - a;
  double len2 = Dot(ab, ab);
  double t = len2 > 0 ? std::clamp(Dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return Dist(p, a + t * ab);
}

/// Distance from p to the closed triangle (a, b, c); handles degenerate triangles.
inline double PointTriangleDistance(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  Vec3 n = Cross(b - a, c - a);
  double n2 = Dot(n, n);
  double scale = std::max({Dot(b - a, b - a), Dot(c - a, c - a), Dot(c - b, c - b)});
  if (n2 > 1e-24 * scale * scale) {
    // Inside test against each edge's inward half-plane.
    Vec3 pa = p - a;
    bool inside = Dot(Cross(b - a, p - a), n) >= 0 && Dot(Cross(c - b, p - b), n) >= 0 &&
                  Dot(Cross(a - c, p - c), n) >= 0;
    if (inside) return std::fabs(Dot(pa, n)) / std::sqrt(n2);
  }
  return std::min({PointSegmentDistance(p, a, b), PointSegmentDistance(p, b, c),
                   PointSegmentDistance(p, c, a)});
}

/// The point of the closed triangle (a, b, c) nearest to p, as its barycentric weights w[] of a,
/// b and c; returns its distance to p. Handles degenerate triangles (the nearest edge point).
inline double ClosestOnTriangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c, double w[3]) {
  Vec3 n = Cross(b - a, c - a);
  double n2 = Dot(n, n);
  double scale = std::max({Dot(b - a, b - a), Dot(c - a, c - a), Dot(c - b, c - b)});
  if (n2 > 1e-24 * scale * scale) {
    double wa = Dot(Cross(c - b, p - b), n) / n2, wb = Dot(Cross(a - c, p - c), n) / n2;
    double wc = 1 - wa - wb;
    if (wa >= 0 && wb >= 0 && wc >= 0) {
      w[0] = wa, w[1] = wb, w[2] = wc;
      return Dist(p, wa * a + (wb * b + wc * c));
    }
  }
  const Vec3 corner[3] = {a, b, c};
  double best = HUGE_VAL;
  for (int i = 0; i < 3; ++i) {
    Vec3 s = corner[i], e = corner[(i + 1) % 3] - s;
    double len2 = Dot(e, e);
    double t = len2 > 0 ? std::clamp(Dot(p - s, e) / len2, 0.0, 1.0) : 0.0;
    double d = Dist(p, s + t * e);
    if (d < best) {
      best = d;
      w[i] = 1 - t, w[(i + 1) % 3] = t, w[(i + 2) % 3] = 0;
    }
  }
  return best;
}

}  // namespace rdmesh
