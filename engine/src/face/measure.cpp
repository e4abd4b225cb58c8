#include "face/measure.h"

#include <algorithm>
#include <cmath>

namespace rdmesh {

double OtherCriteriaRatio(const FaceCriteria& c, const TriangleMeasure& m) {
  double v = 0;
  if (c.rd_tolerance > 0) v = std::max(v, m.rd / c.rd_tolerance);
  if (c.max_length > 0) v = std::max(v, m.max_length / c.max_length);
  return v;
}

namespace {

// Largest |h| of the quadratic h(b) = A b1 b2 + B b2 b0 + C b0 b1 over the triangle, where
// A, B, C come from the heights at the edge midpoints (h_mid = coefficient / 4). Exact for a
// quadratic surface patch; returns the barycentric point of the peak in *peak.
double QuadraticPeak(double h0, double h1, double h2, double peak[3]) {
  double A = 4 * h0, B = 4 * h1, C = 4 * h2;
  double best = std::max({std::fabs(h0), std::fabs(h1), std::fabs(h2)});
  if (best == std::fabs(h0))
    peak[0] = 0, peak[1] = 0.5, peak[2] = 0.5;
  else if (best == std::fabs(h1))
    peak[0] = 0.5, peak[1] = 0, peak[2] = 0.5;
  else
    peak[0] = 0.5, peak[1] = 0.5, peak[2] = 0;
  double det = 4 * B * C - (A - B - C) * (A - B - C);
  if (std::fabs(det) > 1e-300) {
    double b1 = B * (A - B + C) / det, b2 = C * (A + B - C) / det, b0 = 1 - b1 - b2;
    if (b0 >= 0 && b1 >= 0 && b2 >= 0) {
      double h = std::fabs(A * b1 * b2 + B * b2 * b0 + C * b0 * b1);
      if (h > best) best = h, peak[0] = b0, peak[1] = b1, peak[2] = b2;
    }
  }
  return best;
}

// The surface over the triangle as a height field h(lambda) = sum c_ij lambda_i lambda_j (zero at
// the corners), fitted through the three edge-midpoint samples where they actually fall: a
// (u,v) midpoint maps beside the 3D midpoint on a distorted parametrisation, so each sample is
// projected onto the plane and placed by its own barycentric coordinates. Returns max |h|.
double FittedPeak(const Vec3 p[3], Vec3 nh, const Vec3 mid[3], double peak[3]) {
  Vec3 e1 = Normalized(p[1] - p[0]);
  Vec3 e2 = Cross(nh, e1);
  Vec2 c[3] = {{0, 0}, {Dot(p[1] - p[0], e1), 0}, {Dot(p[2] - p[0], e1), Dot(p[2] - p[0], e2)}};
  double area = Orient(c[0], c[1], c[2]);
  double rows[3][3], rhs[3];
  for (int k = 0; k < 3; ++k) {
    Vec3 d = mid[k] - p[0];
    Vec2 x{Dot(d, e1), Dot(d, e2)};
    double l0 = Orient(x, c[1], c[2]) / area, l1 = Orient(c[0], x, c[2]) / area;
    double l2 = 1 - l0 - l1;
    rows[k][0] = l1 * l2, rows[k][1] = l2 * l0, rows[k][2] = l0 * l1;
    rhs[k] = Dot(d, nh);
  }
  auto det3 = [](double a[3][3]) {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  };
  double det = det3(rows);
  // The exact midpoints give det = 1/64; a fit far from that is ill-posed (badly distorted
  // parametrisation): fall back to the plain midpoint model.
  if (!(std::fabs(det) > 0.25 / 64)) return QuadraticPeak(rhs[0], rhs[1], rhs[2], peak);
  double coef[3];
  for (int j = 0; j < 3; ++j) {
    double a[3][3];
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) a[r][q] = q == j ? rhs[r] : rows[r][q];
    coef[j] = det3(a) / det;
  }
  double fitted = QuadraticPeak(coef[0] / 4, coef[1] / 4, coef[2] / 4, peak);
  double samples = std::max({std::fabs(rhs[0]), std::fabs(rhs[1]), std::fabs(rhs[2])});
  if (fitted > 2 * samples) return QuadraticPeak(rhs[0], rhs[1], rhs[2], peak);
  return fitted;
}

// Knot lines followed across one triangle in one direction: at most this many are listed.
constexpr int kMaxKnots = 16;
// An edge cut by knot lines into up to kEdgePieces pieces is sampled at the quarter points of
// each; one cut into more (it is long against the knot spacing) at kEdgeSteps even steps.
// Likewise strips of the triangle between knot lines: halved up to kStripPieces, else
// kStripSteps even strips. Fewer samples for many pieces keep the cost bounded on densely
// knotted surfaces, whose pieces are small against the triangle anyway.
constexpr int kEdgePieces = 4, kEdgeSteps = 3, kStripPieces = 4, kStripSteps = 4;

// The knot lines of `k` strictly inside (lo, hi), ascending, into at[]: their count, or
// kMaxKnots + 1 when there are more (then at[] holds the first ones only).
int KnotsWithin(const Surface::KnotLines& k, double lo, double hi, double* at) {
  int n = 0;
  if (k.at.empty() || !(lo < hi)) return 0;
  double first = 0, last = 0;  // the periods to shift the knots by
  // Within one period of the knots (the usual case) only the knots themselves can fall inside:
  // a copy shifted by a period lies wholly at or beyond one end.
  if (k.period > 0 && !(lo >= k.at.front() && hi <= k.at.back())) {
    first = std::floor((lo - k.at.back()) / k.period);
    last = std::ceil((hi - k.at.front()) / k.period);
  }
  for (double shift = first; shift <= last; ++shift) {
    double offset = shift * k.period;
    // A copy of the knots wholly at or below lo, or at or above hi, adds none: skip its search.
    if (k.at.back() <= lo - offset || k.at.front() + offset >= hi) continue;
    auto it = std::upper_bound(k.at.begin(), k.at.end(), lo - offset);
    for (; it != k.at.end() && *it + offset < hi; ++it) {
      if (n > kMaxKnots) return n;
      if (n == 0 || *it + offset > at[n - 1]) at[n++] = *it + offset;
    }
  }
  return n;
}

// Where to sample [cut[0], cut[pieces]], cut into polynomial pieces at cut[1..pieces): into
// out[] as (start, end) pairs whose middles are the samples, both halves of every piece (a cubic
// piece may bulge both ways) when there are at most max_pieces, else `steps` even intervals.
// Returns the number of intervals.
int Intervals(const double* cut, int pieces, int max_pieces, int steps, double* out) {
  int n = 0;
  if (pieces <= max_pieces) {
    for (int k = 0; k < pieces; ++k) {
      double mid = 0.5 * (cut[k] + cut[k + 1]);
      out[n++] = cut[k], out[n++] = mid, out[n++] = mid, out[n++] = cut[k + 1];
    }
  } else {
    double lo = cut[0], hi = cut[pieces];
    for (int k = 0; k < steps; ++k)
      out[n++] = lo + (hi - lo) * k / steps, out[n++] = lo + (hi - lo) * (k + 1) / steps;
  }
  return n / 2;
}

// The part of the polygon poly[0..n) where sign * coordinate(axis) <= bound, into out[]:
// returns its vertex count.
int ClipPolygon(const Vec2* poly, int n, bool axis_v, double sign, double bound, Vec2* out) {
  int m = 0;
  auto f = [&](Vec2 q) { return sign * (axis_v ? q.y : q.x) - bound; };
  for (int i = 0; i < n; ++i) {
    Vec2 a = poly[i], b = poly[(i + 1) % n];
    double fa = f(a), fb = f(b);
    if (fa <= 0) out[m++] = a;
    if ((fa < 0 && fb > 0) || (fa > 0 && fb < 0)) out[m++] = a + (fa / (fa - fb)) * (b - a);
  }
  return m;
}

// The largest height over the plane of p[] (unit normal nh) of extra samples on a B-spline,
// where the one quadratic of FittedPeak cannot follow the surface: each polynomial piece may
// bulge on its own, a cubic one even both ways (an S along a long triangle is nearly level with
// its plane at the edge midpoints). Samples along each edge that crosses knot lines, and along
// the longest edge even within one piece (an edge's samples do not depend on its direction, so
// the triangles on either side of it see the same points); and across the triangle in strips
// between the knot lines of each direction, at each strip's vertex mean, both halves of a
// triangle within one piece included. Intervals places them all. Returns 0, leaving *where, on
// a surface without knots.
double KnotPeak(Surface& s, const Vec2 uv[3], const Vec3 p[3], Vec3 nh, Vec2* where) {
  if (s.uknots.at.empty() && s.vknots.at.empty()) return 0;
  const Vec3 p0 = p[0];
  int longest = 0;  // the edge p[i] p[i + 1] most likely to hold a whole S of its piece
  for (int i = 1; i < 3; ++i) {
    Vec3 e = p[(i + 1) % 3] - p[i], f = p[(longest + 1) % 3] - p[longest];
    if (Dot(e, e) > Dot(f, f)) longest = i;
  }
  double best = 0;
  auto sample = [&](Vec2 q) {
    double h = std::fabs(Dot(nh, s.Point(q.x, q.y) - p0));
    if (h > best) best = h, *where = q;
  };
  double cut[2 * kMaxKnots + 4], interval[4 * kMaxKnots + 8];  // 2 x (pieces + 1) bounds
  for (int i = 0; i < 3; ++i) {
    Vec2 a = uv[i], b = uv[(i + 1) % 3];
    if (b.x < a.x || (b.x == a.x && b.y < a.y)) std::swap(a, b);
    // Edge parameters of the crossings of both directions, merged.
    int n = 0;
    for (bool axis_v : {false, true}) {
      double ca = axis_v ? a.y : a.x, cb = axis_v ? b.y : b.x;
      int within = KnotsWithin(axis_v ? s.vknots : s.uknots, std::min(ca, cb), std::max(ca, cb),
                               cut + 1 + n);
      for (int k = 0; k < within; ++k) cut[1 + n + k] = (cut[1 + n + k] - ca) / (cb - ca);
      n += within;
    }
    if (n == 0 && i != longest) continue;
    std::sort(cut + 1, cut + 1 + n);
    cut[0] = 0, cut[n + 1] = 1;
    int count = Intervals(cut, n + 1, kEdgePieces, kEdgeSteps, interval);
    for (int k = 0; k < count; ++k) {
      double at = 0.5 * (interval[2 * k] + interval[2 * k + 1]);
      sample((1 - at) * a + at * b);
    }
  }
  for (bool axis_v : {false, true}) {
    auto coord = [&](Vec2 q) { return axis_v ? q.y : q.x; };
    double lo = std::min({coord(uv[0]), coord(uv[1]), coord(uv[2])});
    double hi = std::max({coord(uv[0]), coord(uv[1]), coord(uv[2])});
    int n = KnotsWithin(axis_v ? s.vknots : s.uknots, lo, hi, cut + 1);
    cut[0] = lo, cut[n + 1] = hi;
    int count = Intervals(cut, n + 1, kStripPieces, kStripSteps, interval);
    for (int k = 0; k < count; ++k) {
      Vec2 above[4], strip[5];
      int m = ClipPolygon(uv, 3, axis_v, -1, -interval[2 * k], above);
      m = ClipPolygon(above, m, axis_v, 1, interval[2 * k + 1], strip);
      if (m == 0) continue;
      Vec2 sum;
      for (int j = 0; j < m; ++j) sum = sum + strip[j];
      sample((1.0 / m) * sum);
    }
  }
  return best;
}

}  // namespace

