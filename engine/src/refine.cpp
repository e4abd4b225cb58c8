#include "refine.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <queue>
#include <tuple>

#include "pattern_search.h"

namespace rdmesh {

namespace {

// A split point keeps at least this barycentric weight on every corner; an optimum closer to an
// edge than kEdgeWeight splits that edge instead (the paper's Algorithm 3).
constexpr double kMinWeight = 0.04;
constexpr double kEdgeWeight = 0.12;
// A triangle that descends from this many splits and still violates is not split again: a
// safety net against refinement that makes no progress (sizes shrink ~3x a generation).
constexpr int kMaxGeneration = 24;
// Splits of standing triangles may fold children only in the first generations.
constexpr int kFoldingGenerations = 1;
// The violation given to a folded triangle.
constexpr double kFoldViolation = 4.0;
// Below this shape quality (1 = equilateral) a triangle to refine is a sliver.
constexpr double kSliverQuality = 0.02;
// A collapse whose triangles exceed the criteria by up to this factor is tried with the
// survivor moved to its best place.
constexpr double kCollapseSlack = 2.0;

class Refiner {
 public:
  Refiner(WorkMesh& m, Surface& s, const FaceCriteria& c, double su, double sv, Context* ctx,
          RefineStats* stats)
      : m_(m), s_(s), c_(c), su_(su), sv_(sv), ctx_(ctx), stats_(*stats) {}

  Status RefineToCriteria(int64_t max_triangles);
  Status Improve();
  void Finish();

 private:
  struct Candidate {
    std::vector<TriangleMeasure> measures;
    double max_violation = 0;
    double min_agreement = 1;
  };

