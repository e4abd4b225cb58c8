#pragma once
// The domain of one face in its (u,v) parameter space: the boundary loops (outer loop, holes,
// both sides of a seam, degenerate pole edges) built from the shared edge grids through the
// face's pcurves, and a scale that makes the domain roughly isometric for 2D tests.

#include <TopoDS_Face.hxx>
#include <map>
#include <string>
#include <vector>

#include "boundary/edge_grids.h"
#include "boundary/node_ref.h"
#include "boundary/pcurves.h"
#include "core/geom.h"
#include "geometry/singular_lines.h"
#include "geometry/surface.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Model;

/// Boundary of a face in (u,v). Nodes are the boundary nodes; segments join them with the face
/// on their left for a FORWARD face (orientation is not relied on by the triangulation). A
/// vertex where two loops (or one loop twice) touch at the same (u,v), up to the slack of pcurve
/// ends that meet, is one node; two segments of different edges that lie on each other between
/// the same two nodes in opposite directions (a pinch: the loops touch along them) are left out.
struct FaceDomain {
  std::vector<Vec2> uv;      ///< per node: surface parameters
  std::vector<Vec3> xyz;     ///< per node: world point (shared bit-identically with neighbours)
  std::vector<NodeRef> ref;  ///< per node: B-rep classification
  std::vector<std::array<int, 2>> segments;  ///< node index pairs
  std::vector<bool> segment_splittable;      ///< degenerate (pole) segments may be split
  /// Per segment: the edge id it comes from (0 for a bridge over a gap between pcurve ends) and
  /// the index k of the edge grid segment [t[k], t[k+1]] it stands for.
  std::vector<int> segment_edge, segment_grid_index;
  /// Segments of loop k are [loop_begin[k], loop_begin[k + 1]), the last up to segments.size().
  std::vector<int> loop_begin;
  /// Singular lines inside the face (AddSingularLines): node index pairs, constraints of the
  /// triangulation with the face on both sides; their nodes come after the loops' nodes.
  std::vector<std::array<int, 2>> line_segments;
  double scale_u = 1, scale_v = 1;                ///< multiply u, v by these for isotropic 2D tests
  double umin = 0, umax = 0, vmin = 0, vmax = 0;  ///< bounds of the boundary nodes
};

/// Builds the domain of face `face_id` (its FORWARD orientation) from the edge grids (indexed
/// by edge id - 1). Consecutive pcurves are joined across gaps that the vertex tolerance allows
/// and across whole periods of a periodic surface. An edge grid point whose pcurve (u,v) misses
/// it on the surface (a loose pcurve, within a large edge tolerance) takes the nearby (u,v) where
/// the surface passes through it; an edge whose pcurve misses it by more than half its length
/// takes at every grid point the (u,v) where the surface passes through the point, searched over
/// the whole surface. A loop that runs over more than one period, the rest made of degenerate
/// edges, is taken without them when it closes so over one period. Fails with a reason that names
/// the edges for bad pcurves and loops that do not close.
Status BuildFaceDomain(const Model& model, const FacePcurves& pcurves, int face_id,
                       const std::vector<EdgeGrid>& grids, Surface& surface, FaceDomain* domain);

/// A vertex node's (u,v) is a pcurve's end and its point the vertex's, which the B-rep lets lie
/// as far from that end as the vertex's tolerance. Moves each vertex node whose nearest surface
/// point lies farther along the surface from its pcurve end than kPcurveMiss (1%) of its shorter
/// boundary segment to that point's (u,v), as interior grid points are moved where their pcurve
/// misses them; undoes them all where that makes boundary segments at a moved node conflict
/// (FindConflicts). Returns how many nodes moved.
int MoveVertexNodesToSurface(Surface& surface, FaceDomain* domain);

