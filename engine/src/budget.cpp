#include "budget.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "model.h"

namespace rdmesh {

Result<MeshResult> MeshWithinBudget(const Model& model, const MeshOptions& options,
                                    Context* context) {
  const int64_t budget = options.max_triangles;
  const double diag = model.info.diagonal;
  const double floor = options.max_deviation;  // 0 = none
  double lo = floor > 0 ? floor : 1e-7 * diag;  // finest allowed
  double hi = 0.25 * diag;                      // coarsest tried
  double d = floor > 0 ? floor : 1e-3 * diag;
  // best: the finest feasible mesh so far; its deviation is an upper bracket.
  std::optional<MeshResult> best;
  double best_d = 0, fail_d = 0;  // fail_d: the coarsest deviation known to exceed the budget
  int64_t fail_n = 0;
  for (int iter = 0; iter < 12; ++iter) {
    Result<MeshResult> r = MeshAtDeviation(model, options, d, context);
    if (!r.ok()) return r.status();
    int64_t n = r->summary.triangles;
    if (n <= budget) {
      if (!best || d < best_d) best = std::move(r.value()), best_d = d;
      if (d <= lo * (1 + 1e-9) || n > 0.97 * budget) break;
    } else {
      if (fail_d == 0 || d > fail_d) fail_d = d, fail_n = n;
    }
    // Next guess: triangles ~ 1/d, then bisect (geometrically) inside the bracket.
    double guess = d * static_cast<double>(n) / (0.98 * budget);
    if (best && fail_d > 0) {
      if (guess <= fail_d || guess >= best_d) guess = std::sqrt(fail_d * best_d);
      if (best_d / fail_d < 1.02) break;
    }
    d = std::clamp(guess, lo, hi);
    if (!best && fail_d > 0 && fail_d >= hi) break;
  }
  if (!best)
    return Status(StatusCode::kResourceExhausted,
                  "no mesh fits in " + std::to_string(budget) + " triangles: the coarsest tried has " +
                      std::to_string(fail_n));
  return std::move(*best);
}

}  // namespace rdmesh
