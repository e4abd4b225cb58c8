#include "face/work_mesh.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace rdmesh {

int WorkMesh::AddNode(Vec2 p, Vec3 x, Vec3 n, bool is_fixed, NodeRef r, int axis) {
  pole_axis.push_back(static_cast<int8_t>(axis));
  uv.push_back(p);
  xyz.push_back(x);
  normal.push_back(n);
  fixed.push_back(is_fixed ? 1 : 0);
  ref.push_back(r);
  node_tri.push_back(-1);
  return node_count() - 1;
}

void WorkMesh::MeasureCorners(const std::array<int, 3>& t, Vec2 q[3], Vec3 x[3]) const {
  for (int i = 0; i < 3; ++i) q[i] = uv[t[i]], x[i] = xyz[t[i]];
  for (int i = 0; i < 3; ++i) {
    int axis = pole_axis[t[i]];
    if (axis < 0) continue;
    const Vec2 &a = uv[t[(i + 1) % 3]], &b = uv[t[(i + 2) % 3]];
    if (pole_axis[t[(i + 1) % 3]] >= 0 || pole_axis[t[(i + 2) % 3]] >= 0) continue;
    if (axis == 0)
      q[i].x = 0.5 * (a.x + b.x);
    else
      q[i].y = 0.5 * (a.y + b.y);
  }
}

void WorkMesh::MeasureCorners(int t, Vec2 q[3], Vec3 x[3]) const { MeasureCorners(tri[t], q, x); }

int WorkMesh::CornersWithNeighbours(int t, Vec3 out[12]) const {
  Vec2 uv[3];
  MeasureCorners(t, uv, out);
  int count = 1;
  for (int i = 0; i < 3; ++i) {
    const int w = nbr[t][i];
    if (w >= 0 && alive[w]) MeasureCorners(w, uv, out + 3 * count++);
  }
  return count;
}

std::vector<Vec3> WorkMesh::CornersAroundCorners(int t) const {
  Vec2 uv_scratch[3];
  std::vector<Vec3> out(3);
  MeasureCorners(t, uv_scratch, out.data());
  for (int v : tri[t])
    for (int w : Ring(v)) {
      if (w == t) continue;
      out.resize(out.size() + 3);
      MeasureCorners(w, uv_scratch, &out[out.size() - 3]);
    }
  return out;
}

void WorkMesh::FoldCorners(const std::array<int, 3>& t, Vec2 q[3], Vec3 x[3], Vec3 n[3]) const {
  for (int i = 0; i < 3; ++i) q[i] = uv[t[i]], x[i] = xyz[t[i]], n[i] = normal[t[i]];
  for (int i = 0; i < 3; ++i) {
    int j = t[(i + 1) % 3], k = t[(i + 2) % 3];
    if (pole_axis[t[i]] >= 0 && pole_axis[j] < 0 && pole_axis[k] < 0)
      n[i] = Normalized(normal[j] + normal[k]);
  }
}

int WorkMesh::TriangleCount() const {
  // Every dead slot is in free_slots (ReplaceCavity keeps it so).
  return static_cast<int>(tri.size() - free_slots.size());
}

int WorkMesh::CornerOf(int t, int v) const {
  for (int i = 0; i < 3; ++i)
    if (tri[t][i] == v) return i;
  return -1;
}

namespace {

// Calls visit(t) for the triangles around v, in WorkMesh::Ring's order, until it returns true
// (then returns true). Walks one way (across the edge after v), then, if the fan is open, the
// other way.
template <typename Visit>
bool VisitRing(const WorkMesh& m, int v, Visit visit) {
  int start = m.node_tri[v];
  if (start < 0 || !m.alive[start]) return false;
  size_t count = 0;
  int t = start;
  do {
    if (visit(t)) return true;
    ++count;
    int k = m.CornerOf(t, v);
    t = m.nbr[t][(k + 1) % 3];
  } while (t >= 0 && t != start && count < 4096);
  if (t == start) return false;
  t = start;
  while (true) {
    int k = m.CornerOf(t, v);
    t = m.nbr[t][(k + 2) % 3];
    if (t < 0 || t == start || count >= 4096) break;
    if (visit(t)) return true;
    ++count;
  }
  return false;
}

// WorkMesh::Ring's walk, into *ring (cleared first).
void WalkRing(const WorkMesh& m, int v, std::vector<int>* ring) {
  ring->clear();
  VisitRing(m, v, [ring](int t) {
    ring->push_back(t);
    return false;
  });
}

// The nodes of the triangles `ring` around v, but v, in their order of first appearance.
void RingNodes(const WorkMesh& m, int v, const std::vector<int>& ring, std::vector<int>* out) {
  out->clear();
  for (int t : ring) {
    int k = m.CornerOf(t, v);
    for (int j : {m.tri[t][(k + 1) % 3], m.tri[t][(k + 2) % 3]})
      if (std::find(out->begin(), out->end(), j) == out->end()) out->push_back(j);
  }
}

}  // namespace