  // Corners of a triangle for the fold guard (pole corners take their neighbours' mean normal).
  void Corners(const Tri& t, Vec2 uv[3], Vec3 p[3], Vec3 n[3]) const {
    m_.FoldCorners(t, uv, p, n);
  }
  Candidate Evaluate(const std::vector<Tri>& tris) {
    Candidate cand;
    EvaluateBelow(tris, false, 0, 0, &cand);
    return cand;
  }
  // The measures of `tris`, their largest violation and smallest agreement into *cand. With
  // `stop`, for a candidate wanted only when the fold guard holds (AgreementOk against old_agree)
  // and its max_violation stays below `limit`: false, with *cand partial, once either fails.
  bool EvaluateBelow(const std::vector<Tri>& tris, bool stop, double old_agree, double limit,
                     Candidate* cand) {
    Vec2 uv[3];
    Vec3 p[3], n[3];
    std::vector<double>& agreement = agreement_;  // scratch
    agreement.resize(tris.size());
    for (size_t k = 0; k < tris.size(); ++k) {
      Corners(tris[k], uv, p, n);
      agreement[k] = TriangleAgreement(uv, p, n);
      cand->min_agreement = std::min(cand->min_agreement, agreement[k]);
    }
    if (stop && !AgreementOk(cand->min_agreement, old_agree)) return false;
    cand->measures.resize(tris.size());
    for (size_t k = 0; k < tris.size(); ++k) {
      m_.MeasureCorners(tris[k], uv, p);
      TriangleMeasure& m = cand->measures[k];
      if (!stop)
        m = MeasureTriangle(s_, uv, p, c_);
      else if (!MeasureTriangleBelow(s_, uv, p, c_, limit, &m))
        return false;
      PenaliseFold(tris[k], agreement[k], &m);
      cand->max_violation = std::max(cand->max_violation, m.violation);
      if (stop && !(cand->max_violation < limit)) return false;
    }
    return true;
  }
  // Evaluate(tris).max_violation for a smoothing probe of v; once it cannot win (the maximum
  // reaches `limit`, or AgreementOk fails) a value >= limit, with the triangle that showed it in
  // *stopper. v's normal is evaluated when first needed. Measures tris[first] (if >= 0), then
  // `order` (worst first at the last full measurement, which re-sorts it): the order only changes
  // how soon a loser stops. A full one leaves in `measures` what Evaluate(tris).measures holds.
  double RingViolation(const std::vector<Tri>& tris, int v, double old_agree, double limit,
                       int first, int* stopper, std::vector<int>* order,
                       std::vector<TriangleMeasure>* measures) {
    Vec2 uv[3];
    Vec3 p[3], n[3];
    double min_agreement = 1, worst = 0;
    bool normal_ready = false;
    measures->resize(tris.size());
    const int count = static_cast<int>(order->size());
    for (int j = first >= 0 ? -1 : 0; j < count; ++j) {
      const int k = j < 0 ? first : (*order)[j];
      if (j >= 0 && k == first) continue;
      *stopper = k;
      m_.MeasureCorners(tris[k], uv, p);
      TriangleMeasure& m = (*measures)[k];
      if (!MeasureTriangleBelow(s_, uv, p, c_, limit, &m)) return m.violation;
      worst = std::max(worst, m.violation);
      if (worst >= limit) return worst;
      if (!normal_ready) m_.normal[v] = s_.Normal(m_.uv[v].x, m_.uv[v].y), normal_ready = true;
      Corners(tris[k], uv, p, n);
      double agreement = TriangleAgreement(uv, p, n);
      PenaliseFold(tris[k], agreement, &m);
      min_agreement = std::min(min_agreement, agreement);
      if (!AgreementOk(min_agreement, old_agree)) return HUGE_VAL;
      worst = std::max(worst, m.violation);  // a standing triangle's edges may raise it
      if (worst >= limit) return worst;
    }
    std::stable_sort(order->begin(), order->end(), [&](int a, int b) {
      return (*measures)[a].violation > (*measures)[b].violation;
    });
    return worst;
  }
  // A folded triangle (its normal against the surface's) must be refined whatever it deviates;
  // one that stands against the surface is measured along its edges too (MeasureStanding).
  void PenaliseFold(const Tri& t, double agreement, TriangleMeasure* m) const {
    m->agreement = agreement;
    // At a pole the corner normal is a stand-in (FoldCorners): standing is not known there.
    bool pole = m_.pole_axis[t[0]] + m_.pole_axis[t[1]] + m_.pole_axis[t[2]] > -3;
    if (agreement > kInvalid && agreement < c_.min_normal_cos && !pole) {
      Vec2 uv[3], fold_uv[3];
      Vec3 p[3], fold_p[3], n[3];
      m_.MeasureCorners(t, uv, p);
      m_.FoldCorners(t, fold_uv, fold_p, n);
      MeasureStanding(s_, uv, p, n, c_, m);
    }
    if (agreement <= 0) m->violation = std::max(m->violation, kFoldViolation);
  }
  // Splits may not fold a child, except that a folded parent may leave children no worse.
  bool SplitOk(double child_min, const std::vector<int>& parents) const {
    double parent_min = 1;
    int parent_gen = 0;
    for (int t : parents) {
      parent_min = std::min(parent_min, measure_[t].agreement);
      parent_gen = std::max(parent_gen, static_cast<int>(gen_[t]));
    }
    // A young parent that stands up against the surface spans too much of it: its children may
    // fold, and refinement (a fold counts as a violation) goes on until they do not. Later
    // generations may not fold.
    if (parent_min < 0.2 && parent_gen < kFoldingGenerations) return child_min > kInvalid;
    if (parent_min <= 0) return child_min > kInvalid && child_min >= parent_min;
    return child_min > 0;
  }
  double Agreement(int t) const {
    Vec2 uv[3];
    Vec3 p[3], n[3];
    Corners(m_.tri[t], uv, p, n);
    return TriangleAgreement(uv, p, n);
  }
  double MaxViolation(const std::vector<int>& tris) const {
    double v = 0;
    for (int t : tris) v = std::max(v, measure_[t].violation);
    return v;
  }
  // Agreement(t) is kept in measure_[t].agreement: every measurement that lands in measure_
  // comes with the fold guard of the same corners (PenaliseFold).
  double MinAgreement(const std::vector<int>& tris) const {
    double a = 1;
    for (int t : tris) {
      assert(measure_[t].agreement == Agreement(t));
      a = std::min(a, measure_[t].agreement);
    }
    return a;
  }
  // An optimisation step may not fold a triangle, nor push agreement below the guard where the
  // old triangles met it.
  bool AgreementOk(double new_min, double old_min) const {
    return new_min > 0 && new_min >= std::min(c_.min_normal_cos, old_min) - 1e-12;
  }

  int NewNode(Vec2 q, bool on_pole = false, int pole_of = -1) {
    if (on_pole) {
      return m_.AddNode(q, m_.xyz[pole_of], s_.Normal(q.x, q.y), true, m_.ref[pole_of],
                        m_.pole_axis[pole_of]);
    }
    Vec3 x = s_.Point(q.x, q.y);
    return m_.AddNode(q, x, s_.Normal(q.x, q.y), false, NodeRef{});
  }
  void DropLastNode() {
    m_.uv.pop_back(), m_.xyz.pop_back(), m_.normal.pop_back(), m_.fixed.pop_back();
    m_.ref.pop_back(), m_.node_tri.pop_back(), m_.pole_axis.pop_back();
  }
  std::vector<int> Apply(const std::vector<int>& cavity, const std::vector<Tri>& tris,
                         const Candidate& cand) {
    // Generation: how many splits a triangle descends from (flips and collapses keep it).
    int gen = 0;
    for (int t : cavity) gen = std::max(gen, static_cast<int>(gen_[t]));
    if (splitting_ && tris.size() > cavity.size()) gen = std::min(gen + 1, 255);
    std::vector<int> ids = ReplaceCavity(&m_, cavity, tris);
    if (measure_.size() < m_.tri.size()) {
      measure_.resize(m_.tri.size());
      stamp_.resize(m_.tri.size(), 0);
      gen_.resize(m_.tri.size(), 0);
    }
    for (int id : ids) gen_[id] = static_cast<uint8_t>(gen);
    for (size_t k = 0; k < ids.size(); ++k) {
      measure_[ids[k]] = cand.measures[k];
      ++stamp_[ids[k]];
      if (refining_ && cand.measures[k].violation > 1) Push(ids[k]);
    }
    for (int t : cavity)
      if (!m_.alive[t]) ++stamp_[t];
    return ids;
  }
  void Push(int t) { queue_.push({measure_[t].violation, t, stamp_[t]}); }