namespace {

// Corners lie on the surface but for boundary nodes, which lie on edge curves, within the
// B-rep's tolerance of it. The deviations below are measured from the plane of the corners'
// offsets (less the offsets interpolated linearly), as the estimate for other surfaces measures
// heights over the corners' plane: what refinement can change. Where a corner lies off by more
// than kExactCornerOffset of the request, the corners' offsets are a part of the deviation that
// no refinement removes; there the estimate is kept (its edge heights see part of it), and the
// functions below return -1.
constexpr double kExactCornerOffset = 0.01;

// The largest distance of the triangle p[] from a cone: for a point at height z along the axis
// and distance rho from it, (R + z tan a - rho) cos a inward, where R + z tan a > 0 (this side of
// the apex). Less a linear function, that is concave over a triangle whose plane meets the axis
// outside it, so its largest value lies on an edge; along an edge it is concave in the edge
// parameter, largest where (y . e) / |y| = k (y the point across the axis, e the edge across it,
// k from the edge's rise and its corners' offsets): a quadratic. Into peak[], the barycentric
// weights of where. -1 where a corner lies beyond the apex or off the surface: not measured.
double ConeDeviation(const Surface::Quadric& q, const Vec3 p[3], double offset_limit,
                     double peak[3]) {
  Vec3 y[3];
  double z[3], f[3];
  const double tan_a = q.cone_sin / q.cone_cos;
  auto inward = [&](Vec3 yy, double zz) { return (q.radius + zz * tan_a - Norm(yy)) * q.cone_cos; };
  for (int i = 0; i < 3; ++i) {
    Vec3 d = p[i] - q.center;
    z[i] = Dot(d, q.axis);
    y[i] = d - z[i] * q.axis;
    if (!(q.radius + z[i] * tan_a > 0)) return -1;
    f[i] = inward(y[i], z[i]);
    if (!(std::fabs(f[i]) <= offset_limit)) return -1;
  }
  double dev = 0;
  peak[0] = peak[1] = peak[2] = 1.0 / 3;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const Vec3 e = y[j] - y[i];
    const double ez = z[j] - z[i], E = Dot(e, e), B = Dot(y[i], e);
    const double k = ez * tan_a - (f[j] - f[i]) / q.cone_cos, denom = E * (E - k * k);
    if (!(E > 0) || !(std::fabs(denom) > 1e-300)) continue;
    // E (E - k^2) l^2 + 2 B (E - k^2) l + B^2 - k^2 Y = 0 (Y = |y|^2), whose discriminant over
    // 4 E^2 (E - k^2)^2 is k^2 (E Y - B^2) / (E^2 (E - k^2)), with E Y - B^2 = |y x e|^2: so
    // written, an edge across the axis (k near 0, both roots near -B / E) does not lose its peak
    // to a difference that rounding makes negative (gmsh_solid_56 face 11 at 1e-4: 0.049 mm
    // measured, 0.0195 estimated). Both roots are taken: the one squaring adds is a point of the
    // edge too, whose value is no more than the peak.
    const Vec3 ye = Cross(y[i], e);
    const double half = B / E, disc = k * k * Dot(ye, ye) / (E * denom);
    if (!(disc >= 0)) continue;
    for (double l : {-half - std::sqrt(disc), -half + std::sqrt(disc)}) {
      if (!(l > 0 && l < 1)) continue;
      double g = inward(y[i] + l * e, z[i] + l * ez) - ((1 - l) * f[i] + l * f[j]);
      if (g > dev) dev = g, peak[0] = peak[1] = peak[2] = 0, peak[i] = 1 - l, peak[j] = l;
    }
  }
  return dev;
}

