// The improvement passes of face refinement (Refiner::Improve): collapses that remove interior
// nodes, flips, and smoothing that moves nodes to lower the largest violation around them.
#include <algorithm>
#include <cmath>
#include <queue>
#include <tuple>

#include "face/refine_constants.h"
#include "face/refiner.h"
#include "geometry/pattern_search.h"

namespace rdmesh {

bool Refiner::BestCollapse(int v, CollapseChoice* best, double slack) {
  best->w = -1;
  if (mesh_.fixed[v] || mesh_.node_tri[v] < 0) return false;
  std::vector<int>&cavity = fan_ring_, &nv = fan_nodes_, &nw = link_nodes_;
  mesh_.Fan(v, &cavity, &nv);
  if (nv.size() != cavity.size()) return false;  // not a closed fan
  const double old_agree = MinAgreement(cavity);
  std::vector<Tri>& tris = collapse_tris_;
  Candidate& cand = collapse_cand_;
  for (int w : nv) {
    CollapseTris(mesh_, v, w, cavity, &tris);
    bool oriented = true;  // the cheap (u,v) test first
    for (const Tri& nt : tris)
      oriented = oriented && Orient(mesh_.uv[nt[0]], mesh_.uv[nt[1]], mesh_.uv[nt[2]]) > 0;
    if (!oriented) continue;
    // Link condition: v and w share exactly the two apexes of the triangles on edge v-w.
    mesh_.Fan(w, &link_ring_, &nw);
    int common = 0;
    for (int x : nv) common += std::find(nw.begin(), nw.end(), x) != nw.end();
    if (common != 2) continue;
    // Wanted only within the slack and better than the best so far.
    double limit = std::nextafter(slack, HUGE_VAL);
    if (best->w >= 0) limit = std::min(limit, best->cand.max_violation);
    cand.max_violation = 0, cand.min_agreement = 1;
    if (EvaluateBelow(tris, true, old_agree, limit, &cand)) {
      best->w = w, best->cavity = cavity;
      std::swap(best->cand, cand), std::swap(best->tris, tris);  // the scratch keeps capacity
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
  for (int t : choice.cavity) old_tris.push_back(mesh_.tri[t]), old_measures.push_back(measure_[t]);
  std::vector<int> ids = Apply(choice.cavity, choice.tris, choice.cand, Phase::kImprove);
  mesh_.node_tri[v] = -1;
  if (choice.cand.max_violation <= 1.0) {
    if (!mesh_.fixed[w]) SmoothNode(w);
    return true;
  }
  // Move w, then its free neighbours, then w again; keep it when everything around meets the
  // criteria.
  std::vector<int> movers = {w};
  for (int x : mesh_.Neighbours(w))
    if (!mesh_.fixed[x]) movers.push_back(x);
  if (!mesh_.fixed[w]) movers.push_back(w);
  std::vector<int> region = RingsOf(mesh_, movers);
  std::vector<TriangleMeasure> region_measures;
  for (int t : region) region_measures.push_back(measure_[t]);
  std::vector<std::array<Vec3, 2>> saved_xyz;
  std::vector<Vec2> saved_uv;
  for (int x : movers)
    saved_uv.push_back(mesh_.uv[x]), saved_xyz.push_back({mesh_.xyz[x], mesh_.normal[x]});
  // A region triangle is final once no later mover is its corner: one that still violates then
  // dooms the attempt, so it stops there (the moves are undone below either way).
  std::vector<int> last = LastMoves(mesh_, movers, region);
  auto doomed = [&](int k) {
    for (size_t j = 0; j < region.size(); ++j)
      if (last[j] == k && measure_[region[j]].violation > 1.0) return true;
    return false;
  };
  bool failed = doomed(-1);
  for (int k = 0; k < static_cast<int>(movers.size()) && !failed; ++k) {
    if (!mesh_.fixed[movers[k]]) SmoothNode(movers[k], kMoverEnough);
    const double worst = MaxViolation(region);
    if (worst <= 1.0) return true;
    failed = doomed(k) || (k == 0 && worst > kGiveUpAfterSurvivor);
  }
  for (int k = static_cast<int>(movers.size()) - 1; k >= 0; --k) {
    int x = movers[k];
    mesh_.uv[x] = saved_uv[k], mesh_.xyz[x] = saved_xyz[k][0], mesh_.normal[x] = saved_xyz[k][1];
  }
  for (size_t k = 0; k < region.size(); ++k) measure_[region[k]] = region_measures[k];
  Candidate back;
  back.measures = old_measures;
  Apply(ids, old_tris, back, Phase::kImprove);  // undo the collapse
  return false;
}

int Refiner::CollapsePass(std::vector<uint8_t>* near) {
  // Least damage first: a queue of each node's best collapse keyed by the largest violation it
  // leaves; after a collapse the survivor is smoothed and its neighbours are re-queued.
  int count = 0;
  near->assign(mesh_.node_count(), 0);
  std::vector<uint32_t> node_stamp(mesh_.node_count(), 0);
  using Entry = std::tuple<double, int, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  CollapseChoice choice;
  for (int v = 0; v < mesh_.node_count(); ++v) {
    if ((v & 255) == 255 && context_ && context_->ShouldStop()) return count;
    if (BestCollapse(v, &choice, kCollapseSlack)) queue.push({choice.cand.max_violation, v, 0});
  }
  int64_t ops = 0;
  while (!queue.empty()) {
    auto [cost, v, stamp] = queue.top();
    queue.pop();
    if (stamp != node_stamp[v] || mesh_.node_tri[v] < 0) continue;
    if ((++ops & 255) == 0 && context_ && context_->ShouldStop()) break;
    if (!BestCollapse(v, &choice, kCollapseSlack)) continue;
    if (choice.cand.max_violation > cost * (1 + 1e-9) + 1e-12) {
      queue.push({choice.cand.max_violation, v, ++node_stamp[v]});
      continue;
    }
    if (!CollapseAndSmooth(v, choice)) continue;
    ++count;
    int w = choice.w;
    std::vector<int> around = mesh_.Neighbours(w);
    around.push_back(w);
    for (int x : around) {
      (*near)[x] = 1;
      for (int y : mesh_.Neighbours(x)) (*near)[y] = 1;
    }
    for (int x : around) {
      if (mesh_.fixed[x]) continue;
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
  for (int t = 0; t < static_cast<int>(mesh_.tri.size()); ++t) {
    if ((t & 255) == 255 && context_ && context_->ShouldStop()) break;
    if (!mesh_.alive[t]) continue;
    for (int i = 0; i < 3; ++i) {
      if (!mesh_.alive[t]) break;
      int u = mesh_.nbr[t][i];
      if (u > t && TryFlip(t, i, Phase::kImprove)) ++count;
    }
  }
  return count;
}

bool Refiner::SmoothNode(int v, double enough) {
  if (mesh_.fixed[v] || mesh_.node_tri[v] < 0) return false;
  SmoothScratch& x = smooth_;  // SmoothNode is not reentrant: its vectors keep their capacity
  std::vector<int>&ring = x.ring, &nv = x.nodes, &order = x.order;
  mesh_.Fan(v, &ring, &nv);
  if (nv.size() != ring.size()) return false;
  std::vector<Tri>& tris = x.tris;
  tris.clear();
  for (int t : ring) tris.push_back(mesh_.tri[t]);
  const double old_score = MaxViolation(ring);
  const double old_agree = MinAgreement(ring);
  const Vec2 uv0 = mesh_.uv[v];
  const Vec3 x0 = mesh_.xyz[v], n0 = mesh_.normal[v];
  double r = 0;
  for (int w : nv) {
    Vec2 d = mesh_.uv[w] - uv0;
    r += std::hypot(d.x * scale_u_, d.y * scale_v_);
  }
  r /= nv.size();
  order.resize(ring.size());  // ring triangles, worst first
  for (size_t k = 0; k < ring.size(); ++k) order[k] = static_cast<int>(k);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return measure_[ring[a]].violation > measure_[ring[b]].violation;
  });
  // The search ends at the last probe measured in full (every other value is an upper bound
  // that lost), so that probe's point, normal and measures are the result's.
  std::vector<TriangleMeasure>&measures = x.measures, &best_measures = x.best_measures;
  Vec3 best_xyz, best_normal;
  // The triangle that stopped the last losing probe in each direction (+u, -u, +v, -v) from the
  // last winning one: measured first, it most often stops the next probe that way too.
  int hint[4] = {-1, -1, -1, -1};
  Vec2 center = uv0;
  auto objective = [&](Vec2 q, double bound) {
    mesh_.uv[v] = q;  // the (u,v) test first: S and its normal only for oriented probes
    for (const Tri& nt : tris)
      if (!(Orient(mesh_.uv[nt[0]], mesh_.uv[nt[1]], mesh_.uv[nt[2]]) > 0)) return -HUGE_VAL;
    mesh_.xyz[v] = surface_.Point(q.x, q.y);  // RingViolation evaluates the normal when it needs it
    const Vec2 d = q - center;
    const int dir = std::fabs(d.x * scale_u_) >= std::fabs(d.y * scale_v_) ? (d.x > 0 ? 0 : 1)
                                                                           : (d.y > 0 ? 2 : 3);
    int stopper = -1;
    double worst =
        RingViolation(tris, v, old_agree, -bound, hint[dir], &stopper, &order, &measures);
    if (worst < -bound) {
      best_xyz = mesh_.xyz[v], best_normal = mesh_.normal[v], best_measures = measures;
      center = q;
    } else {
      hint[dir] = stopper;
    }
    return -worst;
  };
  PatternSearchResult res = CrossPatternSearch(
      objective, [](Vec2) { return true; }, uv0, -old_score,
      {0.2 * r / scale_u_, 0.2 * r / scale_v_}, 0.1, 24, -enough);
  if (!(res.value > -old_score * (1 - 1e-6))) {
    mesh_.uv[v] = uv0, mesh_.xyz[v] = x0, mesh_.normal[v] = n0;
    return false;
  }
  mesh_.uv[v] = res.x, mesh_.xyz[v] = best_xyz, mesh_.normal[v] = best_normal;  // v at the optimum
  for (size_t k = 0; k < ring.size(); ++k) {
    measure_[ring[k]] = best_measures[k];
    ++stamp_[ring[k]];
  }
  ++stats_.moves;
  return true;
}

int Refiner::SmoothPass(const std::vector<uint8_t>* only) {
  int count = 0;
  for (int v = 0; v < mesh_.node_count(); ++v) {
    if ((v & 255) == 255 && context_ && context_->ShouldStop()) break;
    if (only && !(*only)[v]) continue;
    count += SmoothNode(v);
  }
  return count;
}

void Refiner::Settle(int rounds) {
  for (int pass = 0; pass < kSettleFlipPasses; ++pass)
    if (FlipPass() == 0) break;
  for (int round = 0; round < rounds; ++round) {
    if (context_ && context_->ShouldStop()) return;
    FlipPass();
    SmoothPass(nullptr);
  }
}

Status Refiner::Improve() {
  std::vector<uint8_t> near;  // nodes within two rings of a collapse's survivor
  for (int round = 0; round < 8; ++round) {
    if (context_ && context_->ShouldStop()) return context_->StopStatus();
    int collapsed = CollapsePass(&near);
    FlipPass();
    if (context_ && context_->ShouldStop()) return context_->StopStatus();
    // The first round smooths every node; later ones only around their own collapses (see
    // kSmoothEverywhereRounds).
    SmoothPass(round < kSmoothEverywhereRounds ? nullptr : &near);
    int nodes = 0;
    for (int v = 0; v < mesh_.node_count(); ++v) nodes += mesh_.node_tri[v] >= 0;
    if (collapsed <= nodes / kStopCollapseDivisor) break;
  }
  return Status::Ok();
}

}  // namespace rdmesh
