#pragma once

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rdmesh/context.h"
#include "rdmesh/mesh.h"
#include "rdmesh/model_info.h"
#include "rdmesh/options.h"
#include "rdmesh/status.h"

namespace rdmesh {

class Model;  // opaque: the loaded B-rep (engine/src/model/model.h)

/// Loads a model from a file; the format follows the extension (.step/.stp, .iges/.igs, .brep).
/// kNotFound, kParseError (with the file name and the reason) or kEmptyModel on failure.
/// Thread-safe (OCCT's readers are serialised internally).
Result<std::shared_ptr<const Model>> LoadModel(const std::string& path, Context* context = nullptr);

/// Loads a model from bytes in memory. `name` is used in messages and ModelInfo.
Result<std::shared_ptr<const Model>> LoadModelFromBytes(const std::string& bytes,
                                                        ModelFormat format, const std::string& name,
                                                        Context* context = nullptr);

/// Summary of a loaded model.
ModelInfo GetModelInfo(const Model& model);

/// Loads OCCT's document framework (names, colours and assembly trees: loads that keep the
/// document, .glb and .obj output, the model store) into this process now, where the program was
/// linked without it (the rdmesh CLI): processes forked afterwards inherit it instead of each
/// loading it again (rdmesh batch). Ok at once where it is built in; else its loading error.
Status LoadDocumentFramework();

/// Meshes a model. Faces that fail are reported in MeshResult::faces and the rest still mesh;
/// the Status is not ok only for bad options, cancellation or a deadline.
/// Thread-safe: one Model may be meshed by several calls at once.
Result<MeshResult> MeshModel(const Model& model, const MeshOptions& options,
                             Context* context = nullptr);

/// Levels of detail (`rdmesh mesh --lod`, MeshRequest.lod_deviation_rel): at most this many.
inline constexpr int kMaxLevels = 8;

/// The levels of a levels-of-detail run from relative deviations (fractions of the bbox diagonal,
/// as MeshOptions::max_deviation_rel), in any order: sorted coarsest first (level 0 = the largest
/// deviation). kInvalidArgument when there are none, more than kMaxLevels, two equal ones, one
/// out of max_deviation_rel's range or > 0 smaller than 1e-7, or when `options` asks for an
/// absolute max_deviation, sets max_deviation_rel or asks for a max_triangles budget (each level
/// is a relative deviation). The one check of `rdmesh mesh --lod` and of lod_deviation_rel.
Result<std::vector<double>> ResolveLevels(std::vector<double> levels_rel,
                                          const MeshOptions& options);

/// One level's options: `options` with max_deviation 0 and max_deviation_rel = `level_rel`. The
/// level's mesh is the mesh of a single MeshModel run with these options, bit for bit.
MeshOptions LevelOptions(const MeshOptions& options, double level_rel);

/// What MeshModelLevels reports, from the calling thread, one level after the other.
struct LevelCallbacks {
  /// Before level `level` starts (its faces then reach the Context's face callback).
  std::function<void(int level)> started;
  /// Level `level`'s result, as MeshModel returns it. A non-ok Status stops the run with it.
  std::function<Status(int level, MeshResult result)> done;
};

/// Meshes one loaded model once per level, coarsest first: level i is
/// MeshModel(model, LevelOptions(options, levels_rel[i]), context). `levels_rel` as
/// ResolveLevels returns it. The context's deadline and cancellation cover the whole run
/// (options.timeout_seconds counts from the first level). Returns the first error (of a run or
/// of `done`), or ok after the last level's `done`.
Status MeshModelLevels(const Model& model, const MeshOptions& options,
                       const std::vector<double>& levels_rel, Context* context,
                       const LevelCallbacks& callbacks);

/// How WriteMesh writes; every field has a usable default.
struct WriteOptions {
  /// .msh: write each node's curve parameter t (edge nodes) or surface (u, v) (face-interior
  /// nodes) in its $Nodes block (MSH "parametric" nodes). Off by default: Gmsh reads both, but
  /// meshio 5 cannot read parametric nodes.
  bool msh_parametric = false;
  /// .msh, .obj and .glb: also write every B-rep edge (MeshResult::edges, degenerate ones left
  /// out) as line elements along its shared edge grid (.glb: LINES primitives with _EDGE_ID).
  /// The other formats ignore it.
  bool edges = true;
  /// .glb: compress it (EXT_meshopt_compression with KHR_mesh_quantization, docs/GLB.md):
  /// positions rounded to a grid that moves no vertex farther than kCompressRoundingShare of
  /// MeshSummary::requested_deviation (a mesh made with MeshOptions::compress keeps its
  /// deviation; none requested: no rounding), octahedral normals, vertex and index order
  /// optimised for the GPU, the ids and the edge table compressed too. The other formats ignore
  /// it.
  bool compress = false;
};

/// Writes the assembled mesh; the extension picks the format: .msh (MSH 4.1 ASCII), .stl
/// (binary), .obj, .ply, .vtu, .glb. A result whose `edges` is empty while its mesh has triangles
/// (one rebuilt from elsewhere, such as a remote run) gets them from BuildEdgeLines at the
/// default sharp angle.
Status WriteMesh(const Model& model, const MeshResult& result, const std::string& path,
                 const WriteOptions& options = {});

/// The edge polylines of an assembled mesh (MeshResult::edges): one EdgeLine per B-rep edge that
/// bounds a face with triangles in `mesh` (but one whose B-rep OCCT fails to query, or whose
/// vertices have no node at all), in edge id order, built from the mesh's node
/// classification (node_dim, node_entity, node_param), so a mesh rebuilt from a remote run gets
/// the same lines. An edge is sharp when its dihedral angle (EdgeLine::dihedral: the
/// largest over its nodes) exceeds `sharp_angle` (degrees). The edges are built on up to
/// `threads` threads (0: all cores); the lines do not depend on it. kInternal when the mesh lacks
/// its node classification.
Result<std::vector<EdgeLine>> BuildEdgeLines(const Model& model, const Mesh& mesh,
                                             double sharp_angle = kDefaultSharpEdgeAngle,
                                             int threads = 0);

/// The file extensions WriteMesh understands, with the dot.
std::vector<std::string> SupportedOutputFormats();

}  // namespace rdmesh
