#include "geometry/pattern_search.h"

#include <cmath>
#include <cstring>
#include <vector>

namespace rdmesh {

double MaximizeOnInterval(const std::function<double(double)>& f, double a, double b, int samples,
                          int iterations, double* best_value) {
  double best_t = 0.5 * (a + b), best = -INFINITY;
  int best_i = 0;
  double h = (b - a) / (samples + 1);
  for (int i = 1; i <= samples; ++i) {
    double t = a + i * h;
    double v = f(t);
    if (v > best) best = v, best_t = t, best_i = i;
  }
  // Golden-section search on the bracket around the best probe.
  double lo = a + (best_i - 1) * h, hi = a + (best_i + 1) * h;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int k = 0; k < iterations; ++k) {
    if (f1 >= f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(x2);
    }
  }
  if (f1 > best) best = f1, best_t = x1;
  if (f2 > best) best = f2, best_t = x2;
  if (best_value) *best_value = best;
  return best_t;
}

PatternSearchResult CrossPatternSearch(const std::function<double(Vec2)>& f,
                                       const std::function<bool(Vec2)>& feasible, Vec2 x0,
                                       double f0, Vec2 step, double min_step_fraction,
                                       int max_evals) {
  return CrossPatternSearch([&f](Vec2 x, double) { return f(x); }, feasible, x0, f0, step,
                            min_step_fraction, max_evals);
}

PatternSearchResult CrossPatternSearch(const BoundedObjective& f,
                                       const std::function<bool(Vec2)>& feasible, Vec2 x0,
                                       double f0, Vec2 step, double min_step_fraction,
                                       int max_evals, double enough) {
  // Every probe's value (or upper bound), to answer repeated probes: after a move the probe back
  // and the extrapolated point are often ones the search has seen. A stored bound stays valid
  // because the bounds passed to f never decrease (they are the best value so far).
  struct Probe {
    Vec2 x;
    double value;
  };
  std::vector<Probe> seen;
  seen.reserve(max_evals + 4);
  auto eval = [&](Vec2 x, double bound) {
    for (const Probe& p : seen)
      if (std::memcmp(&p.x, &x, sizeof(Vec2)) == 0) return p.value;
    double v = f(x, bound);
    seen.push_back({x, v});
    return v;
  };
  PatternSearchResult r{x0, f0, 0};
  Vec2 h = step;
  const Vec2 min_h = min_step_fraction * step;
  while (r.evals < max_evals && (h.x > min_h.x || h.y > min_h.y) && r.value < enough) {
    const Vec2 probes[4] = {{h.x, 0}, {-h.x, 0}, {0, h.y}, {0, -h.y}};
    Vec2 best_x = r.x;
    double best = r.value;
    for (const Vec2& d : probes) {
      Vec2 x = r.x + d;
      if (!feasible(x)) continue;
      double v = eval(x, best);
      ++r.evals;
      if (v > best) best = v, best_x = x;
    }
    if (best > r.value) {
      // Keep going in the same direction while it pays (one extrapolation step).
      Vec2 dir = best_x - r.x;
      r.x = best_x;
      r.value = best;
      Vec2 x = r.x + dir;
      if (r.evals < max_evals && feasible(x)) {
        double v = eval(x, r.value);
        ++r.evals;
        if (v > r.value) r.x = x, r.value = v;
      }
    } else {
      h = 0.5 * h;
    }
  }
  return r;
}

}  // namespace rdmesh
