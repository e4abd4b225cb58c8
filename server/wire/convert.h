#pragma once
// Conversion between the engine's types and the rdmesh.v1 proto messages. server/wire/ is the
// only place that does this; the daemon, the worker and the remote CLI client use it.

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

/// Engine options from a request, as they are: unset fields keep the engine's defaults (an unset
/// max_deviation_rel stays unset). The engine's ValidateOptions checks them.
MeshOptions FromProto(const pb::MeshOptions& in);
/// The request form of engine options; max_deviation_rel only when set.
pb::MeshOptions ToProto(const MeshOptions& in);

/// Model description; `model_id`, `file_bytes`, `cached` and `load_seconds` are the caller's.
pb::ModelInfo ToProto(const ModelInfo& in);
ModelInfo FromProto(const pb::ModelInfo& in);

ModelFormat FromProto(pb::ModelFormat format);
pb::ModelFormat ToProto(ModelFormat format);

pb::FaceStatus ToProto(FaceStatus status);
FaceStatus FromProto(pb::FaceStatus status);
pb::Stage ToProto(Progress::Stage stage);
Progress::Stage FromProto(pb::Stage stage);
SurfaceType SurfaceTypeFromName(const std::string& name);

/// Run totals; the server fills total_seconds and face_messages itself.
pb::Summary ToProto(const MeshSummary& in);
MeshSummary FromProto(const pb::Summary& in);

/// Splits one face into FaceMesh events whose serialized size (inside a MeshEvent) is at most
/// `max_bytes` each; at least one event, even for a face without nodes. uv and normals are
/// included when asked for and present, and so is triangle_deviation with `with_deviation`.
/// Global ids are not: see SplitFaceNodeIds.
std::vector<pb::FaceMesh> SplitFaceMesh(const FaceMesh& face, bool with_uv, bool with_normals,
                                        std::size_t max_bytes = kMaxFaceMessageBytes,
                                        bool with_deviation = false);

/// Splits a welded face's global ids into FaceNodeIds events of at most `max_bytes` each. With
/// `topology` (the assembled mesh), each node's node_dim, node_entity and node_param are added.
/// No events for a face without global ids.
std::vector<pb::FaceNodeIds> SplitFaceNodeIds(const FaceMesh& face, const Mesh* topology,
                                              std::size_t max_bytes = kMaxFaceMessageBytes);

/// Splits an edge line into EdgePolyline events of at most `max_bytes` each (at least one).
std::vector<pb::EdgePolyline> SplitEdgeLine(const EdgeLine& line,
                                            std::size_t max_bytes = kMaxFaceMessageBytes);

/// Rebuilds an engine MeshResult from the events of a Mesh stream: the inverse of the three
/// functions above plus the summary (MeshResult::edges from the EdgePolyline events, empty when
/// the stream carried none). Parts of one face must arrive in chunk order; parts of
/// different faces may interleave.
class MeshResultBuilder {
 public:
  /// Adds one event. kInvalidArgument when it does not fit what came before.
  Status Add(const pb::MeshEvent& event);
  bool has_started() const { return has_started_; }
  bool has_summary() const { return has_summary_; }
  const pb::Started& started() const { return started_; }

  /// The result: one FaceMesh per face id 1..faces in face id order (faces never sent are
  /// kSkipped), the assembled mesh rebuilt through the global ids as the engine assembles it
  /// (node classification only when the stream carried it) and the summary. kInvalidArgument
  /// when the stream is incomplete (no Started or Summary, a face missing parts or ids).
  Result<MeshResult> Finish();

 private:
  struct PendingFace {
    FaceMesh face;
    int next_chunk = 0;
    int chunk_count = 0;
    int next_ids_chunk = 0;
    int ids_chunk_count = 0;
    std::vector<int32_t> node_dim;     // 1 per node, when sent
    std::vector<int32_t> node_entity;  // 1 per node, when sent
    std::vector<double> node_param;    // 2 per node, when sent
  };
  Status AddFace(const pb::FaceMesh& part);
  Status AddNodeIds(const pb::FaceNodeIds& part);
  Status AddEdge(const pb::EdgePolyline& part);
  PendingFace& Slot(int face_id);

  std::vector<PendingFace> faces_;  // index = face_id - 1
  std::vector<EdgeLine> edges_;     // edge id order
  int edge_parts_left_ = 0;         // parts of edges_.back() still to come
  pb::Started started_;
  pb::Summary summary_;
  bool has_started_ = false;
  bool has_summary_ = false;
};

}  // namespace rdmesh::server