// The largest distance of the triangle p[] from a sphere or cylinder, inward: R less the
// distance of its point nearest to the centre (axis), less the corners' offsets there. Into
// peak[], the barycentric weights of where; -1 where a corner lies off the surface.
double QuadricDeviation(const Surface::Quadric& q, const Vec3 p[3], double offset_limit,
                        double peak[3]) {
  Vec3 x[3];  // relative to the centre; for a cylinder, across its axis
  double f[3];
  for (int i = 0; i < 3; ++i) {
    x[i] = p[i] - q.center;
    if (q.kind == Surface::Quadric::Kind::kCylinder) x[i] = x[i] - Dot(x[i], q.axis) * q.axis;
    f[i] = q.radius - Norm(x[i]);
    if (!(std::fabs(f[i]) <= offset_limit)) return -1;
  }
  double dev = q.radius - ClosestOnTriangle(Vec3{}, x[0], x[1], x[2], peak);
  for (int i = 0; i < 3; ++i) dev -= peak[i] * f[i];
  return std::max(dev, 0.0);
}

// The representation deficit a split at the surface point `cen` above the centroid removes: the
// three triangles' area over the triangle's (area2 is twice its area).
double CentroidSplitRd(const Vec3 p[3], Vec3 cen, double area2) {
  double split = Area(p[0], p[1], cen) + Area(p[1], p[2], cen) + Area(p[2], p[0], cen);
  return split / (0.5 * area2) - 1.0;
}

