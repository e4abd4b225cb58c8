#include "boundary/edge_discretize.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "geometry/pattern_search.h"

namespace rdmesh {

SegmentMeasure MeasureSegment(Curve& curve, double a, double b,
                              const std::vector<EdgeSide>* sides) {
  SegmentMeasure m;
  Vec3 pa = curve.Point(a), pb = curve.Point(b);
  m.chord = Dist(pa, pb);
  double sum = 0, far = 0.5 * (a + b), far_value = 0;
  if (curve.shape == Curve::Shape::kLine) {
    // Straight: the curve is its chord. Split in the middle.
    m.split = far;
    sum = m.chord;
  } else if (curve.shape == Curve::Shape::kCircle) {
    // An arc, by angle: symmetric about its middle, which is both the farthest point from the
    // chord and the split that maximises the sum of the sub-chords.
    Vec3 pm = curve.Point(far);
    m.split = far;
    sum = Dist(pa, pm) + Dist(pm, pb);
    far_value = PointSegmentDistance(pm, pa, pb);
  } else {
    // The split that maximises the sum of the sub-chords is, on a small segment, the point
    // farthest from the chord; search the chord sum (the paper's objective) and measure both.
    m.split = MaximizeOnInterval(
        [&](double t) {
          Vec3 p = curve.Point(t);
          return Dist(pa, p) + Dist(p, pb);
        },
        a, b, 5, 14, &sum);
    far = MaximizeOnInterval([&](double t) { return PointSegmentDistance(curve.Point(t), pa, pb); },
                             a, b, 5, 12, &far_value);
  }
  m.sagitta = far_value;
  if (sides && !sides->empty() && far_value > 0) {
    // The sagitta vector, from the chord to the farthest point, split along each face's normal.
    Vec3 p = curve.Point(far), d = pb - pa;
    double len2 = Dot(d, d);
    double s = len2 > 0 ? std::clamp(Dot(p - pa, d) / len2, 0.0, 1.0) : 0.0;
    Vec3 sag = p - (pa + s * d);
    for (const EdgeSide& side : *sides) {
      Vec3 n = side.normal(far);
      double h = Dot(sag, n);
      double tangential = std::sqrt(std::max(0.0, Dot(sag, sag) - h * h));
      m.across = std::max(m.across, tangential / side.max_overshoot);
    }
  }
  // One split recovers 3/4 of the length a segment misses (the deficit falls as 1/n^2), so the
  // segment's own RD (L_S - L_E) / L_E is 4/3 of the gain of its best split.
  m.rd = m.chord > 0 ? (sum / m.chord - 1.0) * 4.0 / 3.0 : INFINITY;
  return m;
}

double SegmentViolation(const SegmentMeasure& m, const EdgeGridCriteria& c) {
  if (c.min_length > 0 && m.chord < 2 * c.min_length && m.chord > 0) return 0;
  double v = 0;
  if (c.max_sagitta > 0) v = std::max(v, m.sagitta / c.max_sagitta);
  if (c.rd_tolerance > 0) v = std::max(v, m.rd / c.rd_tolerance);
  if (c.max_length > 0) v = std::max(v, m.chord / c.max_length);
  v = std::max(v, m.across);
  if (m.chord == 0 && m.sagitta > 0) v = INFINITY;  // a closed segment
  return v;
}

namespace {

// Local size that would meet the criteria exactly, as a multiple of the segment's parameter
// length: sagitta and RD scale with length squared, chord length linearly.
double SizeFactor(const SegmentMeasure& m, const EdgeGridCriteria& c) {
  double f = INFINITY;
  if (c.max_sagitta > 0 && m.sagitta > 0) f = std::min(f, std::sqrt(c.max_sagitta / m.sagitta));
  if (c.rd_tolerance > 0 && m.rd > 0) f = std::min(f, std::sqrt(c.rd_tolerance / m.rd));
  if (c.max_length > 0 && m.chord > 0) f = std::min(f, c.max_length / m.chord);
  if (m.across > 0) f = std::min(f, std::sqrt(1.0 / m.across));
  return f;
}

struct Segment {
  double a, b;
  SegmentMeasure m;
  double violation;
};

// Greedy RD refinement: split the worst segment at its best split point until every segment's
// violation is at most `target`, or the context asks to stop.
std::vector<Segment> Refine(Curve& curve, double first, double last, const EdgeGridCriteria& c,
                            double target, int min_segments, const Context* context) {
  std::vector<Segment> segs;
  for (int i = 0; i < min_segments; ++i) {
    double a = first + (last - first) * i / min_segments;
    double b = i + 1 == min_segments ? last : first + (last - first) * (i + 1) / min_segments;
    SegmentMeasure m = MeasureSegment(curve, a, b, &c.sides);
    segs.push_back({a, b, m, SegmentViolation(m, c)});
  }
  auto worse = [&](int i, int j) { return segs[i].violation < segs[j].violation; };
  std::priority_queue<int, std::vector<int>, decltype(worse)> queue(worse);
  for (int i = 0; i < static_cast<int>(segs.size()); ++i) queue.push(i);
  const int kMaxSegments = 1 << 16;
  while (!queue.empty() && static_cast<int>(segs.size()) < kMaxSegments) {
    int i = queue.top();
    if (segs[i].violation <= target) break;
    if ((segs.size() & 255) == 0 && context && context->ShouldStop()) break;
    queue.pop();
    Segment s = segs[i];
    double t = s.m.split;
    double span = s.b - s.a;
    // keep the split well inside the segment
    t = std::clamp(t, s.a + 0.1 * span, s.b - 0.1 * span);
    SegmentMeasure left = MeasureSegment(curve, s.a, t, &c.sides),
                   right = MeasureSegment(curve, t, s.b, &c.sides);
    segs[i] = {s.a, t, left, SegmentViolation(left, c)};
    segs.push_back({t, s.b, right, SegmentViolation(right, c)});
    queue.push(i);
    queue.push(static_cast<int>(segs.size()) - 1);
  }
  std::sort(segs.begin(), segs.end(), [](const Segment& x, const Segment& y) { return x.a < y.a; });
  return segs;
}

// Places n segments so that each carries the same share of the error density estimated on the
// fine grid `fine` (density = 1 / local size that meets the criteria).
std::vector<double> Equidistribute(const std::vector<Segment>& fine, const EdgeGridCriteria& c,
                                   int n) {
  std::vector<double> cumulative(fine.size() + 1, 0.0);
  for (size_t i = 0; i < fine.size(); ++i) {
    double f = SizeFactor(fine[i].m, c);
    double density = std::isfinite(f) && f > 0 ? 1.0 / f : 0.0;
    cumulative[i + 1] = cumulative[i] + density;
  }
  double total = cumulative.back();
  std::vector<double> ts = {fine.front().a};
  if (total <= 0) {
    // No criterion bites (a straight segment): n equal parameter steps.
    for (int k = 1; k < n; ++k)
      ts.push_back(fine.front().a + (fine.back().b - fine.front().a) * k / n);
  } else {
    size_t i = 0;
    for (int k = 1; k < n; ++k) {
      double target = total * k / n;
      while (i + 1 < fine.size() && cumulative[i + 1] < target) ++i;
      double w = cumulative[i + 1] - cumulative[i];
      double s = w > 0 ? (target - cumulative[i]) / w : 0.5;
      ts.push_back(fine[i].a + std::clamp(s, 0.0, 1.0) * (fine[i].b - fine[i].a));
    }
  }
  ts.push_back(fine.back().b);
  return ts;
}

}  // namespace

std::vector<double> DiscretizeCurve(Curve& curve, double first, double last,
                                    const EdgeGridCriteria& criteria, const Context* context) {
  int min_segments = std::max(1, criteria.min_segments);
  // A fine grid (every segment at a quarter of the criteria) samples the error density.
  std::vector<Segment> fine = Refine(curve, first, last, criteria, 0.25, min_segments, context);
  if (context && context->ShouldStop()) return {first, last};
  double load = 0;
  for (const Segment& s : fine) {
    double f = SizeFactor(s.m, criteria);
    if (std::isfinite(f) && f > 0) load += 1.0 / f;
  }
  int n = std::max(min_segments, static_cast<int>(std::ceil(load * 0.999)));
  n = std::min<int>(n, static_cast<int>(fine.size()));
  // Fewest segments that pass an exact check; each failure adds one segment.
  for (int tries = 0; tries < 8 && n <= static_cast<int>(fine.size()); ++tries, ++n) {
    std::vector<double> ts = Equidistribute(fine, criteria, n);
    bool ok = true;
    for (size_t k = 0; k + 1 < ts.size() && ok; ++k) {
      if ((k & 255) == 255 && context && context->ShouldStop()) return {first, last};
      if (!(ts[k + 1] > ts[k]))
        ok = false;
      else
        ok = SegmentViolation(MeasureSegment(curve, ts[k], ts[k + 1], &criteria.sides), criteria) <=
             1.0;
    }
    if (ok) return ts;
  }
  std::vector<double> ts;
  for (const Segment& s : fine) ts.push_back(s.a);
  ts.push_back(fine.back().b);
  return ts;
}

}  // namespace rdmesh
