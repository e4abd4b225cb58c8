#include "run/budget.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "model/model.h"
#include "run/pipeline.h"

namespace rdmesh {

Result<MeshResult> MeshWithinBudget(const Model& model, const MeshOptions& options,
                                    Context* context) {
  const int64_t budget = options.max_triangles;
  const double diag = model.info.diagonal;
  const double floor = options.max_deviation;   // 0 = none
  double lo = floor > 0 ? floor : 1e-7 * diag;  // finest allowed
  double hi = 0.25 * diag;                      // coarsest tried
  double d = floor > 0 ? floor : 1e-3 * diag;
  // best: the finest feasible mesh so far; its deviation is an upper bracket.
  std::optional<MeshResult> best;
  double best_d = 0, fail_d = 0;  // fail_d: the coarsest deviation known to exceed the budget
  int64_t fail_n = 0;
  // Secant search in log-log (triangles ~ deviation^-slope), bracketed; stops within 10% of
  // the budget or after kMaxRuns runs.
  constexpr int kMaxRuns = 8;
  double prev_d = 0, prev_n = 0;
  for (int iter = 0; iter < kMaxRuns; ++iter) {
    Result<MeshResult> r = MeshAtDeviation(model, options, d, context);
    if (!r.ok()) return r.status();
    const double n = static_cast<double>(r->summary.triangles);

    if (n <= budget) {
      if (!best || d < best_d) best = std::move(r.value()), best_d = d;
      if (d <= lo * (1 + 1e-9) || n >= 0.9 * budget) break;
    } else if (fail_d == 0 || d > fail_d) {
      fail_d = d, fail_n = static_cast<int64_t>(n);
    }
    double slope = 1.0;
    if (prev_d > 0 && prev_n > 0 && n > 0 && std::fabs(std::log(d / prev_d)) > 1e-6)
      slope = std::clamp(-std::log(n / prev_n) / std::log(d / prev_d), 0.5, 2.0);
    prev_d = d, prev_n = n;
    double target = 0.95 * budget;
    double guess = n > 0 ? d * std::pow(n / target, 1.0 / slope) : d * 0.5;
    guess = std::clamp(guess, d / 8, d * 8);  // one run never jumps more than 8x
    if (best && fail_d > 0) {
      if (guess <= fail_d || guess >= best_d) guess = std::sqrt(fail_d * best_d);
      if (best_d / fail_d < 1.02) break;
    }
    d = std::clamp(guess, lo, hi);
    if (!best && fail_d >= hi) break;
  }
  if (!best)
    return Status(StatusCode::kResourceExhausted, "no mesh fits in " + std::to_string(budget) +
                                                      " triangles: the coarsest tried has " +
                                                      std::to_string(fail_n));
  return std::move(*best);
}

}  // namespace rdmesh