// Sets m->deviation to dev and m->violation to the largest of the criteria's ratios.
void Conclude(const FaceCriteria& c, double dev, TriangleMeasure* m) {
  m->deviation = dev;
  double v = OtherCriteriaRatio(c, *m);
  if (c.max_deviation > 0) v = std::max(v, dev / c.max_deviation);
  if (c.min_length > 0 && m->max_length < 2 * c.min_length) v = std::min(v, 1.0);
  m->violation = v;
}

// MeasureTriangle's work. With `may_stop` it returns false as soon as the centroid height alone
// puts the violation at or above `limit` (the fitted peak can only raise the deviation); then
// m->violation holds that lower bound and nothing else is set. It also returns false, with *m
// complete but for the knot-line samples, when the other samples put it at or above `limit`.
bool Measure(Surface& s, const Vec2 uv[3], const Vec3 p[3], const FaceCriteria& c, bool may_stop,
             double limit, TriangleMeasure* out) {
  TriangleMeasure& m = *out;
  m = TriangleMeasure();
  Vec2 cen_uv = (1.0 / 3.0) * (uv[0] + uv[1] + uv[2]);
  Vec3 n = Cross(p[1] - p[0], p[2] - p[0]);
  double area2 = Norm(n);
  double len2 = std::max({Dot(p[1] - p[0], p[1] - p[0]), Dot(p[2] - p[1], p[2] - p[1]),
                          Dot(p[0] - p[2], p[0] - p[2])});
  m.max_length = std::sqrt(len2);
  const bool flat = area2 > 1e-10 * len2;  // not degenerate in 3D
  // A sphere, cylinder or cone: the exact deviation, no samples (a pole triangle, two corners
  // at one point, stands for nothing: it falls through to the case below, as do a triangle on
  // a cone beyond its apex and one with a corner off the surface).
  double peak[3], dev = -1;
  if (s.quadric.kind != Surface::Quadric::Kind::kNone &&
      (flat ||
       std::min({Dist(p[0], p[1]), Dist(p[1], p[2]), Dist(p[2], p[0])}) > 1e-12 * m.max_length)) {
    const double offset_limit =
        c.max_deviation > 0 ? kExactCornerOffset * c.max_deviation : HUGE_VAL;
    dev = s.quadric.kind == Surface::Quadric::Kind::kCone
              ? ConeDeviation(s.quadric, p, offset_limit, peak)
              : QuadricDeviation(s.quadric, p, offset_limit, peak);
  }
  if (dev >= 0) {
    m.exact = true;
    m.worst_uv = peak[0] * uv[0] + (peak[1] * uv[1] + peak[2] * uv[2]);
    if (c.rd_tolerance > 0 && flat) {
      m.rd = CentroidSplitRd(p, s.Point(cen_uv.x, cen_uv.y), area2);
    } else if (!flat) {
      m.rd = dev > 0 ? INFINITY : 0;
    }
    Conclude(c, dev, &m);
    return !(may_stop && m.violation >= limit);
  }
  Vec3 cen = s.Point(cen_uv.x, cen_uv.y);
  if (may_stop && flat && c.max_deviation > 0 &&
      !(c.min_length > 0 && m.max_length < 2 * c.min_length)) {
    Vec3 nh = (1.0 / area2) * n;
    double bound = std::fabs(Dot(nh, cen - p[0])) / c.max_deviation;
    if (bound >= limit) {
      m.violation = bound;
      return false;
    }
  }
  Vec3 mid[3];
  for (int i = 0; i < 3; ++i) {
    Vec2 mid_uv = 0.5 * (uv[(i + 1) % 3] + uv[(i + 2) % 3]);
    mid[i] = s.Point(mid_uv.x, mid_uv.y);
  }
  dev = 0;
  bool stopped = false;  // skipped the knot samples, known to violate the limit
  m.worst_uv = cen_uv;
  if (flat) {
    // Heights of the surface over the triangle's plane: at the centroid, and the peak of the
    // quadratic through the edge midpoints (exact for a quadratic patch).
    Vec3 nh = (1.0 / area2) * n;
    dev = FittedPeak(p, nh, mid, peak);
    m.worst_uv = peak[0] * uv[0] + (peak[1] * uv[1] + peak[2] * uv[2]);
    double hc = std::fabs(Dot(nh, cen - p[0]));
    if (hc > dev) dev = hc, m.worst_uv = cen_uv;
    // Samples between knot lines, only where they may change the outcome: not for a triangle
    // these samples put over the limit already (it is split anyway, or a probe rejects it; the
    // probe then gets false below), nor one too small to split.
    double gate = c.max_deviation * (may_stop ? std::min(limit, 1.0) : 1.0);
    if (dev < gate && !(c.min_length > 0 && m.max_length < 2 * c.min_length)) {
      Vec2 knot_uv;
      double hk = KnotPeak(s, uv, p, nh, &knot_uv);
      if (hk > dev) dev = hk, m.worst_uv = knot_uv;
    } else if (may_stop && dev >= gate && dev < c.max_deviation) {
      stopped = true;
    }
    if (c.rd_tolerance > 0) m.rd = CentroidSplitRd(p, cen, area2);
  } else {
    // Degenerate in 3D. At a pole (two corners at one point) it vanishes from the output and
    // stands for nothing; otherwise it is a sliver: measure the surface against its segment.
    double shortest = std::min({Dist(p[0], p[1]), Dist(p[1], p[2]), Dist(p[2], p[0])});
    if (shortest > 1e-12 * m.max_length) {
      dev = PointTriangleDistance(cen, p[0], p[1], p[2]);
      for (int i = 0; i < 3; ++i)
        dev = std::max(dev, PointTriangleDistance(mid[i], p[0], p[1], p[2]));
      m.rd = dev > 0 ? INFINITY : 0;
    }
  }
  Conclude(c, dev, &m);
  return !stopped;
}

}  // namespace