  bool RealignPole(int p);
  struct CollapseChoice {
    int w = -1;
    Candidate cand;
    std::vector<Tri> tris;
    std::vector<int> cavity;
  };
  bool BestCollapse(int v, CollapseChoice* best, double slack = 1.0);
  bool CollapseAndSmooth(int v, CollapseChoice& choice);
  bool SmoothNode(int v);
  bool SplitTriangle(int t);
  bool SplitEdge(int t, int i);
  bool RescueSplit(int node, std::vector<int>* cavity, std::vector<Tri>* tris, Candidate* cand);
  bool TryFlip(int t, int i);
  void Legalize(int node);
  int CollapsePass();
  int FlipPass();
  int SmoothPass();

  WorkMesh& m_;
  Surface& s_;
  const FaceCriteria& c_;
  double su_, sv_;
  Context* ctx_;
  RefineStats& stats_;
  std::vector<TriangleMeasure> measure_;
  std::vector<uint32_t> stamp_;
  bool refining_ = false;
  bool splitting_ = false;    // Apply() is applying a split
  std::vector<uint8_t> gen_;  // per triangle: split generation
  bool sliver_recursion_ = false;
  bool rescue_ = false;  // splits may flip folded children's outer edges (RescueSplit)
  std::priority_queue<std::tuple<double, int, uint32_t>> queue_;
  std::vector<int> fan_ring_, fan_nodes_, link_ring_, link_nodes_;  // BestCollapse's scratch
  std::vector<double> agreement_;                                   // EvaluateBelow's
};

Status Refiner::RefineToCriteria(int64_t max_triangles) {
  measure_.resize(m_.tri.size());
  stamp_.assign(m_.tri.size(), 0);
  gen_.assign(m_.tri.size(), 0);
  refining_ = true;
  for (int t = 0; t < static_cast<int>(m_.tri.size()); ++t) {
    if (!m_.alive[t]) continue;
    Vec2 uv[3];
    Vec3 p[3];
    m_.MeasureCorners(t, uv, p);
    measure_[t] = MeasureTriangle(s_, uv, p, c_);
    PenaliseFold(m_.tri[t], Agreement(t), &measure_[t]);
    if (measure_[t].violation > 1) Push(t);
  }
  int64_t ops = 0;
  // Plain splits first; then the triangles they left violating get splits with flips too
  // (RescueSplit), which only they need.
  for (int phase = 0; phase < 2 && !stats_.budget_hit; ++phase) {
    rescue_ = phase == 1;
    if (rescue_)
      for (int t = 0; t < static_cast<int>(m_.tri.size()); ++t)
        if (m_.alive[t] && measure_[t].violation > 1) Push(t);
    while (!queue_.empty()) {
      auto [violation, t, stamp] = queue_.top();
      queue_.pop();
      if (!m_.alive[t] || stamp != stamp_[t]) continue;
      if (violation <= 1) break;
      if (m_.TriangleCount() >= max_triangles) {
        stats_.budget_hit = true;
        break;
      }
      if ((++ops & 255) == 0 && ctx_ && ctx_->ShouldStop()) return ctx_->StopStatus();
      // No progress here: leave it; Finish() reports it through max_violation.
      if (gen_[t] >= kMaxGeneration) continue;
      splitting_ = true;
      SplitTriangle(t);
      splitting_ = false;
    }
    queue_ = {};
  }
  rescue_ = false;
  refining_ = false;
  return Status::Ok();
}

bool Refiner::RealignPole(int p) {
  std::vector<int> cavity, added;
  std::vector<Tri> tris;
  double shift = 0;
  if (!PoleFanTris(&m_, p, &cavity, &tris, &added, &shift)) return false;
  auto undo = [&] {
    for (size_t k = 0; k < added.size(); ++k) DropLastNode();
    return false;
  };
  // Already one aligned fan: nothing to do.
  double span = std::max(m_.uv[p].x - s_.umin, s_.umax - s_.umin) + (s_.vmax - s_.vmin);
  if (tris.size() == cavity.size() && shift <= 1e-9 * span) return undo();
  for (const Tri& nt : tris)
    if (!(Orient(m_.uv[nt[0]], m_.uv[nt[1]], m_.uv[nt[2]]) > 0)) return undo();
  Candidate cand = Evaluate(tris);
  if (!(cand.min_agreement > 0)) return undo();
  Apply(cavity, tris, cand);
  bool used = false;
  for (const Tri& nt : tris) used = used || nt[0] == p || nt[1] == p || nt[2] == p;
  if (!used) m_.node_tri[p] = -1;
  return true;
}

bool Refiner::SplitTriangle(int t) {
  const Tri tri = m_.tri[t];
  // A fan triangle at a pole first gets a pole node of its own under it.
  int poles = 0, pole = -1;
  for (int i = 0; i < 3; ++i)
    if (m_.pole_axis[tri[i]] >= 0) ++poles, pole = tri[i];
  if (poles == 1 && RealignPole(pole)) return true;
  Vec2 uv[3];
  Vec3 p[3], n[3];
  Corners(tri, uv, p, n);
  const TriangleMeasure& mt = measure_[t];
  // A triangle too long for max_length: split its longest edge in the middle when allowed.
  double dev_ratio = c_.max_deviation > 0 ? mt.deviation / c_.max_deviation : 0;
  double rd_ratio = c_.rd_tolerance > 0 ? mt.rd / c_.rd_tolerance : 0;
  if (c_.max_length > 0 && mt.max_length / c_.max_length >= std::max(dev_ratio, rd_ratio)) {
    int longest = 0;
    double best = -1;
    for (int i = 0; i < 3; ++i) {
      double l = Dist(p[(i + 1) % 3], p[(i + 2) % 3]);
      if (l > best) best = l, longest = i;
    }
    if (m_.kind[t][longest] != EdgeKind::kFixed && SplitEdge(t, longest)) return true;
  }
  // A sliver (two corners almost together) gains nothing from an interior point: its long edges
  // carry the deviation, so bisect the longest one (Rivara) when it may be split.
  {
    double l2[3], sum = 0;
    for (int i = 0; i < 3; ++i)
      l2[i] = Dot(p[(i + 1) % 3] - p[(i + 2) % 3], p[(i + 1) % 3] - p[(i + 2) % 3]), sum += l2[i];
    double quality = sum > 0 ? 4 * std::sqrt(3.0) * Area(p[0], p[1], p[2]) / sum : 1;
    int longest = static_cast<int>(std::max_element(l2, l2 + 3) - l2);
    if (quality < kSliverQuality &&
        m_.pole_axis[tri[0]] + m_.pole_axis[tri[1]] + m_.pole_axis[tri[2]] == -3 &&
        m_.kind[t][longest] != EdgeKind::kFixed) {
      if (SplitEdge(t, longest)) return true;
      // The neighbour across the long edge blocks it (the split would fold it): refine the
      // neighbour first, then this sliver again.
      int u = m_.nbr[t][longest];
      if (u >= 0 && !sliver_recursion_) {
        sliver_recursion_ = true;
        bool done = SplitTriangle(u);
        sliver_recursion_ = false;
        if (done) {
          if (m_.alive[t]) Push(t);
          return true;
        }
      }
    }
  }
  // The area-optimal interior point (the paper's Algorithm 1), searched in barycentric
  // coordinates from where the deviation peaks.
  auto to_uv = [&](Vec2 b) { return (1 - b.x - b.y) * uv[0] + (b.x * uv[1] + b.y * uv[2]); };
  double det = Orient(uv[0], uv[1], uv[2]);
  Vec2 b0{1.0 / 3, 1.0 / 3};
  if (det > 0) {
    Vec2 w = mt.worst_uv;
    b0 = {Orient(uv[0], w, uv[2]) / det, Orient(uv[0], uv[1], w) / det};
  }
  auto clamp_weights = [](Vec2 b, double lo) {
    double w0 = std::max(1 - b.x - b.y, lo), w1 = std::max(b.x, lo), w2 = std::max(b.y, lo);
    double sum = w0 + w1 + w2;
    return Vec2{w1 / sum, w2 / sum};
  };
  b0 = clamp_weights(b0, 0.1);
  auto feasible = [](Vec2 b) {
    return b.x >= kMinWeight && b.y >= kMinWeight && 1 - b.x - b.y >= kMinWeight;
  };
  auto objective = [&](Vec2 b) { return SplitAreaRatio(s_, uv, p, to_uv(b)); };
  PatternSearchResult r =
      CrossPatternSearch(objective, feasible, b0, objective(b0), {0.08, 0.08}, 0.1, 30);
  Vec2 b = r.x;
  double w[3] = {1 - b.x - b.y, b.x, b.y};
  int k = static_cast<int>(std::min_element(w, w + 3) - w);
  if (w[k] < kEdgeWeight) {
    // Split the nearby edge, unless it is a short one (that would only make slivers).
    double edge = Dist(p[(k + 1) % 3], p[(k + 2) % 3]);
    if (m_.kind[t][k] != EdgeKind::kFixed && edge >= 0.3 * mt.max_length && SplitEdge(t, k))
      return true;
    b = clamp_weights(b, kEdgeWeight);
  }
  const double longest = mt.max_length;
  for (Vec2 bb : {b, Vec2{1.0 / 3, 1.0 / 3}, Vec2{0.25, 0.25}, Vec2{0.5, 0.25}, Vec2{0.25, 0.5}}) {
    int node = NewNode(to_uv(bb));
    // A node on top of a corner makes slivers, not progress.
    bool apart = true;
    for (int i = 0; i < 3; ++i) apart = apart && Dist(m_.xyz[node], p[i]) > 0.02 * longest;
    if (!apart) {
      DropLastNode();
      continue;
    }
    std::vector<int> cavity = {t};
    std::vector<Tri> tris = SplitTriangleTris(m_, t, node);
    Candidate cand = Evaluate(tris);
    if (SplitOk(cand.min_agreement, cavity) ||
        (rescue_ && RescueSplit(node, &cavity, &tris, &cand))) {
      Apply(cavity, tris, cand);
      ++stats_.splits;
      Legalize(node);
      return true;
    }
    DropLastNode();
  }
  // Neither point keeps the children unfolded: try its edges before giving up on it.
  for (int i = 0; i < 3; ++i)
    if (m_.kind[t][i] != EdgeKind::kFixed &&
        Dist(p[(i + 1) % 3], p[(i + 2) % 3]) >= 0.3 * mt.max_length && SplitEdge(t, i))
      return true;
  return false;
}

bool Refiner::SplitEdge(int t, int i) {
  const int b = m_.tri[t][(i + 1) % 3], c = m_.tri[t][(i + 2) % 3];
  const bool pole = m_.kind[t][i] == EdgeKind::kSplittable;
  std::vector<int> cavity;
  std::vector<Tri> tris;
  auto place = [&](double s) { return (1 - s) * m_.uv[b] + s * m_.uv[c]; };
  double s_best = 0.5;
  if (!pole) {
    // The paper's Algorithm 2: the point on the edge that maximises the area of the new
    // triangles.
    SplitEdgeTris(m_, t, i, -1, &cavity, &tris);
    std::vector<Tri> shape = tris;
    s_best = MaximizeOnInterval(
        [&](double s) {
          Vec2 q = place(s);
          Vec3 x = s_.Point(q.x, q.y);
          double area = 0;
          for (const Tri& nt : shape) {
            Vec3 pts[3];
            for (int j = 0; j < 3; ++j) pts[j] = nt[j] < 0 ? x : m_.xyz[nt[j]];
            area += Area(pts[0], pts[1], pts[2]);
          }
          return area;
        },
        0.3, 0.7, 3, 6, nullptr);
  }
  if (pole) {
    // On a pole edge, put the new node under the apex, so the fan edge to it follows a
    // parameter line (a meridian on a sphere).
    double du = m_.uv[c].x - m_.uv[b].x, dv = m_.uv[c].y - m_.uv[b].y;
    Vec2 apex = m_.uv[m_.tri[t][i]];
    double along =
        (std::fabs(du) >= std::fabs(dv)) ? (apex.x - m_.uv[b].x) / du : (apex.y - m_.uv[b].y) / dv;
    s_best = std::clamp(std::isfinite(along) ? along : 0.5, 0.2, 0.8);
  }
  int node = pole ? NewNode(place(s_best), true, b) : NewNode(place(s_best));
  SplitEdgeTris(m_, t, i, node, &cavity, &tris);
  Candidate cand = Evaluate(tris);
  if (!SplitOk(cand.min_agreement, cavity) &&
      !(rescue_ && RescueSplit(node, &cavity, &tris, &cand))) {
    DropLastNode();
    return false;
  }
  Apply(cavity, tris, cand);
  ++stats_.edge_splits;
  Legalize(node);
  return true;
}

// A split of a triangle whose long edges cut across a curved surface can fold a child that
// leans on such an edge, whatever point it takes. Flipping each folded child's outer edge
// together with the split, as one operation, gives the children the node beyond instead.
bool Refiner::RescueSplit(int node, std::vector<int>* cavity, std::vector<Tri>* tris,
                          Candidate* cand) {
  std::vector<int> cav = *cavity;
  std::vector<Tri> nt = *tris;
  const size_t children = nt.size();
  for (size_t k = 0; k < children; ++k) {
    if (cand->measures[k].agreement > 0) continue;
    int w;
    Tri out[2];
    if (!FlipOuterEdgeTris(m_, cav, nt[k], node, &w, out)) return false;
    for (const Tri& x : out)
      if (!(Orient(m_.uv[x[0]], m_.uv[x[1]], m_.uv[x[2]]) > 0)) return false;
    nt[k] = out[0];
    nt.push_back(out[1]);
    cav.push_back(w);
  }
  if (nt.size() == children) return false;
  Candidate c = Evaluate(nt);
  // A last resort must make progress: the worst triangle gets better.
  if (!SplitOk(c.min_agreement, cav) || !(c.max_violation < MaxViolation(cav))) return false;
  *cavity = std::move(cav), *tris = std::move(nt), *cand = std::move(c);
  ++stats_.rescues;
  return true;
}

bool Refiner::TryFlip(int t, int i) {
  if (m_.kind[t][i] != EdgeKind::kFree) return false;
  std::vector<int> cavity;
  std::vector<Tri> tris;
  if (!FlipTris(m_, t, i, &cavity, &tris)) return false;
  // Both new triangles must keep positive orientation: a cheap test first.
  for (const Tri& nt : tris)
    if (!(Orient(m_.uv[nt[0]], m_.uv[nt[1]], m_.uv[nt[2]]) > 0)) return false;
  double old_score = MaxViolation(cavity);
  Candidate cand = Evaluate(tris);
  if (!AgreementOk(cand.min_agreement, MinAgreement(cavity))) return false;
  bool better = cand.max_violation < old_score * (1 - 1e-9);
  if (!better && cand.max_violation <= old_score * (1 + 1e-12) && old_score == 0) {
    // Ties (no criterion bites, e.g. planar): the larger 3D area, else keep.
    double old_area = 0, new_area = 0;
    for (int x : cavity)
      old_area += Area(m_.xyz[m_.tri[x][0]], m_.xyz[m_.tri[x][1]], m_.xyz[m_.tri[x][2]]);
    for (const Tri& nt : tris) new_area += Area(m_.xyz[nt[0]], m_.xyz[nt[1]], m_.xyz[nt[2]]);
    better = new_area > old_area * (1 + 1e-9);
  }
  if (!better) return false;
  Apply(cavity, tris, cand);
  ++stats_.flips;
  return true;
}

void Refiner::Legalize(int node) {
  // Lawson-style: test the edges opposite the new node; a flip brings two new such edges.
  std::vector<int> stack = m_.Ring(node);
  int budget = 64;
  while (!stack.empty() && budget-- > 0) {
    int t = stack.back();
    stack.pop_back();
    if (!m_.alive[t]) continue;
    int k = m_.CornerOf(t, node);
    if (k < 0) continue;
    int u = m_.nbr[t][k];
    if (TryFlip(t, k)) {
      for (int x : {t, u})
        if (x >= 0 && m_.alive[x] && m_.CornerOf(x, node) >= 0) stack.push_back(x);
    }
  }
}

bool Refiner::BestCollapse(int v, CollapseChoice* best, double slack) {
  best->w = -1;
  if (m_.fixed[v] || m_.node_tri[v] < 0) return false;
  std::vector<int>&cavity = fan_ring_, &nv = fan_nodes_, &nw = link_nodes_;
  m_.Fan(v, &cavity, &nv);
  if (nv.size() != cavity.size()) return false;  // not a closed fan
  const double old_agree = MinAgreement(cavity);
  for (int w : nv) {
    std::vector<Tri> tris;
    CollapseTris(m_, v, w, cavity, &tris);
    bool oriented = true;  // the cheap (u,v) test first
    for (const Tri& nt : tris)
      oriented = oriented && Orient(m_.uv[nt[0]], m_.uv[nt[1]], m_.uv[nt[2]]) > 0;
    if (!oriented) continue;
    // Link condition: v and w share exactly the two apexes of the triangles on edge v-w.
    m_.Fan(w, &link_ring_, &nw);
    int common = 0;
    for (int x : nv) common += std::find(nw.begin(), nw.end(), x) != nw.end();
    if (common != 2) continue;
    // Wanted only within the slack and better than the best so far.
    double limit = std::nextafter(slack, HUGE_VAL);
    if (best->w >= 0) limit = std::min(limit, best->cand.max_violation);
    Candidate cand;
    if (EvaluateBelow(tris, true, old_agree, limit, &cand)) {
      best->w = w, best->cand = std::move(cand), best->tris = std::move(tris);
      best->cavity = cavity;
    }
  }
  return best->w >= 0;
}

// Collapses v into choice.w, then moves w to lower the largest violation around it. Keeps the
// result only when every triangle around w meets the criteria; otherwise restores the mesh.
bool Refiner::CollapseAndSmooth(int v, CollapseChoice& choice) {
  const int w = choice.w;
  std::vector<Tri> old_tris;
  std::vector<TriangleMeasure> old_measures;
  for (int t : choice.cavity) old_tris.push_back(m_.tri[t]), old_measures.push_back(measure_[t]);
  std::vector<int> ids = Apply(choice.cavity, choice.tris, choice.cand);
  m_.node_tri[v] = -1;
  if (choice.cand.max_violation <= 1.0) {
    if (!m_.fixed[w]) SmoothNode(w);
    return true;
  }
  // Move w, then its free neighbours, then w again; keep it when everything around meets the
  // criteria.
  std::vector<int> movers = {w};
  for (int x : m_.Neighbours(w))
    if (!m_.fixed[x]) movers.push_back(x);
  if (!m_.fixed[w]) movers.push_back(w);
  std::vector<int> region = RingsOf(m_, movers);
  std::vector<TriangleMeasure> region_measures;
  for (int t : region) region_measures.push_back(measure_[t]);
  std::vector<std::array<Vec3, 2>> saved_xyz;
  std::vector<Vec2> saved_uv;
  for (int x : movers) saved_uv.push_back(m_.uv[x]), saved_xyz.push_back({m_.xyz[x], m_.normal[x]});
  // A region triangle is final once no later mover is its corner: one that still violates then
  // dooms the attempt, so it stops there (the moves are undone below either way).
  std::vector<int> last = LastMoves(m_, movers, region);
  auto doomed = [&](int k) {
    for (size_t j = 0; j < region.size(); ++j)
      if (last[j] == k && measure_[region[j]].violation > 1.0) return true;
    return false;
  };
  bool failed = doomed(-1);
  for (int k = 0; k < static_cast<int>(movers.size()) && !failed; ++k) {
    if (!m_.fixed[movers[k]]) SmoothNode(movers[k]);
    if (MaxViolation(region) <= 1.0) return true;
    failed = doomed(k);
  }
  for (int k = static_cast<int>(movers.size()) - 1; k >= 0; --k) {
    int x = movers[k];
    m_.uv[x] = saved_uv[k], m_.xyz[x] = saved_xyz[k][0], m_.normal[x] = saved_xyz[k][1];
  }
  for (size_t k = 0; k < region.size(); ++k) measure_[region[k]] = region_measures[k];
  Candidate back;
  back.measures = old_measures;
  Apply(ids, old_tris, back);  // undo the collapse
  return false;
}

int Refiner::CollapsePass() {
  // Least damage first: a queue of each node's best collapse keyed by the largest violation it
  // leaves; after a collapse the survivor is smoothed and its neighbours are re-queued.
  int count = 0;
  std::vector<uint32_t> node_stamp(m_.node_count(), 0);
  using Entry = std::tuple<double, int, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  CollapseChoice choice;
  for (int v = 0; v < m_.node_count(); ++v)
    if (BestCollapse(v, &choice, kCollapseSlack)) queue.push({choice.cand.max_violation, v, 0});
  int64_t ops = 0;
  while (!queue.empty()) {
    auto [cost, v, stamp] = queue.top();
    queue.pop();
    if (stamp != node_stamp[v] || m_.node_tri[v] < 0) continue;
    if ((++ops & 255) == 0 && ctx_ && ctx_->ShouldStop()) break;
    if (!BestCollapse(v, &choice, kCollapseSlack)) continue;
    if (choice.cand.max_violation > cost * (1 + 1e-9) + 1e-12) {
      queue.push({choice.cand.max_violation, v, ++node_stamp[v]});
      continue;
    }
    if (!CollapseAndSmooth(v, choice)) continue;
    ++count;
    int w = choice.w;
    std::vector<int> around = m_.Neighbours(w);
    around.push_back(w);
    for (int x : around) {
      if (m_.fixed[x]) continue;
      ++node_stamp[x];
      if (BestCollapse(x, &choice, kCollapseSlack))
        queue.push({choice.cand.max_violation, x, node_stamp[x]});
    }
  }
  stats_.collapses += count;
  return count;
}

int Refiner::FlipPass() {
  int count = 0;
  for (int t = 0; t < static_cast<int>(m_.tri.size()); ++t) {
    if (!m_.alive[t]) continue;
    for (int i = 0; i < 3; ++i) {
      if (!m_.alive[t]) break;
      int u = m_.nbr[t][i];
      if (u > t && TryFlip(t, i)) ++count;
    }
  }
  return count;
}

bool Refiner::SmoothNode(int v) {
  if (m_.fixed[v] || m_.node_tri[v] < 0) return false;
  std::vector<int> ring, nv;
  m_.Fan(v, &ring, &nv);
  if (nv.size() != ring.size()) return false;
  std::vector<Tri> tris;
  for (int t : ring) tris.push_back(m_.tri[t]);
  const double old_score = MaxViolation(ring);
  const double old_agree = MinAgreement(ring);
  const Vec2 uv0 = m_.uv[v];
  const Vec3 x0 = m_.xyz[v], n0 = m_.normal[v];
  double r = 0;
  for (int w : nv) {
    Vec2 d = m_.uv[w] - uv0;
    r += std::hypot(d.x * su_, d.y * sv_);
  }
  r /= nv.size();
  std::vector<int> order(ring.size());  // ring triangles, worst first
  for (size_t k = 0; k < ring.size(); ++k) order[k] = static_cast<int>(k);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return measure_[ring[a]].violation > measure_[ring[b]].violation;
  });
  // The search ends at the last probe measured in full (every other value is an upper bound
  // that lost), so that probe's point, normal and measures are the result's.
  std::vector<TriangleMeasure> measures, best_measures;
  Vec3 best_xyz, best_normal;
  // The triangle that stopped the last losing probe in each direction (+u, -u, +v, -v) from the
  // last winning one: measured first, it most often stops the next probe that way too.
  int hint[4] = {-1, -1, -1, -1};
  Vec2 center = uv0;
  auto objective = [&](Vec2 q, double bound) {
    m_.uv[v] = q;  // the (u,v) test first: S and its normal only for oriented probes
    for (const Tri& nt : tris)
      if (!(Orient(m_.uv[nt[0]], m_.uv[nt[1]], m_.uv[nt[2]]) > 0)) return -HUGE_VAL;
    m_.xyz[v] = s_.Point(q.x, q.y);  // RingViolation evaluates the normal when it needs it
    const Vec2 d = q - center;
    const int dir =
        std::fabs(d.x * su_) >= std::fabs(d.y * sv_) ? (d.x > 0 ? 0 : 1) : (d.y > 0 ? 2 : 3);
    int stopper = -1;
    double worst =
        RingViolation(tris, v, old_agree, -bound, hint[dir], &stopper, &order, &measures);
    if (worst < -bound) {
      best_xyz = m_.xyz[v], best_normal = m_.normal[v], best_measures = measures;
      center = q;
    } else {
      hint[dir] = stopper;
    }
    return -worst;
  };
  PatternSearchResult res = CrossPatternSearch(
      objective, [](Vec2) { return true; }, uv0, -old_score, {0.2 * r / su_, 0.2 * r / sv_}, 0.1,
      24);
  if (!(res.value > -old_score * (1 - 1e-6))) {
    m_.uv[v] = uv0, m_.xyz[v] = x0, m_.normal[v] = n0;
    return false;
  }
  m_.uv[v] = res.x, m_.xyz[v] = best_xyz, m_.normal[v] = best_normal;  // v at the optimum
  for (size_t k = 0; k < ring.size(); ++k) {
    measure_[ring[k]] = best_measures[k];
    ++stamp_[ring[k]];
  }
  ++stats_.moves;
  return true;
}

