#pragma once
// Derivative-free optimisers: every placement in the method (edge split, triangle split, node
// smoothing) is a local search over surface or curve evaluations only.

#include <cmath>
#include <functional>

#include "core/geom.h"

namespace rdmesh {

/// Maximises f on [a, b]: `samples` evenly spaced interior probes pick a bracket, golden-section
/// search narrows it for `iterations` steps. Returns the best t; its value in *best_value.
double MaximizeOnInterval(const std::function<double(double)>& f, double a, double b, int samples,
                          int iterations, double* best_value);

/// Cross ("compass") pattern search for a maximum of f in the plane: probe x +- step along both
/// axes, move to the best feasible improvement, halve the step when none improves. Stops when
/// the step falls below `min_step` (per axis, as a fraction of the start step) or after
/// `max_evals` evaluations. `feasible` guards every probe (folds, orientation). A probe that
/// lands exactly on a point the search already evaluated reuses its value (it still counts as an
/// evaluation, so the result does not depend on this).
struct PatternSearchResult {
  Vec2 x;
  double value = 0;
  int evals = 0;
};
PatternSearchResult CrossPatternSearch(const std::function<double(Vec2)>& f,
                                       const std::function<bool(Vec2)>& feasible, Vec2 x0,
                                       double f0, Vec2 step, double min_step_fraction,
                                       int max_evals);

/// The same search with a bounded objective: f(x, bound) must return f's exact value when it
/// exceeds `bound`, and may return any value <= bound otherwise (so an expensive objective can
/// stop as soon as it knows the probe cannot win). Takes the same steps as the unbounded search.
/// It stops as soon as the best value reaches `enough`.
using BoundedObjective = std::function<double(Vec2 x, double bound)>;
PatternSearchResult CrossPatternSearch(const BoundedObjective& f,
                                       const std::function<bool(Vec2)>& feasible, Vec2 x0,
                                       double f0, Vec2 step, double min_step_fraction,
                                       int max_evals, double enough = HUGE_VAL);

}  // namespace rdmesh