double DeviationLimit(const FaceCriteria& c, const Vec2 uv[3]) {
  if (c.deviation_scale == nullptr) return c.max_deviation;
  const Vec2 cen = (1.0 / 3.0) * (uv[0] + uv[1] + uv[2]);
  double scale = c.deviation_scale->At(cen.x, cen.y);
  for (int i = 0; i < 3; ++i) scale = std::min(scale, c.deviation_scale->At(uv[i].x, uv[i].y));
  return c.max_deviation * scale;
}

namespace {

// The criteria for one triangle: a varying deviation limit fixed at its value there.
FaceCriteria AtTriangle(const FaceCriteria& c, const Vec2 uv[3]) {
  FaceCriteria local = c;
  local.max_deviation = DeviationLimit(c, uv);
  local.deviation_scale = nullptr;
  return local;
}

}  // namespace

TriangleMeasure MeasureTriangle(Surface& s, const Vec2 uv[3], const Vec3 p[3],
                                const FaceCriteria& c) {
  TriangleMeasure m;
  Measure(s, uv, p, c.deviation_scale ? AtTriangle(c, uv) : c, false, 0, &m);
  return m;
}

bool MeasureTriangleBelow(Surface& s, const Vec2 uv[3], const Vec3 p[3], const FaceCriteria& c,
                          double limit, TriangleMeasure* m) {
  return Measure(s, uv, p, c.deviation_scale ? AtTriangle(c, uv) : c, true, limit, m);
}