int Refiner::SmoothPass() {
  int count = 0;
  for (int v = 0; v < m_.node_count(); ++v) {
    if ((v & 255) == 255 && ctx_ && ctx_->ShouldStop()) break;
    count += SmoothNode(v);
  }
  return count;
}

Status Refiner::Improve() {
  for (int round = 0; round < 8; ++round) {
    if (ctx_ && ctx_->ShouldStop()) return ctx_->StopStatus();
    int collapsed = CollapsePass();
    FlipPass();
    if (ctx_ && ctx_->ShouldStop()) return ctx_->StopStatus();
    SmoothPass();
    int nodes = 0;
    for (int v = 0; v < m_.node_count(); ++v) nodes += m_.node_tri[v] >= 0;
    if (collapsed <= nodes / 500) break;
  }
  return Status::Ok();
}

void Refiner::Finish() {
  stats_.max_violation = 0;
  stats_.max_deviation = 0;
  for (int t = 0; t < static_cast<int>(m_.tri.size()); ++t) {
    if (!m_.alive[t]) continue;
    stats_.max_violation = std::max(stats_.max_violation, measure_[t].violation);
    stats_.max_deviation = std::max(stats_.max_deviation, measure_[t].deviation);
  }
}

}  // namespace

Status RefineFace(WorkMesh* mesh, Surface& surface, const FaceCriteria& criteria, double scale_u,
                  double scale_v, int64_t max_triangles, bool improve, Context* context,
                  RefineStats* stats) {
  *stats = RefineStats();
  Refiner refiner(*mesh, surface, criteria, scale_u, scale_v, context, stats);
  Status st = refiner.RefineToCriteria(max_triangles);
  if (!st.ok()) return st;
  if (improve) {
    st = refiner.Improve();
    if (!st.ok()) return st;
  }
  refiner.Finish();
  return Status::Ok();
}

}  // namespace rdmesh
