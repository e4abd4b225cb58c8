#pragma once
// The Refiner: one face's working mesh with the measures of its triangles, and the local
// operations on it. Internal to face refinement: refiner.cpp holds the measures and the cavity
// replacement that every operation shares, refiner_split.cpp refinement to the criteria (splits,
// flips), refiner_improve.cpp the improvement passes (collapse, flip, smooth).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <queue>
#include <tuple>
#include <vector>

#include "face/measure.h"
#include "face/refine.h"
#include "face/work_mesh.h"
#include "geometry/surface.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Refiner {
 public:
  // `scale_u`, `scale_v` make (u,v) roughly isometric (FaceDomain::scale_u, scale_v).
  Refiner(WorkMesh& mesh, Surface& surface, const FaceCriteria& criteria, double scale_u,
          double scale_v, Context* context, RefineStats* stats)
      : mesh_(mesh),
        surface_(surface),
        criteria_(criteria),
        scale_u_(scale_u),
        scale_v_(scale_v),
        context_(context),
        stats_(*stats) {}

  // `settle_rounds`: see RefineFace.
  Status RefineToCriteria(int64_t max_triangles, int settle_rounds = 0);
  /// Splits every triangle over the criteria, worst first (RefineToCriteria's work after the
  /// first measures and Settle).
  Status SplitViolating(int64_t max_triangles);
  Status Improve();
  /// The final check of triangles measured by estimate (not a quadric's exact distance): each
  /// is measured again densely (DenseDeviation, along the free edges and inside), and the ones
  /// over the criterion are split as refinement splits, then their new triangles checked.
  Status Verify(int64_t max_triangles);
  void Finish();

 private:
  struct Candidate {
    std::vector<TriangleMeasure> measures;
    double max_violation = 0;
    double min_agreement = 1;
  };

  // What a cavity replacement (Apply) belongs to. kRefine: refinement to the criteria (splits,
  // and the pole realignments and flips that come with them): triangles that add to their cavity
  // are one split generation older, and new triangles that violate the criteria are queued.
  // kImprove: the improvement passes: generations are kept, nothing is queued.
  enum class Phase { kRefine, kImprove };
  // How a split may go. rescue: a split that folds a child may flip the child's outer edge with
  // it (RescueSplit), the second round of RefineToCriteria. for_sliver: the split makes room for
  // a sliver beside it (SplitSliver), so it does not split a sliver's neighbour in turn.
  struct SplitMode {
    bool rescue = false;
    bool for_sliver = false;
  };

  // --- Measures (refiner.cpp)
  Candidate Evaluate(const std::vector<Tri>& tris) {
    Candidate cand;
    EvaluateBelow(tris, false, 0, 0, &cand);
    return cand;
  }
  // The measures of `tris`, their largest violation and smallest agreement into *cand. With
  // `stop`, for a candidate wanted only when the fold guard holds (AgreementOk against old_agree)
  // and its max_violation stays below `limit`: false, with *cand partial, once either fails.
  bool EvaluateBelow(const std::vector<Tri>& tris, bool stop, double old_agree, double limit,
                     Candidate* cand);
  // Evaluate(tris).max_violation for a smoothing probe of v; once it cannot win (the maximum
  // reaches `limit`, or AgreementOk fails) a value >= limit, with the triangle that showed it in
  // *stopper. v's normal is evaluated when first needed. Measures tris[first] (if >= 0), then
  // `order` (worst first at the last full measurement, which re-sorts it): the order only changes
  // how soon a loser stops. A full one leaves in `measures` what Evaluate(tris).measures holds.
  double RingViolation(const std::vector<Tri>& tris, int v, double old_agree, double limit,
                       int first, int* stopper, std::vector<int>* order,
                       std::vector<TriangleMeasure>* measures);
  // A folded triangle (its normal against the surface's) must be refined whatever it deviates.
  // Every triangle but a pole's is measured along its edges too (MeasureEdgeHeights): where it is
  // tilted against the surface its plane heights fall short.
  void PenaliseFold(const Tri& t, double agreement, TriangleMeasure* m) const;
  // Whether nodes a and b are joined by a boundary edge (an edge grid's chord, or a pole's).
  bool BoundaryEdge(int a, int b) const;
  // Splits may not fold a child, except that a folded parent may leave children no worse.
  bool SplitOk(double child_min, const std::vector<int>& parents) const;
  double Agreement(int t) const;
  double MaxViolation(const std::vector<int>& tris) const {
    double v = 0;
    for (int t : tris) v = std::max(v, measure_[t].violation);
    return v;
  }
  // Agreement(t) is kept in measure_[t].agreement: every measurement that lands in measure_
  // comes with the fold guard of the same corners (PenaliseFold).
  double MinAgreement(const std::vector<int>& tris) const;
  // An optimisation step may not fold a triangle, nor push agreement below the guard where the
  // old triangles met it.
  bool AgreementOk(double new_min, double old_min) const {
    return new_min > 0 && new_min >= std::min(criteria_.min_normal_cos, old_min) - 1e-12;
  }

  // --- Nodes and cavities (refiner.cpp)
  int NewNode(Vec2 q, bool on_pole = false, int pole_of = -1);
  void DropLastNode();
  // Replaces the triangles `cavity` by `tris`, measured in `cand`; the new triangle ids.
  std::vector<int> Apply(const std::vector<int>& cavity, const std::vector<Tri>& tris,
                         const Candidate& cand, Phase phase);
  void Push(int t) { queue_.push({measure_[t].violation, t, stamp_[t]}); }

  // --- Refinement (refiner_split.cpp). SplitTriangle tries its strategies in turn, the first that
  // applies and succeeds wins: RealignPoleFan, SplitForLength, SplitSliver, SplitAtAreaOptimum,
  // SplitAnyEdge. Each takes the triangle's corners (uv, p: FoldCorners).
  // A fold that no split removes: one that kFoldRun splits in a row handed on to a child, or,
  // after one such split, one across which the surface's own normal jumps between two corners
  // (a twisted patch's fold line). A first triangle's fold stays to split (it may be too big).
  bool StuckFold(int t) const;
  bool SplitTriangle(int t, SplitMode mode);
  bool RealignPoleFan(int t);
  bool RealignPole(int p);
  bool SplitForLength(int t, const Vec3 p[3], SplitMode mode);
  bool SplitSliver(int t, const Vec3 p[3], SplitMode mode);
  bool SplitAtAreaOptimum(int t, const Vec2 uv[3], const Vec3 p[3], SplitMode mode);
  bool SplitAnyEdge(int t, const Vec3 p[3], SplitMode mode);
  bool SplitEdge(int t, int i, SplitMode mode, double at = -1);
  bool SplitAtPoint(int t, Vec2 q);
  bool SplitAtNode(int t, int node, SplitMode mode);
  bool CommitSplit(int node, SplitMode mode, std::vector<int>* cavity, std::vector<Tri>* tris,
                   int64_t* count);
  bool RescueSplit(int node, std::vector<int>* cavity, std::vector<Tri>* tris, Candidate* cand);
  bool ReshapeByFlip(int t);
  bool TryFlip(int t, int i, Phase phase);
  void Legalize(int node);

  // --- Improvement (refiner_improve.cpp)
  struct CollapseChoice {
    int w = -1;
    Candidate cand;
    std::vector<Tri> tris;
    std::vector<int> cavity;
  };
  bool BestCollapse(int v, CollapseChoice* best, double slack = 1.0);
  bool CollapseAndSmooth(int v, CollapseChoice& choice);
  // Moves v to lower the largest violation of its ring; the search stops early once that is at
  // or below `enough` (by default it goes on to the best it finds).
  bool SmoothNode(int v, double enough = -HUGE_VAL);
  // Marks in *near (one per node) the nodes within two rings of each collapse's survivor.
  int CollapsePass(std::vector<uint8_t>* near);
  int FlipPass();
  // Over every node, or only those `only` marks.
  int SmoothPass(const std::vector<uint8_t>* only);
  // Flip passes until none flips (at most a few), then `rounds` of a flip pass and a smoothing
  // pass: on a first triangulation, before refinement queues anything.
  void Settle(int rounds);

  WorkMesh& mesh_;
  Surface& surface_;
  const FaceCriteria& criteria_;
  double scale_u_, scale_v_;
  Context* context_;
  RefineStats& stats_;
  std::vector<TriangleMeasure> measure_;
  std::vector<uint32_t> stamp_;
  std::vector<uint8_t> generation_;  // per triangle: how many splits it descends from
  // Per triangle: how many splits in a row made folded triangles down to it (0 unfolded).
  std::vector<uint8_t> fold_run_;
  double face_diagonal_ = 0;  // of the box of the nodes RefineToCriteria starts from
  std::priority_queue<std::tuple<double, int, uint32_t>> queue_;
  std::vector<int> fan_ring_, fan_nodes_, link_ring_, link_nodes_;  // BestCollapse's scratch
  std::vector<Tri> collapse_tris_;
  Candidate collapse_cand_;
  struct SmoothScratch {
    std::vector<int> ring, nodes, order;
    std::vector<Tri> tris;
    std::vector<TriangleMeasure> measures, best_measures;
  } smooth_;                       // SmoothNode's
  std::vector<double> agreement_;  // EvaluateBelow's
};

}  // namespace rdmesh