double TriangleAgreement(const Vec2 uv[3], const Vec3 p[3], const Vec3 normals[3]) {
  double o = Orient(uv[0], uv[1], uv[2]);
  Vec2 e0 = uv[1] - uv[0], e1 = uv[2] - uv[1], e2 = uv[0] - uv[2];
  double l2 =
      std::max({e0.x * e0.x + e0.y * e0.y, e1.x * e1.x + e1.y * e1.y, e2.x * e2.x + e2.y * e2.y});
  if (!(o > 1e-12 * l2)) return kInvalid;
  Vec3 n = Cross(p[1] - p[0], p[2] - p[0]);
  double len2 = std::max({Dot(p[1] - p[0], p[1] - p[0]), Dot(p[2] - p[1], p[2] - p[1]),
                          Dot(p[0] - p[2], p[0] - p[2])});
  double area2 = Norm(n);
  if (!(area2 > 1e-6 * len2)) {
    // Degenerate in 3D: only a pole triangle (two corners at one point) is acceptable.
    double shortest = std::min({Dist(p[0], p[1]), Dist(p[1], p[2]), Dist(p[2], p[0])});
    return shortest <= 1e-12 * std::sqrt(len2) ? 1.0 : kInvalid;
  }
  Vec3 nh = (1.0 / area2) * n;
  double worst = 1.0;
  for (int i = 0; i < 3; ++i) worst = std::min(worst, Dot(nh, normals[i]));
  return worst;
}

void MeasureEdgeHeights(Surface& s, const Vec2 uv[3], const Vec3 p[3], const Vec3 normals[3],
                        const FaceCriteria& criteria, int edges, TriangleMeasure* m) {
  const FaceCriteria c = criteria.deviation_scale ? AtTriangle(criteria, uv) : criteria;
  if (!(c.max_deviation > 0) || (c.min_length > 0 && m->max_length < 2 * c.min_length)) return;
  if (m->exact) return;  // nothing to add
  for (int i = 0; i < 3; ++i) {
    if (!(edges >> i & 1)) continue;
    const int a = (i + 1) % 3, b = (i + 2) % 3;
    double length = Dist(p[a], p[b]);
    if (!(length > 0)) continue;
    Vec3 d = (1.0 / length) * (p[b] - p[a]);
    Vec3 normal = normals[a] + normals[b];
    normal = normal - Dot(normal, d) * d;  // across the edge
    double norm = Norm(normal);
    if (!(norm > 1e-12)) continue;
    Vec2 q = 0.5 * (uv[a] + uv[b]);
    double h = std::fabs(Dot(normal, s.Point(q.x, q.y) - p[a])) / norm;
    if (h > m->deviation) m->deviation = h, m->worst_uv = q;
  }
  m->violation = std::max(m->violation, m->deviation / c.max_deviation);
}