/// How far the domain's nodes (points of the edges' 3D curves, shared with the neighbouring
/// faces) lie off the surface at their (u,v): the largest |(xyz - S(uv)) . N(uv)|. The B-rep lets
/// it reach the edge and vertex tolerances; the mesh's triangles along such an edge lean from its
/// points to the surface, so the face cannot be meshed much closer than this. `moved`, empty or
/// one per node: how far the run moved the node off its curve (off-surface runs), taken off its
/// distance, so that what remains is the B-rep's.
double BoundaryGap(const FaceDomain& domain, Surface& surface,
                   const std::vector<double>& moved = {});

/// How far the domain's nodes lie off the face where their (u,v) runs past the surface's own
/// range (IntoSurfaceRange): the largest |xyz - S(uv moved into the range)|, 0 where none does.
/// There OCCT extends the surface, so BoundaryGap sees the extension, while the face ends at the
/// range. `domain` in the face's own (u,v) (not its B-spline conversion's); `moved` as
/// BoundaryGap's.
double BoundaryGapPastSurface(const TopoDS_Face& face, const FaceDomain& domain,
                              const std::vector<double>& moved = {});

/// How far the face's trim (its pcurves on the surface) lies from its edges' 3D curves, which
/// the mesh's boundary follows (they are shared with the neighbours): the largest distance from
/// a point of a pcurve's image to the 3D curve, at 33 points of each edge whose tolerance is
/// above `above` (the others' curves agree within it). Seen from the surface, the mesh misses the
/// face by this much along its boundary.
double EdgeTrimGap(const TopoDS_Face& face, double above);

/// How far the chords of the domain's edge segments (not bridges) lie off the surface at their
/// middles, along the normal: the largest |(S(mid uv) - mid xyz) . N(mid uv)|. Face refinement
/// cannot change them; the edge grids set them (and keep them no finer than the edge tolerance).
double BoundaryChordHeight(const FaceDomain& domain, Surface& surface);

/// A defect of a domain that the constrained triangulation cannot take: segments `a` and `b`
/// cross, touch or overlap in (u,v), or (b = -1) segment `a` belongs to a loop that encloses no
/// area (fewer than three nodes, or all on one line).
struct DomainConflict {
  int a = 0, b = -1;
};

/// All conflicts of the domain's boundary segments, in scaled (u,v). Most come from edge grids
/// too coarse for the face (a chord that cuts across a nearby loop); splitting the edge grid
/// segments involved removes them. When `context` (may be null) asks to stop, returns early with
/// the conflicts found so far.
std::vector<DomainConflict> FindConflicts(const FaceDomain& domain,
                                          const Context* context = nullptr);

/// A sentence that names the edges of the first conflict, for failure reasons.
std::string DescribeConflict(const FaceDomain& domain, const DomainConflict& conflict);

/// Interior seed points for curved faces: a coarse (u,v) grid, spaced by how far the surface
/// normal turns, so that no starting triangle spans more than ~45 degrees of the surface. Grid
/// lines are even along a parameter unless the turn is concentrated in part of its range (a blunt
/// nose on a long body, a tight blend along one side of a patch); then they split the turn into
/// even parts, so that the pole of such a nose gets a ring of seeds at one distance instead of
/// fans across the whole nose, and the blend gets lines of its own.
std::vector<Vec2> SeedPoints(const FaceDomain& domain, Surface& surface);

/// Adds the parts of `lines` (the face's singular lines, FindSingularLines) that run inside the
/// domain between two of its boundary nodes as line segments, through kLinePieces - 1 nodes of
/// their own at the first end's point (the line is one point in 3D). A line that a boundary
/// segment crosses between nodes (its edges were not pinned there: PinSingularLines) is left
/// out, and the face is meshed as if it had none. Returns how many parts were added.
int AddSingularLines(const std::vector<SingularLine>& lines, FaceDomain* domain);

/// True when p lies inside the domain (even-odd rule over all boundary segments).
bool InsideDomain(const FaceDomain& domain, Vec2 p);

}  // namespace rdmesh
