#pragma once
// One face, start to end: evaluator, (u,v) domain, constrained triangulation, refinement, and
// the FaceMesh it hands to assembly. Faces are independent once the edge grids exist.

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "boundary/edge_grids.h"
#include "boundary/node_ref.h"
#include "boundary/pcurves.h"
#include "face/measure.h"
#include "geometry/singular_lines.h"
#include "rdmesh/context.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Model;
class Surface;
struct FaceDomain;

/// Face evaluators made once and lent to several runs on one model (the levels of detail):
/// MakeFaceSurface the first time a run asks for a face, a view of that same evaluator after.
/// What an evaluator returns does not depend on what it evaluated before (its caches are exact),
/// so a run meshes the same with a fresh or a lent one. One slot per face and kind (exact, or
/// converted with --nurbs): the tasks of a run never ask for one face at once (one task per face).
class FaceSurfaces {
 public:
  explicit FaceSurfaces(int face_count);
  ~FaceSurfaces();
  /// An evaluator of face `face_id` for one task; valid while this object lives.
  std::unique_ptr<Surface> Lend(const Model& model, const FacePcurves& pcurves, int face_id,
                                bool nurbs);

 private:
  std::vector<std::unique_ptr<Surface>> exact_, nurbs_;
};

struct FaceJob {
  FaceCriteria criteria;
  int64_t max_triangles = 0;  ///< per-face safety cap
  bool nurbs = false;
  bool improve = true;       ///< run the collapse / flip / smooth loop after refinement
  bool off_surface = false;  ///< MeshOptions::off_surface
  /// With off_surface: per face id - 1, which way it bends (FaceBendSides), and the vertices
  /// moved with their edges (MoveEdgeGrids), which the face's domain takes.
  const std::vector<int8_t>* bend_sides = nullptr;
  const std::map<int, Vec3>* moved_vertices = nullptr;
  /// Per face id - 1, its singular lines (FaceSingularLines), whose crossings with its edges
  /// are in the grids (PinSingularLines); null = none.
  const std::vector<std::vector<SingularLine>>* singular_lines = nullptr;
  /// Evaluators shared with other runs on the model (levels of detail); null = made per face.
  FaceSurfaces* surfaces = nullptr;
};

/// How far a face's B-rep keeps its boundary from its surface: its edges off the surface
/// (`edges`), its pcurves' images off its edges' 3D curves (`trim`, measured where the edges'
/// tolerance is coarser than the request), and its edges' largest tolerance.
struct BrepGaps {
  double edges = 0, trim = 0, tolerance = 0;
  double Largest() const { return std::max(edges, trim); }
};

/// A face's reason when the B-rep keeps it from the requested `deviation`: how far its edges lie
/// off its surface, or its pcurves from its edges' curves where that is more, and its edges'
/// tolerance. What the B-rep explains: a triangle measured from corners that far off, or beside
/// chords as coarse as the edges' tolerance, can read up to the request plus the larger of the
/// two. Where refinement left the face further over (`missed`, its largest deviation; 0 when it
/// met the criteria), the reason says so as well.
std::string BrepReason(double deviation, const BrepGaps& gaps, double missed);

/// A face's reason when refinement left `over` triangles over the criteria, `folds` of them
/// folded after kFoldRun splits in a row each handed the fold on (RefineStats::stuck_folds).
std::string StuckFoldReason(int64_t folds, int64_t over);

/// Meshes face `face_id` of the model. Never throws: OCCT failures and bad loops come back as a
/// kFailed FaceMesh with the reason. Boundary nodes keep their B-rep classification in `refs`
/// (one per FaceMesh node) for assembly.
FaceMesh MeshFace(const Model& model, const FacePcurves& pcurves, int face_id,
                  const std::vector<EdgeGrid>& grids, const FaceJob& job, Context* context,
                  std::vector<NodeRef>* refs);

/// What a representative's copies match their boundary against (PlaceCopy): the
/// representative's domain, built once for all its copies. Never throws: a failure comes back as
/// the copies' reason ("instance boundary differs", or the OCCT exception's).
Result<FaceDomain> CopySource(const Model& model, const FacePcurves& pcurves, int rep_id,
                              const std::vector<EdgeGrid>& grids);

/// The mesh of an instanced copy: the representative's interior nodes moved by the placement,
/// the boundary rebuilt exactly from the copy's own edges. `source` is CopySource of the
/// representative.
FaceMesh PlaceCopy(const Model& model, const FacePcurves& pcurves, int face_id, const FaceMesh& rep,
                   const std::vector<NodeRef>& rep_refs, const Result<FaceDomain>& source,
                   const std::vector<EdgeGrid>& grids, std::vector<NodeRef>* refs);

}  // namespace rdmesh
