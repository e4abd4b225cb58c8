#pragma once
// Conversion between the engine's types and the rdmesh.v1 proto messages. server/ is the only
// place that does this; the remote CLI client reuses these functions.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rdmesh/context.h"
#include "rdmesh/engine.h"
#include "rdmesh/mesh.h"
#include "rdmesh/options.h"
#include "rdmesh/status.h"
#include "rdmesh/v1/rdmesh.pb.h"

namespace rdmesh::server {

namespace pb = ::rdmesh::v1;

/// Largest serialized size of one FaceMesh event, in bytes. Faces larger than this are split.
inline constexpr std::size_t kMaxFaceMessageBytes = 1u << 20;

/// Engine options from a request. Unset fields keep the engine's defaults. kInvalidArgument with
/// a readable message for values no run accepts (NaN, infinite or negative lengths, negative
/// counts); the engine's ValidateOptions then checks ranges and combinations.
Result<MeshOptions> FromProto(const pb::MeshOptions& in);
/// The request form of engine options (max_deviation_rel is always set).
pb::MeshOptions ToProto(const MeshOptions& in);

/// Model description; `model_id`, `file_bytes`, `cached` and `load_seconds` are the caller's.
pb::ModelInfo ToProto(const ModelInfo& in);
ModelInfo FromProto(const pb::ModelInfo& in);

ModelFormat FromProto(pb::ModelFormat format);
pb::ModelFormat ToProto(ModelFormat format);
/// The format a file name's extension names (.step/.stp, .iges/.igs, .brep/.brp), else kAuto.
ModelFormat FormatFromName(const std::string& name);

pb::FaceStatus ToProto(FaceStatus status);
FaceStatus FromProto(pb::FaceStatus status);
pb::Stage ToProto(Progress::Stage stage);
SurfaceType SurfaceTypeFromName(const std::string& name);

/// Run totals; the server fills total_seconds and face_messages itself.
pb::Summary ToProto(const MeshSummary& in);
MeshSummary FromProto(const pb::Summary& in);

/// Splits one face into FaceMesh events whose serialized size is at most `max_bytes` each
/// (at least one event, even for a face without nodes). uv and normals are included when asked
/// for and present.
std::vector<pb::FaceMesh> SplitFaceMesh(const FaceMesh& face, bool with_uv, bool with_normals,
                                        std::size_t max_bytes = kMaxFaceMessageBytes);

/// Rebuilds faces from FaceMesh events (the inverse of SplitFaceMesh). Parts of one face must
/// arrive in chunk order; parts of different faces may interleave.
class FaceMeshJoiner {
 public:
  /// Adds one part. kInvalidArgument when the part does not fit what came before.
  Status Add(const pb::FaceMesh& part);
  /// True when every started face has all its parts.
  bool complete() const;
  /// The finished faces, in face id order (faces never received are absent).
  std::vector<FaceMesh> TakeFaces();

 private:
  struct Pending {
    FaceMesh face;
    int next_chunk = 0;
    int chunk_count = 0;
  };
  std::vector<Pending> pending_;  // index = face_id - 1
};

}  // namespace rdmesh::server
