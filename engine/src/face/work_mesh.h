#pragma once
// The working triangulation of one face and the paper's local operations on it: triangle split,
// edge split, edge flip, plus edge collapse and node relocation (smoothing). Plain index arrays
// with triangle adjacency; every operation replaces a small cavity of triangles and relinks it.

#include <array>
#include <cstdint>
#include <vector>

#include "boundary/node_ref.h"
#include "core/geom.h"

namespace rdmesh {

/// Kind of a triangle edge.
enum class EdgeKind : uint8_t {
  kFree = 0,        ///< interior edge: may be flipped or split
  kFixed = 1,       ///< boundary edge from an edge grid: never changes
  kSplittable = 2,  ///< boundary edge of a degenerate (pole) edge: may be split, never flipped
};

struct WorkMesh {
  // Nodes.
  std::vector<Vec2> uv;        ///< surface parameters
  std::vector<Vec3> xyz;       ///< world point
  std::vector<Vec3> normal;    ///< unit surface normal Su x Sv at the node
  std::vector<uint8_t> fixed;  ///< 1 = boundary node: never moves, never goes away
  std::vector<NodeRef> ref;    ///< B-rep classification
  std::vector<int> node_tri;   ///< one alive triangle incident to the node (-1 = none)
  /// Nodes on a degenerate (pole) edge: which parameter runs along that edge (0 = u, 1 = v);
  /// -1 for other nodes. A pole is one 3D point, so its parameter along the edge is arbitrary.
  std::vector<int8_t> pole_axis;
  // Triangles (counter-clockwise in (u,v)).
  std::vector<std::array<int, 3>> tri;
  std::vector<std::array<int, 3>> nbr;  ///< neighbour across the edge opposite corner i; -1 none
  std::vector<std::array<EdgeKind, 3>> kind;  ///< kind of the edge opposite corner i
  std::vector<uint8_t> alive;
  std::vector<int> free_slots;  ///< dead triangle slots to reuse

  int node_count() const { return static_cast<int>(uv.size()); }
  int AddNode(Vec2 uv, Vec3 xyz, Vec3 normal, bool fixed, NodeRef ref, int pole_axis = -1);
  /// The corners of triangle t as refinement should measure them: a pole corner takes, along its
  /// pole edge, the mean parameter of the other two corners, so the (u,v) patch sampled is the
  /// one the 3D triangle stands for.
  void MeasureCorners(int t, Vec2 uv[3], Vec3 xyz[3]) const;
  void MeasureCorners(const std::array<int, 3>& t, Vec2 uv[3], Vec3 xyz[3]) const;
  /// MeasureCorners' points of triangle t and of its live neighbours, three per triangle, into
  /// out[0..12): how many triangles (1 to 4).
  int CornersWithNeighbours(int t, Vec3 out[12]) const;
  /// MeasureCorners' points of triangle t, then of every other triangle at each of its corners
  /// (Ring), three per triangle: the triangles the mesh's nearest point to a point over t can
  /// lie on where thin triangles meet at a corner.
  std::vector<Vec3> CornersAroundCorners(int t) const;
  /// The corners of triangle t for the fold guard (TriangleAgreement). The surface normal at a
  /// pole depends on the direction it is approached from, so a pole corner takes its
  /// neighbours' mean normal.
  void FoldCorners(const std::array<int, 3>& t, Vec2 uv[3], Vec3 xyz[3], Vec3 normals[3]) const;
  /// Live triangle count.
  int TriangleCount() const;
  /// The corner of triangle t that holds node v, or -1.
  int CornerOf(int t, int v) const;
  /// Triangles incident to node v (walks the adjacency around it).
  std::vector<int> Ring(int v) const;
  /// Whether nodes a and b share an edge; if so its kind into *edge_kind (from the first
  /// triangle of Ring(a) that holds b). Allocates nothing.
  bool EdgeKindOf(int a, int b, EdgeKind* edge_kind) const;
  /// Nodes adjacent to node v.
  std::vector<int> Neighbours(int v) const;
  /// Ring(v) into *ring and Neighbours(v) into *neighbours (same orders), from one walk, into
  /// the caller's vectors (their capacity is reused).
  void Fan(int v, std::vector<int>* ring, std::vector<int>* neighbours) const;
};

/// Builds the working mesh from domain nodes plus extra interior nodes and their triangulation.
/// `constrained[t][i]` marks boundary edges; `splittable(a, b)` says which are pole edges.
void InitWorkMesh(const std::vector<std::array<int, 3>>& triangles,
                  const std::vector<std::array<bool, 3>>& constrained,
                  const std::vector<std::array<int, 2>>& splittable_segments, WorkMesh* mesh);

/// A new triangle of a cavity replacement.
using Tri = std::array<int, 3>;

/// Replaces the triangles `old_tris` (a connected cavity) by `new_tris`, which must cover the
/// same region: edges on the cavity's border keep their neighbours and kinds; edges inside the
/// new set are free. Returns the ids of the new triangles (reusing the old slots first).
std::vector<int> ReplaceCavity(WorkMesh* mesh, const std::vector<int>& old_tris,
                               const std::vector<Tri>& new_tris);

/// The triangles a split of triangle t at node n makes (n not yet linked).
std::vector<Tri> SplitTriangleTris(const WorkMesh& mesh, int t, int n);
/// The cavity and new triangles of splitting the edge opposite corner i of t at node n.
void SplitEdgeTris(const WorkMesh& mesh, int t, int i, int n, std::vector<int>* cavity,
                   std::vector<Tri>* tris);
/// The two triangles that replace t and its neighbour across edge i when that edge is flipped.
/// False when there is no neighbour.
bool FlipTris(const WorkMesh& mesh, int t, int i, std::vector<int>* cavity, std::vector<Tri>* tris);
/// For `child`, a new triangle of a cavity replacement with node n at one corner: flipping its
/// outer edge (the one without n, on the border of `cavity`) with the triangle w beyond it.
/// Gives w and the two triangles that replace child and w. False when that edge is not free or
/// w is missing or already in the cavity.
bool FlipOuterEdgeTris(const WorkMesh& mesh, const std::vector<int>& cavity, const Tri& child,
                       int n, int* w, Tri out[2]);
/// The triangles around v after collapsing v into its neighbour w (the two triangles on the
/// edge v-w disappear), from `ring` = Ring(v).
void CollapseTris(const WorkMesh& mesh, int v, int w, const std::vector<int>& ring,
                  std::vector<Tri>* tris);
/// The triangles around any of `nodes`, each once, in order of first appearance.
std::vector<int> RingsOf(const WorkMesh& mesh, const std::vector<int>& nodes);
/// For moving the nodes `movers` one after another (fixed ones stay put), per triangle of
/// `tris`: the index in `movers` of the last move among its corners, -1 for none. After that
/// move the triangle no longer changes.
std::vector<int> LastMoves(const WorkMesh& mesh, const std::vector<int>& movers,
                           const std::vector<int>& tris);

/// Rebuilds the triangles around pole node p so that each fan triangle (one pole corner) gets a
/// pole node of its own, under the middle of its ring edge. Adds the new pole nodes (returned in
/// `new_nodes`; the caller drops them when it rejects the change); `shift` is the largest move
/// along the pole edge. False when p's neighbourhood is not a simple pole fan.
bool PoleFanTris(WorkMesh* mesh, int p, std::vector<int>* cavity, std::vector<Tri>* tris,
                 std::vector<int>* new_nodes, double* shift);

}  // namespace rdmesh
