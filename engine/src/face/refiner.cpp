// The Refiner's shared part: measuring candidate triangles (with the fold guard), making and
// dropping nodes, and replacing a cavity of triangles with measured ones.
#include "face/refiner.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "face/refine_constants.h"

namespace rdmesh {

bool Refiner::EvaluateBelow(const std::vector<Tri>& tris, bool stop, double old_agree, double limit,
                            Candidate* cand) {
  Vec2 uv[3];
  Vec3 p[3], n[3];
  std::vector<double>& agreement = agreement_;  // scratch
  agreement.resize(tris.size());
  for (size_t k = 0; k < tris.size(); ++k) {
    mesh_.FoldCorners(tris[k], uv, p, n);
    agreement[k] = TriangleAgreement(uv, p, n);
    cand->min_agreement = std::min(cand->min_agreement, agreement[k]);
  }
  if (stop && !AgreementOk(cand->min_agreement, old_agree)) return false;
  cand->measures.resize(tris.size());
  for (size_t k = 0; k < tris.size(); ++k) {
    mesh_.MeasureCorners(tris[k], uv, p);
    TriangleMeasure& m = cand->measures[k];
    if (!stop)
      m = MeasureTriangle(surface_, uv, p, criteria_);
    else if (!MeasureTriangleBelow(surface_, uv, p, criteria_, limit, &m))
      return false;
    PenaliseFold(tris[k], agreement[k], &m);
    cand->max_violation = std::max(cand->max_violation, m.violation);
    if (stop && !(cand->max_violation < limit)) return false;
  }
  return true;
}

double Refiner::RingViolation(const std::vector<Tri>& tris, int v, double old_agree, double limit,
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
    mesh_.MeasureCorners(tris[k], uv, p);
    TriangleMeasure& m = (*measures)[k];
    if (!MeasureTriangleBelow(surface_, uv, p, criteria_, limit, &m)) return m.violation;
    worst = std::max(worst, m.violation);
    if (worst >= limit) return worst;
    if (!normal_ready)
      mesh_.normal[v] = surface_.Normal(mesh_.uv[v].x, mesh_.uv[v].y), normal_ready = true;
    mesh_.FoldCorners(tris[k], uv, p, n);
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

void Refiner::PenaliseFold(const Tri& t, double agreement, TriangleMeasure* m) const {
  m->agreement = agreement;
  // At a pole the corner normal is a stand-in (FoldCorners): the edge heights are not known there.
  bool pole = mesh_.pole_axis[t[0]] + mesh_.pole_axis[t[1]] + mesh_.pole_axis[t[2]] > -3;
  // An exact measure has nothing to add (MeasureEdgeHeights leaves it as it is).
  if (agreement > kInvalid && !pole && !m->exact) {
    // A triangle standing against the surface: every edge. Else the edges that refinement can
    // split: not a chord of an edge grid, which holds that edge's deviation (and its distance to
    // this surface, up to the edge's tolerance).
    int edges = 7;
    if (agreement >= criteria_.min_normal_cos)
      for (int i = 0; i < 3; ++i)
        if (BoundaryEdge(t[(i + 1) % 3], t[(i + 2) % 3])) edges &= ~(1 << i);
    Vec2 uv[3], fold_uv[3];
    Vec3 p[3], fold_p[3], n[3];
    mesh_.MeasureCorners(t, uv, p);
    mesh_.FoldCorners(t, fold_uv, fold_p, n);
    MeasureEdgeHeights(surface_, uv, p, n, criteria_, edges, m);
  }
  if (agreement <= 0) m->violation = std::max(m->violation, kFoldViolation);
}

bool Refiner::BoundaryEdge(int a, int b) const {
  if (!mesh_.fixed[a] || !mesh_.fixed[b]) return false;
  // Not an edge yet: one that an operation makes, inside the face.
  EdgeKind kind;
  return mesh_.EdgeKindOf(a, b, &kind) && kind != EdgeKind::kFree;
}

bool Refiner::SplitOk(double child_min, const std::vector<int>& parents) const {
  double parent_min = 1;
  int parent_gen = 0;
  for (int t : parents) {
    parent_min = std::min(parent_min, measure_[t].agreement);
    parent_gen = std::max(parent_gen, static_cast<int>(generation_[t]));
  }
  // A young parent that stands up against the surface spans too much of it: its children may
  // fold, and refinement (a fold counts as a violation) goes on until they do not. Later
  // generations may not fold.
  if (parent_min < 0.2 && parent_gen < kFoldingGenerations) return child_min > kInvalid;
  if (parent_min <= 0) return child_min > kInvalid && child_min >= parent_min;
  return child_min > 0;
}

double Refiner::Agreement(int t) const {
  Vec2 uv[3];
  Vec3 p[3], n[3];
  mesh_.FoldCorners(mesh_.tri[t], uv, p, n);
  return TriangleAgreement(uv, p, n);
}

double Refiner::MinAgreement(const std::vector<int>& tris) const {
  double a = 1;
  for (int t : tris) {
    assert(measure_[t].agreement == Agreement(t));
    a = std::min(a, measure_[t].agreement);
  }
  return a;
}

int Refiner::NewNode(Vec2 q, bool on_pole, int pole_of) {
  if (on_pole) {
    return mesh_.AddNode(q, mesh_.xyz[pole_of], surface_.Normal(q.x, q.y), true, mesh_.ref[pole_of],
                         mesh_.pole_axis[pole_of]);
  }
  Vec3 x = surface_.Point(q.x, q.y);
  return mesh_.AddNode(q, x, surface_.Normal(q.x, q.y), false, NodeRef{});
}

void Refiner::DropLastNode() {
  mesh_.uv.pop_back(), mesh_.xyz.pop_back(), mesh_.normal.pop_back(), mesh_.fixed.pop_back();
  mesh_.ref.pop_back(), mesh_.node_tri.pop_back(), mesh_.pole_axis.pop_back();
}

std::vector<int> Refiner::Apply(const std::vector<int>& cavity, const std::vector<Tri>& tris,
                                const Candidate& cand, Phase phase) {
  // Generation: how many splits a triangle descends from (flips and collapses keep it).
  // Fold run: how many splits in a row made folded triangles down to a folded one (0 unfolded).
  int gen = 0, fold_run = 0;
  for (int t : cavity) {
    gen = std::max(gen, static_cast<int>(generation_[t]));
    if (measure_[t].agreement <= 0) fold_run = std::max(fold_run, static_cast<int>(fold_run_[t]));
  }
  if (phase == Phase::kRefine && tris.size() > cavity.size())
    gen = std::min(gen + 1, 255), fold_run = std::min(fold_run + 1, 255);
  std::vector<int> ids = ReplaceCavity(&mesh_, cavity, tris);
  if (measure_.size() < mesh_.tri.size()) {
    measure_.resize(mesh_.tri.size());
    stamp_.resize(mesh_.tri.size(), 0);
    generation_.resize(mesh_.tri.size(), 0);
    fold_run_.resize(mesh_.tri.size(), 0);
  }
  for (size_t k = 0; k < ids.size(); ++k) {
    generation_[ids[k]] = static_cast<uint8_t>(gen);
    fold_run_[ids[k]] = static_cast<uint8_t>(cand.measures[k].agreement <= 0 ? fold_run : 0);
    measure_[ids[k]] = cand.measures[k];
    ++stamp_[ids[k]];
    if (phase == Phase::kRefine && cand.measures[k].violation > 1) Push(ids[k]);
  }
  for (int t : cavity)
    if (!mesh_.alive[t]) ++stamp_[t];
  return ids;
}

}  // namespace rdmesh