std::vector<int> WorkMesh::Ring(int v) const {
  std::vector<int> ring;
  ring.reserve(8);
  WalkRing(*this, v, &ring);
  return ring;
}

bool WorkMesh::EdgeKindOf(int a, int b, EdgeKind* edge_kind) const {
  return VisitRing(*this, a, [&](int t) {
    const int k = CornerOf(t, b);
    if (k < 0) return false;
    *edge_kind = kind[t][3 - k - CornerOf(t, a)];
    return true;
  });
}

std::vector<int> WorkMesh::Neighbours(int v) const {
  std::vector<int> ring, out;
  Fan(v, &ring, &out);
  return out;
}

void WorkMesh::Fan(int v, std::vector<int>* ring, std::vector<int>* neighbours) const {
  WalkRing(*this, v, ring);
  RingNodes(*this, v, *ring, neighbours);
}

void InitWorkMesh(const std::vector<std::array<int, 3>>& triangles,
                  const std::vector<std::array<bool, 3>>& constrained,
                  const std::vector<std::array<int, 2>>& splittable_segments, WorkMesh* m) {
  const int nt = static_cast<int>(triangles.size());
  m->tri = triangles;
  m->nbr.assign(nt, {-1, -1, -1});
  m->kind.assign(nt, {EdgeKind::kFree, EdgeKind::kFree, EdgeKind::kFree});
  m->alive.assign(nt, 1);
  m->free_slots.clear();
  // Directed edges (a, b, triangle), sorted: a face of 10^5 boundary nodes makes a few 10^5 of
  // them, which a map allocates one by one. Where a directed edge repeats, the last triangle
  // counts.
  std::vector<std::array<int, 3>> edges;
  edges.reserve(3 * static_cast<size_t>(nt));
  for (int t = 0; t < nt; ++t) {
    for (int i = 0; i < 3; ++i) {
      edges.push_back({triangles[t][(i + 1) % 3], triangles[t][(i + 2) % 3], t});
      m->node_tri[triangles[t][i]] = t;
    }
  }
  std::sort(edges.begin(), edges.end());
  // The triangle holding directed edge a->b, or -1.
  auto triangle_of = [&edges](int a, int b) {
    auto it = std::lower_bound(edges.begin(), edges.end(), std::array<int, 3>{a, b + 1, 0});
    return it == edges.begin() || (*(it - 1))[0] != a || (*(it - 1))[1] != b ? -1 : (*(it - 1))[2];
  };
  for (const auto& s : splittable_segments) {
    Vec2 d = m->uv[s[1]] - m->uv[s[0]];
    int8_t axis = std::fabs(d.x) >= std::fabs(d.y) ? 0 : 1;
    m->pole_axis[s[0]] = m->pole_axis[s[1]] = axis;
  }
  // Splittable segments as sorted (low, high) node pairs: a face with 10^5 boundary nodes asks
  // this for every boundary edge.
  std::vector<std::pair<int, int>> splittable;
  splittable.reserve(splittable_segments.size());
  for (const auto& s : splittable_segments)
    splittable.push_back({std::min(s[0], s[1]), std::max(s[0], s[1])});
  std::sort(splittable.begin(), splittable.end());
  auto is_splittable = [&](int a, int b) {
    return std::binary_search(splittable.begin(), splittable.end(),
                              std::make_pair(std::min(a, b), std::max(a, b)));
  };
  for (int t = 0; t < nt; ++t) {
    for (int i = 0; i < 3; ++i) {
      int a = triangles[t][(i + 1) % 3], b = triangles[t][(i + 2) % 3];
      const int other = triangle_of(b, a);
      if (other >= 0) m->nbr[t][i] = other;
      if (constrained[t][i] || other < 0)
        m->kind[t][i] = is_splittable(a, b) ? EdgeKind::kSplittable : EdgeKind::kFixed;
    }
  }
}

