#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rdmesh {

/// Kind of a face's underlying surface (as OCCT's GeomAbs_SurfaceType).
enum class SurfaceType {
  kPlane,
  kCylinder,
  kCone,
  kSphere,
  kTorus,
  kBezier,
  kBSpline,
  kRevolution,
  kExtrusion,
  kOffset,
  kOther,
};
/// Stable lower-case name, e.g. "bspline".
const char* SurfaceTypeName(SurfaceType type);

/// Outcome of meshing one face.
enum class FaceStatus {
  kOk,       ///< meshed within the requested criteria
  kFailed,   ///< no triangles; `reason` says why
  kSkipped,  ///< not requested (face subset) or the run stopped first
};
const char* FaceStatusName(FaceStatus status);

/// The mesh of one B-rep face. Nodes are local to the face; boundary nodes also appear in the
/// neighbouring faces' meshes with the same `global_ids` entry and bit-identical `xyz`.
struct FaceMesh {
  int face_id = 0;  ///< 1..F, TopExp::MapShapes order of the whole shape
  SurfaceType surface_type = SurfaceType::kOther;
  FaceStatus status = FaceStatus::kSkipped;
  std::string reason;  ///< why the face failed or was skipped; empty when ok

  std::vector<double> xyz;          ///< 3 per node: x y z, model units, world frame
  std::vector<double> uv;           ///< 2 per node: u v, the face surface's own parameters
  std::vector<double> normals;      ///< 3 per node: unit outward normal of the face at the node
  std::vector<int32_t> triangles;   ///< 3 per triangle: 0-based node ids, counter-clockwise seen
                                    ///< from outside (right-handed with the outward normal)
  std::vector<int64_t> global_ids;  ///< 1 per node: 0-based node id in the assembled Mesh
  /// 1 per triangle: the refinement's estimated largest distance between the triangle and the
  /// exact surface (MeasureTriangle), model units; its maximum is `max_deviation`.
  std::vector<double> triangle_deviation;

  double max_deviation = 0.0;  ///< estimated largest mesh-surface distance, model units
  double area = 0.0;           ///< area of the triangles, model units^2
  double exact_area = 0.0;     ///< area of the B-rep face, model units^2
  double seconds = 0.0;        ///< wall time spent on this face
  /// MeshOptions::off_surface: how far the face's interior nodes lie off its surface, along the
  /// face's outward normal (negative: inward), model units; 0 on the surface. A face that bends
  /// one way in parts only moves there only: this is the offset where it moved.
  double offset = 0.0;
  /// MeshOptions::off_surface: why a face stayed on its surface (a plane, a saddle, or the
  /// offset mesh missed the deviation), or, for a face moved in parts only, where it moved
  /// ("moved where it bends one way (N of M grid points)..."); empty for a face moved whole.
  std::string offset_reason;

  int64_t triangle_count() const { return static_cast<int64_t>(triangles.size() / 3); }
  int64_t node_count() const { return static_cast<int64_t>(xyz.size() / 3); }
};

/// The whole model as one watertight triangle mesh: boundary nodes are shared between faces.
struct Mesh {
  std::vector<double> xyz;             ///< 3 per node, model units, world frame
  std::vector<int32_t> triangles;      ///< 3 per triangle, 0-based node ids, outward orientation
  std::vector<int32_t> triangle_face;  ///< 1 per triangle: the B-rep face id (1..F)
  /// 1 per triangle: its face's FaceMesh::triangle_deviation, model units (empty when the faces
  /// carry none, as a remote result whose stream did not ask for them).
  std::vector<double> triangle_deviation;
  /// Where each node lies on the B-rep: 0 = vertex, 1 = edge, 2 = face interior.
  std::vector<int8_t> node_dim;
  /// 1 per node: the id of that vertex (1..V), edge (1..E) or face (1..F).
  std::vector<int32_t> node_entity;
  /// 2 per node: the curve parameter t (edge nodes; second entry 0), or the surface (u, v) of a
  /// face-interior node; 0 0 for vertices.
  std::vector<double> node_param;

  int64_t triangle_count() const { return static_cast<int64_t>(triangles.size() / 3); }
  int64_t node_count() const { return static_cast<int64_t>(xyz.size() / 3); }
};

/// One B-rep edge of the assembled mesh as a polyline: its edge grid, which every face beside
/// the edge shares, so the polyline's nodes are boundary nodes of all those faces.
struct EdgeLine {
  int edge_id = 0;  ///< 1..E, TopExp::MapShapes order of the whole shape
  /// 0-based Mesh node ids in curve order (increasing curve parameter of the FORWARD edge): the
  /// start vertex's node, the edge nodes, the end vertex's node. A closed edge starts and ends
  /// at the same node; a degenerate edge may be a single node. No id repeats consecutively.
  std::vector<int32_t> nodes;
  std::vector<int32_t> faces;  ///< ids of the B-rep faces the edge bounds, ascending, each once
  bool seam = false;           ///< a face lies on both sides (the seam of a periodic surface)
  bool degenerate = false;     ///< no extent in 3D: a pole, or an edge shorter than its tolerance
  /// Sharp: the dihedral angle exceeds the sharp angle, or the edge is free (one face, no seam).
  bool sharp = false;
  /// Dihedral angle, degrees (0 = tangent, 90 = a box's edge): the largest, over the edge's
  /// nodes (its vertices and edge-grid nodes, at their curve parameters), of the angle between
  /// the faces' exact outward surface normals there (the largest over pairs when more than two
  /// faces meet; nodes where a normal is singular are skipped). -1 when undefined: fewer than
  /// two faces, a seam, a degenerate edge, or a singular normal at every node.
  double dihedral = -1.0;
};

/// Dihedral angle (degrees) above which an edge counts as sharp.
inline constexpr double kDefaultSharpEdgeAngle = 30.0;

/// Totals and timings of a run.
struct MeshSummary {
  int64_t triangles = 0;
  int64_t nodes = 0;
  int faces_ok = 0;
  int faces_failed = 0;
  int faces_skipped = 0;
  double requested_deviation = 0.0;  ///< the absolute max deviation asked for (0 = none)
  double estimated_deviation = 0.0;  ///< the largest estimated deviation over all faces
  double mesh_area = 0.0;
  double exact_area = 0.0;
  double edge_seconds = 0.0;  ///< edge grid
  double face_seconds = 0.0;  ///< face interiors
  double seconds = 0.0;       ///< edge grid + faces + assembly (not model loading)
  int64_t edges = 0;          ///< B-rep edges discretised
  int64_t edge_segments = 0;  ///< segments of all edge grids
};

/// Everything a run produces.
struct MeshResult {
  std::vector<FaceMesh> faces;  ///< one per face id, in face id order (index = face_id - 1)
  Mesh mesh;                    ///< the assembled watertight mesh of the ok faces
  /// The B-rep edges of `mesh` as polylines (BuildEdgeLines), in edge id order.
  std::vector<EdgeLine> edges;
  MeshSummary summary;
};

}  // namespace rdmesh
