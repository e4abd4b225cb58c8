#include "face/unfold.h"

#include <algorithm>

#include "face/measure.h"
#include "geometry/surface.h"

namespace rdmesh {

namespace {

double Agreement(const WorkMesh& m, const Tri& t) {
  Vec2 uv[3];
  Vec3 p[3], n[3];
  m.FoldCorners(t, uv, p, n);
  return TriangleAgreement(uv, p, n);
}

// How far triangles are from folding: fewer folds first, then the larger smallest agreement.
struct FoldScore {
  int folds = 0;
  double min_agreement = 1;
  bool Beats(const FoldScore& o) const {
    return folds < o.folds || (folds == o.folds && min_agreement > o.min_agreement + 1e-9);
  }
};

FoldScore Score(double a, double b) { return {(a <= 0) + (b <= 0), std::min(a, b)}; }

// The best flip of an edge of folded triangle t (agreement_t): the edge (corner index) whose
// flipped pair scores best, if that beats the pair as it is; -1 when no flip helps.
int BestFlip(const WorkMesh& m, int t, double agreement_t, std::vector<int>* cavity,
             std::vector<Tri>* tris) {
  int best = -1;
  FoldScore best_score;
  std::vector<int> c;
  std::vector<Tri> x;
  for (int i = 0; i < 3; ++i) {
    if (m.kind[t][i] != EdgeKind::kFree || !FlipTris(m, t, i, &c, &x)) continue;
    bool valid = true;
    for (const Tri& nt : x) valid = valid && Orient(m.uv[nt[0]], m.uv[nt[1]], m.uv[nt[2]]) > 0;
    if (!valid) continue;
    FoldScore now = Score(agreement_t, Agreement(m, m.tri[c[1]]));
    FoldScore flipped = Score(Agreement(m, x[0]), Agreement(m, x[1]));
    if (flipped.Beats(now) && (best < 0 || flipped.Beats(best_score))) {
      best = i, best_score = flipped;
      *cavity = c, *tris = x;
    }
  }
  return best;
}

// The folded triangles of the mesh and its smallest agreement.
FoldScore MeshScore(const WorkMesh& m) {
  FoldScore s;
  for (int t = 0; t < static_cast<int>(m.tri.size()); ++t) {
    if (!m.alive[t]) continue;
    double a = Agreement(m, m.tri[t]);
    s.folds += a <= 0;
    s.min_agreement = std::min(s.min_agreement, a);
  }
  return s;
}

// The longest free edge of triangle t in (u,v) scaled by su, sv (its corner index), or -1.
int LongestFreeEdge(const WorkMesh& m, int t, double su, double sv) {
  int edge = -1;
  double longest = 0;
  for (int i = 0; i < 3; ++i) {
    if (m.kind[t][i] != EdgeKind::kFree) continue;
    Vec2 a = m.uv[m.tri[t][(i + 1) % 3]], b = m.uv[m.tri[t][(i + 2) % 3]];
    double dx = (a.x - b.x) * su, dy = (a.y - b.y) * sv;
    if (dx * dx + dy * dy > longest) longest = dx * dx + dy * dy, edge = i;
  }
  return edge;
}

// Splits the edge opposite corner i of t at its (u,v) midpoint; false (mesh unchanged but for
// an unused node) when a new triangle would not keep its (u,v) orientation.
bool BisectEdge(WorkMesh* m, Surface& s, int t, int i) {
  Vec2 q = 0.5 * (m->uv[m->tri[t][(i + 1) % 3]] + m->uv[m->tri[t][(i + 2) % 3]]);
  int n = m->AddNode(q, s.Point(q.x, q.y), s.Normal(q.x, q.y), false, NodeRef{});
  std::vector<int> cavity;
  std::vector<Tri> tris;
  SplitEdgeTris(*m, t, i, n, &cavity, &tris);
  for (const Tri& x : tris)
    if (!(Orient(m->uv[x[0]], m->uv[x[1]], m->uv[x[2]]) > 0)) return false;
  ReplaceCavity(m, cavity, tris);
  return true;
}

}  // namespace

int UnfoldFlips(WorkMesh* mesh) {
  WorkMesh& m = *mesh;
  std::vector<int> stack;
  auto push_if_folded = [&](int t) {
    if (t >= 0 && m.alive[t] && Agreement(m, m.tri[t]) <= 0) stack.push_back(t);
  };
  for (int t = static_cast<int>(m.tri.size()) - 1; t >= 0; --t) push_if_folded(t);
  // Each flip ends the pass sooner in theory; the cap guards against round-off cycles.
  const int max_flips = 16 * static_cast<int>(m.tri.size()) + 64;
  int flips = 0;
  std::vector<int> cavity;
  std::vector<Tri> tris;
  while (!stack.empty() && flips < max_flips) {
    int t = stack.back();
    stack.pop_back();
    if (!m.alive[t]) continue;
    double agreement = Agreement(m, m.tri[t]);
    if (agreement > 0 || BestFlip(m, t, agreement, &cavity, &tris) < 0) continue;
    std::vector<int> ids = ReplaceCavity(&m, cavity, tris);
    ++flips;
    // The new pair and the folded triangles around it may flip on.
    for (int id : ids) {
      for (int k = 0; k < 3; ++k) push_if_folded(m.nbr[id][k]);
      push_if_folded(id);
    }
  }
  return flips;
}

int CountFolds(const WorkMesh& mesh) { return MeshScore(mesh).folds; }

int UnfoldInitialMesh(WorkMesh* mesh, Surface& surface, double scale_u, double scale_v) {
  WorkMesh& m = *mesh;
  const int flips = UnfoldFlips(&m);
  int added = 0;
  const int max_added = std::max(16, m.node_count());
  FoldScore score = MeshScore(m);
  for (bool progress = true; progress && score.folds > 0 && added < max_added;) {
    progress = false;
    std::vector<int> folded;
    for (int t = 0; t < static_cast<int>(m.tri.size()); ++t)
      if (m.alive[t] && Agreement(m, m.tri[t]) <= 0) folded.push_back(t);
    for (int t : folded) {
      if (added >= max_added || !m.alive[t] || Agreement(m, m.tri[t]) > 0) continue;
      int edge = LongestFreeEdge(m, t, scale_u, scale_v);
      if (edge < 0) continue;
      // A bisection stays only when the mesh, flipped again, has fewer folds or a larger
      // smallest agreement (a fold beside a coarse boundary segment may have no cure inside).
      WorkMesh trial = m;
      if (!BisectEdge(&trial, surface, t, edge)) continue;
      UnfoldFlips(&trial);
      FoldScore s = MeshScore(trial);
      if (!s.Beats(score)) continue;
      m = std::move(trial);
      score = s;
      ++added;
      progress = true;
    }
  }
  return flips + added;
}

}  // namespace rdmesh