std::vector<int> ReplaceCavity(WorkMesh* m, const std::vector<int>& old_tris,
                               const std::vector<Tri>& new_tris) {
  // Cavities are small: flat lists searched linearly beat maps (no allocation per edge).
  // Border of the cavity: directed edge a->b with its outside neighbour and kind.
  struct Border {
    int a, b;
    int outside;
    EdgeKind kind;
  };
  thread_local std::vector<Border> border;
  border.clear();
  for (int t : old_tris) {
    for (int i = 0; i < 3; ++i) {
      int n = m->nbr[t][i];
      if (n >= 0 && std::find(old_tris.begin(), old_tris.end(), n) != old_tris.end()) continue;
      int a = m->tri[t][(i + 1) % 3], b = m->tri[t][(i + 2) % 3];
      border.push_back({a, b, n, m->kind[t][i]});
    }
  }
  for (int t : old_tris) m->alive[t] = 0;
  std::vector<int> ids;
  ids.reserve(new_tris.size());
  size_t reuse = 0;
  for (const Tri& nt : new_tris) {
    int id;
    if (reuse < old_tris.size()) {
      id = old_tris[reuse++];
    } else if (!m->free_slots.empty()) {
      id = m->free_slots.back();
      m->free_slots.pop_back();
    } else {
      id = static_cast<int>(m->tri.size());
      m->tri.push_back({});
      m->nbr.push_back({});
      m->kind.push_back({});
      m->alive.push_back(0);
    }
    m->tri[id] = nt;
    m->alive[id] = 1;
    ids.push_back(id);
  }
  for (; reuse < old_tris.size(); ++reuse) m->free_slots.push_back(old_tris[reuse]);
  // Link the new triangles to each other and to the border. A directed edge may be listed more
  // than once (a cavity that is not a disc); as with a map, the last entry wins.
  auto find_border = [&](int a, int b) -> const Border* {
    for (size_t k = border.size(); k-- > 0;)
      if (border[k].a == a && border[k].b == b) return &border[k];
    return nullptr;
  };
  auto find_inner = [&](int a, int b) {
    int found = -1;
    for (int id : ids)
      for (int i = 0; i < 3; ++i)
        if (m->tri[id][(i + 1) % 3] == a && m->tri[id][(i + 2) % 3] == b) found = id;
    return found;
  };
  for (int id : ids) {
    for (int i = 0; i < 3; ++i) {
      int a = m->tri[id][(i + 1) % 3], b = m->tri[id][(i + 2) % 3];
      m->node_tri[m->tri[id][i]] = id;
      int in = find_inner(b, a);
      if (in >= 0) {
        m->nbr[id][i] = in;
        m->kind[id][i] = EdgeKind::kFree;
        continue;
      }
      const Border* out = find_border(a, b);
      if (!out) {  // a new piece of a pole edge (RebuildPoleFan)
        m->nbr[id][i] = -1;
        m->kind[id][i] =
            m->pole_axis[a] >= 0 && m->pole_axis[b] >= 0 ? EdgeKind::kSplittable : EdgeKind::kFixed;
        continue;
      }
      m->nbr[id][i] = out->outside;
      m->kind[id][i] = out->kind;
      int o = out->outside;
      if (o >= 0) {
        for (int j = 0; j < 3; ++j) {
          if (m->tri[o][(j + 1) % 3] == b && m->tri[o][(j + 2) % 3] == a) m->nbr[o][j] = id;
        }
      }
    }
  }
  return ids;
}

std::vector<Tri> SplitTriangleTris(const WorkMesh& m, int t, int n) {
  const Tri& x = m.tri[t];
  return {{x[0], x[1], n}, {x[1], x[2], n}, {x[2], x[0], n}};
}

void SplitEdgeTris(const WorkMesh& m, int t, int i, int n, std::vector<int>* cavity,
                   std::vector<Tri>* tris) {
  int a = m.tri[t][i], b = m.tri[t][(i + 1) % 3], c = m.tri[t][(i + 2) % 3];
  *cavity = {t};
  *tris = {{a, b, n}, {a, n, c}};
  int u = m.nbr[t][i];
  if (u >= 0) {
    int d = m.tri[u][(m.CornerOf(u, b) + 1) % 3];  // u = (d, c, b) up to rotation
    cavity->push_back(u);
    tris->push_back({d, c, n});
    tris->push_back({d, n, b});
  }
}

bool FlipTris(const WorkMesh& m, int t, int i, std::vector<int>* cavity, std::vector<Tri>* tris) {
  int u = m.nbr[t][i];
  if (u < 0) return false;
  int a = m.tri[t][i], b = m.tri[t][(i + 1) % 3], c = m.tri[t][(i + 2) % 3];
  int d = m.tri[u][(m.CornerOf(u, b) + 1) % 3];
  *cavity = {t, u};
  *tris = {{a, b, d}, {a, d, c}};
  return true;
}