double DenseDeviation(Surface& s, const Vec2 uv[3], const Vec3 p[3], int edges, double suspect,
                      Vec2* where) {
  // The surface over the barycentric grid of step 1/kN: X at each node's (u,v) weights b, and
  // from the grid the derivatives of X(b) at each node.
  constexpr int kN = 4;
  auto q_of = [&](Vec2 b) { return (1 - b.x - b.y) * uv[0] + (b.x * uv[1] + b.y * uv[2]); };
  auto point = [&](Vec2 b) {
    const Vec2 q = q_of(b);
    return s.Point(q.x, q.y);
  };
  Vec3 x[kN + 1][kN + 1];
  for (int i = 0; i <= kN; ++i)
    for (int j = 0; i + j <= kN; ++j) x[i][j] = point({double(i) / kN, double(j) / kN});
  auto column = [&](int i, int j, bool along_j) {  // dX / db_1 (or db_2) at node (i, j)
    auto at = [&](int k) { return along_j ? x[i][k] : x[k][j]; };
    const int c = along_j ? j : i, room = kN - i - j;
    const int lo = c > 0 ? c - 1 : c, hi = room > 0 ? c + 1 : c;
    return (double(kN) / (hi - lo)) * (at(hi) - at(lo));
  };
  // The Gauss-Newton step toward `target` from a surface point x with derivative columns c1, c2
  // (along two parameters): into *d; false when the columns are degenerate.
  auto solve = [](Vec3 target, Vec3 x, Vec3 c1, Vec3 c2, Vec2* d) {
    const double a11 = Dot(c1, c1), a12 = Dot(c1, c2), a22 = Dot(c2, c2);
    const double det = a11 * a22 - a12 * a12;
    if (!(det > 1e-12 * a11 * a22)) return false;
    const Vec3 r = target - x;
    const double r1 = Dot(c1, r), r2 = Dot(c2, r);
    *d = {(a22 * r1 - a12 * r2) / det, (a11 * r2 - a12 * r1) / det};
    return true;
  };
  // The robust phase works in (u,v): its steps are bounded by the triangle's longest side in
  // (u,v), not by the triangle's width, so a sliver in (u,v) can search across its own width.
  double span = 0;
  for (int i = 0; i < 3; ++i)
    span = std::max(
        span, std::fabs(uv[(i + 1) % 3].x - uv[i].x) + std::fabs(uv[(i + 1) % 3].y - uv[i].y));
  // Every surface point's distance from the target is an upper bound of the nearest one's: the
  // search keeps the least it finds, at (u,v) `at`, S(at) = `x_at`.
  double best = 0;
  auto nearest = [&](Vec2 w, Vec3 xw, Vec3 c1, Vec3 c2) {
    const Vec3 target = (1 - w.x - w.y) * p[0] + (w.x * p[1] + w.y * p[2]);
    double d = Dist(target, xw);
    Vec2 at = q_of(w), b = w, db;
    Vec3 x_at = xw, xb = xw;
    // Two steps with the grid's derivatives, within a quarter of the triangle beyond its edges.
    for (int k = 0; k < 2 && solve(target, xb, c1, c2, &db); ++k) {
      b = {std::clamp(b.x + db.x, -0.25, 1.25), std::clamp(b.y + db.y, -0.25, 1.25)};
      xb = point(b);
      if (Dist(target, xb) < d) d = Dist(target, xb), at = q_of(b), x_at = xb;
    }
    // A point that reads over `suspect`: more steps from the best so far, in (u,v) with S's
    // derivatives by differences there, each at most the triangle's longest (u,v) side, within
    // the face's bounds (an uneven parametrisation can put the nearest surface point in a
    // neighbour's patch, or across a sliver's width).
    if (d > suspect && span > 0) {
      const double h = span / 64;
      Vec2 q = at, dq;
      Vec3 xq = x_at;
      for (int k = 0; k < 6; ++k) {
        const Vec3 su = (1 / h) * (s.Point(q.x + h, q.y) - xq);
        const Vec3 sv = (1 / h) * (s.Point(q.x, q.y + h) - xq);
        if (!solve(target, xq, su, sv, &dq)) break;
        const double len = std::fabs(dq.x) + std::fabs(dq.y);
        if (len > span) dq = (span / len) * dq;
        const Vec2 next{std::clamp(q.x + dq.x, s.umin, s.umax),
                        std::clamp(q.y + dq.y, s.vmin, s.vmax)};
        if (std::fabs(next.x - q.x) + std::fabs(next.y - q.y) < 1e-6 * span) break;
        q = next, xq = s.Point(q.x, q.y);
        if (Dist(target, xq) < d) d = Dist(target, xq), at = q;
      }
    }
    if (d > best) best = d, *where = at;
  };
  auto follow = [&](int i, int j) {
    nearest({double(i) / kN, double(j) / kN}, x[i][j], column(i, j, false), column(i, j, true));
  };
  // The centroid (not a grid node) with the mean derivatives of the three nodes around it.
  const Vec2 centroid{1.0 / 3, 1.0 / 3};
  nearest(centroid, point(centroid),
          (1.0 / 3) * (column(1, 1, false) + column(2, 1, false) + column(1, 2, false)),
          (1.0 / 3) * (column(1, 1, true) + column(2, 1, true) + column(1, 2, true)));
  follow(1, 1), follow(2, 1), follow(1, 2);  // (1/2, 1/4, 1/4) and its turns
  // Edge k runs between corners k + 1 and k + 2: edge 0 is i + j = kN, edge 1 is i = 0, edge 2
  // is j = 0.
  for (int t = 1; t < kN; ++t) {
    if (edges & 1) follow(t, kN - t);
    if (edges & 2) follow(0, t);
    if (edges & 4) follow(t, 0);
  }
  return best;
}

double SurfaceSideDeviation(Surface& s, const Vec2 uv[3], Vec2 extra, int edges, const Vec3* near,
                            int count, double limit, Vec2* where) {
  constexpr int kN = 8;
  constexpr int kMaxDepth = 3;      // sub-triangles down to 1/64 of a grid cell
  constexpr int kMaxSamples = 400;  // a bound on the cost per triangle
  double best = 0;
  int samples = 0;
  // A sample of barycentric (b1, b2): its point and its distance to the nearest triangle. Points
  // on a skipped edge read 0: the chord or the B-rep's edge holds them. The distance is folded
  // over the triangles lazily: after the first (an upper bound) the rest only where a decision
  // needs it, which gives the same readings for a quarter of the distances.
  struct Sample {
    double b1, b2;
    Vec3 x;
    mutable double d;
    mutable int folded;  // triangles folded into d so far
  };
  auto exact = [&](const Sample& r) -> double {
    for (; r.folded < count; ++r.folded) {
      const int k = r.folded;
      r.d =
          std::min(r.d, PointTriangleDistance(r.x, near[3 * k], near[3 * k + 1], near[3 * k + 2]));
    }
    return r.d;
  };
  auto on_skipped_edge = [&](double b1, double b2) {
    return (b1 == 0 && !(edges & 2)) || (b2 == 0 && !(edges & 4)) ||
           (std::fabs(b1 + b2 - 1) < 1e-12 && !(edges & 1));
  };
  auto sample = [&](double b1, double b2) {
    const Vec2 q = (1 - b1 - b2) * uv[0] + (b1 * uv[1] + b2 * uv[2]);
    Sample r{b1, b2, s.Point(q.x, q.y), 0, count};
    const bool corner = (b1 == 0 && b2 == 0) || b1 == 1 || b2 == 1;
    if (corner || on_skipped_edge(b1, b2)) return r;  // the corners lie on the surface
    ++samples;
    r.d = HUGE_VAL, r.folded = 0;
    if (count > 0) {
      r.d = std::min(r.d, PointTriangleDistance(r.x, near[0], near[1], near[2]));
      r.folded = 1;
    }
    // The nearest is no farther than the first: below the best so far, it cannot be the best.
    if (r.d > best && exact(r) > best) best = r.d, *where = q;
    return r;
  };
  // Grid node (i, j) has weights (1 - b1 - b2, b1, b2): edge 0 is i + j = kN, edge 1 is i = 0,
  // edge 2 is j = 0.
  Sample grid[kN + 1][kN + 1];
  for (int i = 0; i <= kN; ++i)
    for (int j = 0; i + j <= kN; ++j) grid[i][j] = sample(double(i) / kN, double(j) / kN);
  // A cell's points lie within its sag of the plane of its corners, and the distance to the mesh
  // is 1-Lipschitz: where the corners' largest reading plus the sag passes the limit, the cell is
  // split in four and read again (a sliver's grid can step over a bulge beside its corner).
  auto sag_of = [](const Sample& a, const Sample& b, const Sample& m) {
    return Dist(m.x, 0.5 * (a.x + b.x));
  };
  auto refine = [&](auto&& self, const Sample& a, const Sample& b, const Sample& c, double sag,
                    int depth) -> void {
    if (depth > kMaxDepth || samples >= kMaxSamples) return;
    if (!(std::max({a.d, b.d, c.d}) + sag > limit)) return;  // upper bounds: so would the exact
    if (!(std::max({exact(a), exact(b), exact(c)}) + sag > limit)) return;
    const Sample ab = sample(0.5 * (a.b1 + b.b1), 0.5 * (a.b2 + b.b2));
    const Sample bc = sample(0.5 * (b.b1 + c.b1), 0.5 * (b.b2 + c.b2));
    const Sample ca = sample(0.5 * (c.b1 + a.b1), 0.5 * (c.b2 + a.b2));
    // The children's sag: a quarter of the largest measured at this level's midpoints.
    const double child = 0.25 * std::max({sag_of(a, b, ab), sag_of(b, c, bc), sag_of(c, a, ca)});
    self(self, a, ab, ca, child, depth + 1);
    self(self, ab, b, bc, child, depth + 1);
    self(self, ca, bc, c, child, depth + 1);
    self(self, ab, bc, ca, child, depth + 1);
  };
  if (limit > 0) {
    // A cell's sag from the grid's second differences through its corners (a chord of one step
    // bows by an eighth of the second difference).
    auto second = [&](int i, int j) {
      double m = 0;
      if (i > 0 && i + j < kN)
        m = std::max(m, Dist(grid[i - 1][j].x + grid[i + 1][j].x, 2 * grid[i][j].x));
      if (j > 0 && i + j < kN)
        m = std::max(m, Dist(grid[i][j - 1].x + grid[i][j + 1].x, 2 * grid[i][j].x));
      if (i > 0 && j > 0 && i + j <= kN)
        m = std::max(m, Dist(grid[i - 1][j + 1].x + grid[i + 1][j - 1].x, 2 * grid[i][j].x));
      return m / 8;
    };
    double bend[kN + 1][kN + 1];
    for (int i = 0; i <= kN; ++i)
      for (int j = 0; i + j <= kN; ++j) bend[i][j] = second(i, j);
    for (int i = 0; i < kN; ++i) {
      for (int j = 0; i + j < kN; ++j) {
        const double up = std::max({bend[i][j], bend[i + 1][j], bend[i][j + 1]});
        refine(refine, grid[i][j], grid[i + 1][j], grid[i][j + 1], up, 0);
        if (i + j + 2 <= kN) {
          const double down = std::max({bend[i + 1][j], bend[i][j + 1], bend[i + 1][j + 1]});
          refine(refine, grid[i + 1][j], grid[i + 1][j + 1], grid[i][j + 1], down, 0);
        }
      }
    }
  }
  sample(1.0 / 3, 1.0 / 3);
  const double area = Orient(uv[0], uv[1], uv[2]);
  if (area > 0) {
    const double w0 = Orient(extra, uv[1], uv[2]) / area, w1 = Orient(uv[0], extra, uv[2]) / area;
    if (w0 > 1e-9 && w1 > 1e-9 && 1 - w0 - w1 > 1e-9) {
      double d = HUGE_VAL;
      const Vec3 x = s.Point(extra.x, extra.y);
      for (int k = 0; k < count; ++k)
        d = std::min(d, PointTriangleDistance(x, near[3 * k], near[3 * k + 1], near[3 * k + 2]));
      if (d > best) best = d, *where = extra;
    }
  }
  return best;
}

double SplitAreaRatio(Surface& s, const Vec2 uv[3], const Vec3 p[3], Vec2 q) {
  Vec3 x = s.Point(q.x, q.y);
  double a = Area(p[0], p[1], p[2]);
  if (!(a > 0)) return 0;
  return (Area(p[0], p[1], x) + Area(p[1], p[2], x) + Area(p[2], p[0], x)) / a;
}

}  // namespace rdmesh