bool FlipOuterEdgeTris(const WorkMesh& m, const std::vector<int>& cavity, const Tri& child, int n,
                       int* w, Tri out[2]) {
  int k = child[0] == n ? 0 : child[1] == n ? 1 : child[2] == n ? 2 : -1;
  if (k < 0) return false;
  const int a = child[(k + 1) % 3], b = child[(k + 2) % 3];
  // The cavity triangle that holds the directed edge a->b; its neighbour there is w.
  for (int t : cavity) {
    int i = m.CornerOf(t, a);
    if (i < 0 || m.tri[t][(i + 1) % 3] != b) continue;
    int e = (i + 2) % 3;  // the edge a->b lies opposite this corner
    *w = m.nbr[t][e];
    if (*w < 0 || m.kind[t][e] != EdgeKind::kFree ||
        std::find(cavity.begin(), cavity.end(), *w) != cavity.end())
      return false;
    // w holds b->a; c is its third corner. The quad a, c, b, n takes the diagonal n-c.
    const int c = m.tri[*w][(m.CornerOf(*w, a) + 1) % 3];
    out[0] = {a, c, n};
    out[1] = {c, b, n};
    return true;
  }
  return false;
}

void CollapseTris(const WorkMesh& m, int v, int w, const std::vector<int>& ring,
                  std::vector<Tri>* tris) {
  tris->clear();
  for (int t : ring) {
    if (m.CornerOf(t, w) >= 0) continue;
    Tri x = m.tri[t];
    x[m.CornerOf(t, v)] = w;
    tris->push_back(x);
  }
}

std::vector<int> RingsOf(const WorkMesh& m, const std::vector<int>& nodes) {
  std::vector<int> out;
  for (int x : nodes)
    for (int t : m.Ring(x))
      if (std::find(out.begin(), out.end(), t) == out.end()) out.push_back(t);
  return out;
}

std::vector<int> LastMoves(const WorkMesh& m, const std::vector<int>& movers,
                           const std::vector<int>& tris) {
  std::vector<int> last(tris.size(), -1);
  for (size_t j = 0; j < tris.size(); ++j)
    for (int k = 0; k < static_cast<int>(movers.size()); ++k)
      if (!m.fixed[movers[k]] && m.CornerOf(tris[j], movers[k]) >= 0) last[j] = k;
  return last;
}

}  // namespace rdmesh

namespace rdmesh {

bool PoleFanTris(WorkMesh* m, int p, std::vector<int>* cavity, std::vector<Tri>* tris,
                 std::vector<int>* new_nodes, double* shift) {
  const int axis = m->pole_axis[p];
  if (axis < 0) return false;
  *cavity = m->Ring(p);
  // Chain the link edges a -> b of the triangles (p, a, b) from a pole node onward.
  std::map<int, int> next;
  for (int t : *cavity) {
    int k = m->CornerOf(t, p);
    next[m->tri[t][(k + 1) % 3]] = m->tri[t][(k + 2) % 3];
  }
  std::map<int, int> prev;
  for (auto [a, b] : next) prev[b] = a;
  int start = -1;
  for (auto [a, b] : next)
    if (!prev.count(a)) start = a;
  if (start < 0) return false;
  std::vector<int> chain = {start};
  while (next.count(chain.back()) && chain.size() <= cavity->size())
    chain.push_back(next[chain.back()]);
  if (chain.size() != cavity->size() + 1) return false;
  const bool has_start = m->pole_axis[chain.front()] >= 0;
  const bool has_end = m->pole_axis[chain.back()] >= 0;
  if (!has_start && !has_end) return false;
  // Regular ring nodes R_0..R_r between the pole neighbours.
  std::vector<int> r(chain.begin() + (has_start ? 1 : 0), chain.end() - (has_end ? 1 : 0));
  for (int x : r)
    if (m->pole_axis[x] >= 0) return false;
  const int fans = static_cast<int>(r.size()) - 1;
  if (fans < 1) return false;
  auto along = [&](Vec2 q) { return axis == 0 ? q.x : q.y; };
  // One pole node per fan, under the middle of its ring edge. A fan that holds a fixed boundary
  // edge (no pole neighbour on its side) keeps p.
  std::vector<int> n(fans);
  double worst = 0;
  new_nodes->clear();
  for (int j = 0; j < fans; ++j) {
    if ((j == 0 && !has_start) || (j == fans - 1 && !has_end)) {
      n[j] = p;
      continue;
    }
    Vec2 q = m->uv[p];
    double target = 0.5 * (along(m->uv[r[j]]) + along(m->uv[r[j + 1]]));
    worst = std::max(worst, std::fabs(target - along(q)));
    (axis == 0 ? q.x : q.y) = target;
    n[j] = m->AddNode(q, m->xyz[p], m->normal[p], true, m->ref[p], axis);
    new_nodes->push_back(n[j]);
  }
  *shift = worst;
  tris->clear();
  if (has_start) tris->push_back({n[0], chain.front(), r[0]});
  for (int j = 0; j < fans; ++j) {
    tris->push_back({n[j], r[j], r[j + 1]});
    if (j + 1 < fans) tris->push_back({n[j + 1], n[j], r[j + 1]});
  }
  if (has_end) tris->push_back({n[fans - 1], r[fans], chain.back()});
  return true;
}

}  // namespace rdmesh
