#include "wire/convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace rdmesh::server {
namespace {

TEST(ConvertOptionsTest, UnsetFieldsKeepTheEngineDefaults) {
  const MeshOptions options = FromProto(pb::MeshOptions());
  const MeshOptions defaults;
  EXPECT_EQ(options.max_deviation, defaults.max_deviation);
  EXPECT_EQ(options.max_deviation_rel, defaults.max_deviation_rel);
  EXPECT_FALSE(options.max_deviation_rel.has_value());  // unset stays unset
  EXPECT_EQ(MaxDeviationRel(options), kDefaultMaxDeviationRel);
  EXPECT_EQ(options.max_triangles, 0);
  EXPECT_FALSE(options.nurbs);
  EXPECT_TRUE(options.face_ids.empty());
  EXPECT_FALSE(ToProto(options).has_max_deviation_rel());
}

TEST(ConvertOptionsTest, ExplicitZeroRelativeDeviationIsKept) {
  pb::MeshOptions in;
  in.set_max_deviation_rel(0.0);
  in.set_rd_tolerance(1e-3);
  const MeshOptions options = FromProto(in);
  EXPECT_EQ(options.max_deviation_rel, 0.0);
  EXPECT_EQ(options.rd_tolerance, 1e-3);
  EXPECT_TRUE(ValidateOptions(options).ok());
}

TEST(ConvertOptionsTest, RoundTrip) {
  MeshOptions in;
  in.max_deviation = 0.05;
  in.max_deviation_rel = 2e-4;
  in.rd_tolerance = 1e-3;
  in.max_triangles = 12345;
  in.min_edge_length = 0.01;
  in.max_edge_length = 3.5;
  in.nurbs = true;
  in.threads = 3;
  in.face_ids = {4, 1, 9};
  in.timeout_seconds = 7.5;
  in.sharp_edge_angle = 45.0;
  in.compress = true;
  const MeshOptions out = FromProto(ToProto(in));
  EXPECT_EQ(out.max_deviation, in.max_deviation);
  EXPECT_EQ(out.max_deviation_rel, in.max_deviation_rel);
  EXPECT_EQ(out.rd_tolerance, in.rd_tolerance);
  EXPECT_EQ(out.max_triangles, in.max_triangles);
  EXPECT_EQ(out.min_edge_length, in.min_edge_length);
  EXPECT_EQ(out.max_edge_length, in.max_edge_length);
  EXPECT_EQ(out.nurbs, in.nurbs);
  EXPECT_EQ(out.threads, in.threads);
  EXPECT_EQ(out.face_ids, in.face_ids);
  EXPECT_EQ(out.timeout_seconds, in.timeout_seconds);
  EXPECT_EQ(out.sharp_edge_angle, in.sharp_edge_angle);
  EXPECT_EQ(out.compress, in.compress);
  EXPECT_EQ(FromProto(pb::MeshOptions()).sharp_edge_angle, kDefaultSharpEdgeAngle);
  EXPECT_FALSE(FromProto(pb::MeshOptions()).compress);
}

// FromProto converts; the engine's ValidateOptions, the one check of options, refuses what no
// run accepts and names the field.
TEST(ConvertOptionsTest, ValuesNoRunAcceptsAreRefusedByTheEngine) {
  const auto rejects = [](auto set, const std::string& field) {
    pb::MeshOptions in;
    set(&in);
    const Status valid = ValidateOptions(FromProto(in));
    EXPECT_FALSE(valid.ok()) << field;
    EXPECT_EQ(valid.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(valid.message().find(field), std::string::npos) << valid.message();
  };
  rejects([](pb::MeshOptions* o) { o->set_max_deviation(-1); }, "max_deviation");
  rejects([](pb::MeshOptions* o) { o->set_max_deviation(std::nan("")); }, "max_deviation");
  rejects([](pb::MeshOptions* o) { o->set_max_deviation_rel(-0.1); }, "max_deviation_rel");
  rejects(
      [](pb::MeshOptions* o) { o->set_max_edge_length(std::numeric_limits<double>::infinity()); },
      "max_edge_length");
  rejects([](pb::MeshOptions* o) { o->set_min_edge_length(-2); }, "min_edge_length");
  rejects([](pb::MeshOptions* o) { o->set_rd_tolerance(-1e-3); }, "rd_tolerance");
  rejects([](pb::MeshOptions* o) { o->set_max_triangles(-5); }, "max_triangles");
  rejects([](pb::MeshOptions* o) { o->set_threads(-1); }, "threads");
  rejects([](pb::MeshOptions* o) { o->add_face_ids(0); }, "face_ids");
  rejects(
      [](pb::MeshOptions* o) {
        o->set_compress(true);
        o->set_max_triangles(100);
      },
      "compress");
  rejects(
      [](pb::MeshOptions* o) {
        o->set_compress(true);
        o->set_max_deviation_rel(0);
        o->set_rd_tolerance(0.01);
      },
      "compress");
}

TEST(ConvertModelInfoTest, RoundTrip) {
  ModelInfo in;
  in.name = "bracket.step";
  in.format = "step";
  in.length_unit = "inch";
  in.unit_scale_mm = 25.4;
  in.faces = 42;
  in.edges = 100;
  in.vertices = 60;
  in.solids = 2;
  in.shells = 2;
  in.unique_faces = 21;
  in.instances = 2;
  in.bbox = {-1, -2, -3, 4, 5, 6};
  in.diagonal = 12.4;
  in.surface_types = {{"plane", 30}, {"cylinder", 12}};
  in.part_names = {"base", "lid"};
  in.closed = true;
  const pb::ModelInfo message = ToProto(in);
  EXPECT_EQ(message.bbox_size(), 6);
  EXPECT_EQ(message.surface_types_size(), 2);
  const ModelInfo out = FromProto(message);
  EXPECT_EQ(out.name, in.name);
  EXPECT_EQ(out.length_unit, in.length_unit);
  EXPECT_EQ(out.unit_scale_mm, in.unit_scale_mm);
  EXPECT_EQ(out.faces, in.faces);
  EXPECT_EQ(out.edges, in.edges);
  EXPECT_EQ(out.unique_faces, in.unique_faces);
  EXPECT_EQ(out.bbox, in.bbox);
  EXPECT_EQ(out.surface_types, in.surface_types);
  EXPECT_EQ(out.part_names, in.part_names);
  EXPECT_TRUE(out.closed);
}

TEST(ConvertEnumsTest, FormatsStatusesAndStages) {
  for (ModelFormat f : {ModelFormat::kStep, ModelFormat::kIges, ModelFormat::kBrep}) {
    EXPECT_EQ(FromProto(ToProto(f)), f);
  }
  EXPECT_EQ(ToProto(ModelFormat::kAuto), pb::MODEL_FORMAT_UNSPECIFIED);
  for (FaceStatus s : {FaceStatus::kOk, FaceStatus::kFailed, FaceStatus::kSkipped}) {
    EXPECT_EQ(FromProto(ToProto(s)), s);
  }
  for (Progress::Stage stage :
       {Progress::Stage::kLoading, Progress::Stage::kEdges, Progress::Stage::kFaces,
        Progress::Stage::kAssembly, Progress::Stage::kDone}) {
    EXPECT_EQ(FromProto(ToProto(stage)), stage);
  }
  EXPECT_EQ(ToProto(Progress::Stage::kFaces), pb::STAGE_FACES);
  for (int t = 0; t <= static_cast<int>(SurfaceType::kOther); ++t) {
    const auto type = static_cast<SurfaceType>(t);
    EXPECT_EQ(SurfaceTypeFromName(SurfaceTypeName(type)), type);
  }
}

TEST(ConvertSummaryTest, RoundTrip) {
  MeshSummary in;
  in.triangles = 5'000'001;
  in.nodes = 2'500'003;
  in.faces_ok = 10;
  in.faces_failed = 1;
  in.faces_skipped = 2;
  in.requested_deviation = 0.01;
  in.estimated_deviation = 0.009;
  in.mesh_area = 99.5;
  in.exact_area = 100.0;
  in.edge_seconds = 0.5;
  in.face_seconds = 2.5;
  in.seconds = 3.25;
  in.edges = 30;
  in.edge_segments = 900;
  const MeshSummary out = FromProto(ToProto(in));
  EXPECT_EQ(out.triangles, in.triangles);
  EXPECT_EQ(out.nodes, in.nodes);
  EXPECT_EQ(out.faces_failed, in.faces_failed);
  EXPECT_EQ(out.faces_skipped, in.faces_skipped);
  EXPECT_EQ(out.estimated_deviation, in.estimated_deviation);
  EXPECT_EQ(out.seconds, in.seconds);
  EXPECT_EQ(out.edge_segments, in.edge_segments);
}

/// A face of `nodes` nodes on a strip, with every per-node array filled.
FaceMesh MakeFace(int id, int64_t nodes) {
  FaceMesh face;
  face.face_id = id;
  face.surface_type = SurfaceType::kBSpline;
  face.status = FaceStatus::kOk;
  std::mt19937 random(id);
  std::uniform_real_distribution<double> any(-1000.0, 1000.0);
  for (int64_t i = 0; i < nodes; ++i) {
    for (int k = 0; k < 3; ++k) face.xyz.push_back(any(random));
    for (int k = 0; k < 2; ++k) face.uv.push_back(any(random));
    for (int k = 0; k < 3; ++k) face.normals.push_back(any(random));
    face.global_ids.push_back(i);
  }
  for (int64_t i = 0; i + 2 < nodes; ++i) {
    face.triangles.insert(
        face.triangles.end(),
        {static_cast<int32_t>(i), static_cast<int32_t>(i + 1), static_cast<int32_t>(i + 2)});
    face.triangle_deviation.push_back(std::fabs(any(random)) / 4000.0);  // in [0, 0.25]
  }
  face.max_deviation = 0.25;
  face.area = 12.0;
  face.exact_area = 12.5;
  face.seconds = 0.75;
  return face;
}

/// A Started event for a model of `faces` faces.
pb::MeshEvent StartedEvent(int faces) {
  pb::MeshEvent event;
  event.mutable_started()->mutable_model()->set_faces(faces);
  return event;
}

pb::MeshEvent SummaryEvent(int64_t nodes, int64_t triangles) {
  MeshSummary summary;
  summary.nodes = nodes;
  summary.triangles = triangles;
  pb::MeshEvent event;
  *event.mutable_summary() = ToProto(summary);
  return event;
}

/// Sends `face` through SplitFaceMesh and SplitFaceNodeIds into `builder`.
void Stream(const FaceMesh& face, const Mesh* topology, MeshResultBuilder* builder,
            std::size_t max_bytes = kMaxFaceMessageBytes) {
  for (pb::FaceMesh& part : SplitFaceMesh(face, true, true, max_bytes, true)) {
    pb::MeshEvent event;
    *event.mutable_face() = std::move(part);
    ASSERT_TRUE(builder->Add(event).ok());
  }
  for (pb::FaceNodeIds& part : SplitFaceNodeIds(face, topology, max_bytes)) {
    pb::MeshEvent event;
    *event.mutable_node_ids() = std::move(part);
    ASSERT_TRUE(builder->Add(event).ok());
  }
}

void ExpectSameFace(const FaceMesh& a, const FaceMesh& b) {
  EXPECT_EQ(a.face_id, b.face_id);
  EXPECT_EQ(a.surface_type, b.surface_type);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.reason, b.reason);
  EXPECT_EQ(a.xyz, b.xyz);
  EXPECT_EQ(a.uv, b.uv);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.global_ids, b.global_ids);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.triangle_deviation, b.triangle_deviation);
  EXPECT_EQ(a.max_deviation, b.max_deviation);
  EXPECT_EQ(a.area, b.area);
  EXPECT_EQ(a.exact_area, b.exact_area);
}

TEST(SplitFaceMeshTest, SmallFaceIsOneMessage) {
  const FaceMesh face = MakeFace(3, 100);
  const std::vector<pb::FaceMesh> parts = SplitFaceMesh(face, true, true);
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].chunk_count(), 1);
  EXPECT_EQ(parts[0].node_count(), 100);
  EXPECT_EQ(parts[0].triangle_count(), 98);
  EXPECT_EQ(parts[0].surface_type(), "bspline");
  EXPECT_EQ(SplitFaceNodeIds(face, nullptr).size(), 1u);
}

TEST(SplitFaceMeshTest, LargeFaceSplitsUnderOneMiBAndJoinsBack) {
  const FaceMesh face = MakeFace(1, 120'000);  // ~11 MB of arrays
  const std::vector<pb::FaceMesh> parts =
      SplitFaceMesh(face, true, true, kMaxFaceMessageBytes, true);
  ASSERT_GT(parts.size(), 5u);
  for (const pb::FaceMesh& part : parts) {
    pb::MeshEvent event;
    *event.mutable_face() = part;
    EXPECT_LE(event.ByteSizeLong(), kMaxFaceMessageBytes);
    if (part.chunk_index() + 1 < part.chunk_count()) {
      EXPECT_GT(event.ByteSizeLong(), kMaxFaceMessageBytes / 2);  // not wastefully small
    }
    EXPECT_EQ(part.chunk_count(), static_cast<int>(parts.size()));
  }
  // Every node is its own global node: a topology of 120k edge nodes.
  Mesh topology;
  topology.xyz = face.xyz;
  topology.node_dim.assign(face.node_count(), 1);
  topology.node_entity.assign(face.node_count(), 1'000'000);
  for (int64_t i = 0; i < face.node_count(); ++i) {
    topology.node_param.insert(topology.node_param.end(), {0.5 * i, 0.0});
  }
  const std::vector<pb::FaceNodeIds> ids = SplitFaceNodeIds(face, &topology);
  ASSERT_GT(ids.size(), 1u);
  for (const pb::FaceNodeIds& part : ids) {
    pb::MeshEvent event;
    *event.mutable_node_ids() = part;
    EXPECT_LE(event.ByteSizeLong(), kMaxFaceMessageBytes);
  }

  MeshResultBuilder builder;
  ASSERT_TRUE(builder.Add(StartedEvent(1)).ok());
  Stream(face, &topology, &builder);
  ASSERT_TRUE(builder.Add(SummaryEvent(face.node_count(), face.triangle_count())).ok());
  Result<MeshResult> result = builder.Finish();
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  ASSERT_EQ(result->faces.size(), 1u);
  ExpectSameFace(result->faces[0], face);
  EXPECT_EQ(result->mesh.xyz, face.xyz);
  EXPECT_EQ(result->mesh.triangles, face.triangles);
  EXPECT_EQ(result->mesh.triangle_deviation, face.triangle_deviation);
  EXPECT_EQ(result->mesh.node_entity, topology.node_entity);
  EXPECT_EQ(result->mesh.node_param, topology.node_param);
}

TEST(SplitFaceMeshTest, OptionalArraysOnlyWhenAskedFor) {
  const FaceMesh face = MakeFace(2, 5000);
  const std::vector<pb::FaceMesh> lean = SplitFaceMesh(face, false, false, 16 * 1024);
  ASSERT_GT(lean.size(), 1u);
  for (const pb::FaceMesh& part : lean) {
    EXPECT_EQ(part.uv_size(), 0);
    EXPECT_EQ(part.normals_size(), 0);
    EXPECT_EQ(part.triangle_deviation_size(), 0);
    EXPECT_LE(part.ByteSizeLong(), 16u * 1024);
  }
  for (const pb::FaceNodeIds& part : SplitFaceNodeIds(face, nullptr, 16 * 1024)) {
    EXPECT_EQ(part.node_dim_size(), 0);
    EXPECT_EQ(part.node_param_size(), 0);
    EXPECT_LE(part.ByteSizeLong(), 16u * 1024);
  }
}

TEST(SplitFaceMeshTest, FailedFaceWithoutNodesIsOneMessageWithItsReason) {
  FaceMesh face;
  face.face_id = 12;
  face.status = FaceStatus::kFailed;
  face.reason = "pcurve missing on edge 31";
  const std::vector<pb::FaceMesh> parts = SplitFaceMesh(face, true, true);
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].status(), pb::FACE_STATUS_FAILED);
  EXPECT_EQ(parts[0].reason(), face.reason);
  EXPECT_EQ(parts[0].node_count(), 0);
  EXPECT_TRUE(SplitFaceNodeIds(face, nullptr).empty());
}

/// Two unit triangles welded along their shared edge, plus a collapsed triangle at a "pole".
std::vector<FaceMesh> TwoWeldedFaces() {
  FaceMesh a;
  a.face_id = 1;
  a.status = FaceStatus::kOk;
  a.xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  a.triangles = {0, 1, 2};
  a.global_ids = {0, 1, 2};
  FaceMesh b;
  b.face_id = 3;
  b.status = FaceStatus::kOk;
  b.xyz = {1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 1, 0};  // node 3 is node 1 again (a pole)
  b.triangles = {0, 1, 2, 1, 3, 2};              // the second collapses
  b.global_ids = {1, 3, 2, 3};
  return {a, b};
}

TEST(MeshResultBuilderTest, WeldsFacesThroughGlobalIdsAsTheEngineDoes) {
  const std::vector<FaceMesh> faces = TwoWeldedFaces();
  MeshResultBuilder builder;
  ASSERT_TRUE(builder.Add(StartedEvent(4)).ok());
  Stream(faces[1], nullptr, &builder);  // completion order, not face order
  Stream(faces[0], nullptr, &builder);
  ASSERT_TRUE(builder.Add(SummaryEvent(4, 2)).ok());
  Result<MeshResult> result = builder.Finish();
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  ASSERT_EQ(result->faces.size(), 4u);
  EXPECT_EQ(result->faces[1].status, FaceStatus::kSkipped);  // face 2 never sent
  EXPECT_EQ(result->faces[3].status, FaceStatus::kSkipped);
  EXPECT_EQ(result->mesh.xyz, (std::vector<double>{0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}));
  EXPECT_EQ(result->mesh.triangles, (std::vector<int32_t>{0, 1, 2, 1, 3, 2}));
  EXPECT_EQ(result->mesh.triangle_face, (std::vector<int32_t>{1, 3}));
  EXPECT_TRUE(result->mesh.node_dim.empty());  // no topology was asked for
  EXPECT_EQ(result->summary.nodes, 4);
}

TEST(MeshResultBuilderTest, RefusesIncompleteOrDisorderedStreams) {
  const std::vector<FaceMesh> faces = TwoWeldedFaces();
  {
    MeshResultBuilder builder;  // no summary
    ASSERT_TRUE(builder.Add(StartedEvent(3)).ok());
    Stream(faces[0], nullptr, &builder);
    EXPECT_EQ(builder.Finish().status().code(), StatusCode::kInvalidArgument);
  }
  {
    MeshResultBuilder builder;  // ids before the face
    pb::MeshEvent ids;
    *ids.mutable_node_ids() = SplitFaceNodeIds(faces[0], nullptr)[0];
    EXPECT_EQ(builder.Add(ids).code(), StatusCode::kInvalidArgument);
  }
  {
    MeshResultBuilder builder;  // a face without its ids
    ASSERT_TRUE(builder.Add(StartedEvent(3)).ok());
    pb::MeshEvent face;
    *face.mutable_face() = SplitFaceMesh(faces[0], false, false)[0];
    ASSERT_TRUE(builder.Add(face).ok());
    ASSERT_TRUE(builder.Add(SummaryEvent(3, 1)).ok());
    EXPECT_EQ(builder.Finish().status().code(), StatusCode::kInvalidArgument);
  }
  {
    MeshResultBuilder builder;  // a skipped part
    const FaceMesh big = MakeFace(1, 3000);
    const auto parts = SplitFaceMesh(big, true, false, 32 * 1024);
    ASSERT_GT(parts.size(), 2u);
    pb::MeshEvent event;
    *event.mutable_face() = parts[0];
    ASSERT_TRUE(builder.Add(event).ok());
    *event.mutable_face() = parts[2];
    EXPECT_EQ(builder.Add(event).code(), StatusCode::kInvalidArgument);
  }
}

TEST(SplitEdgeLineTest, LongEdgeSplitsUnderTheLimitAndJoinsBack) {
  const std::vector<FaceMesh> faces = TwoWeldedFaces();
  EdgeLine shared;  // the side the two faces share, nodes 1 and 2
  shared.edge_id = 2;
  shared.nodes = {1, 2};
  shared.faces = {1, 3};
  shared.sharp = true;
  shared.dihedral = 90.0;
  EdgeLine seam;  // a long closed polyline over nodes 0..3, in small messages
  seam.edge_id = 5;
  seam.faces = {3};
  seam.seam = true;
  for (int i = 0; i < 5000; ++i) seam.nodes.push_back(i % 4);
  seam.nodes.push_back(0);
  EXPECT_EQ(SplitEdgeLine(shared).size(), 1u);
  const std::vector<pb::EdgePolyline> parts = SplitEdgeLine(seam, 4096);
  ASSERT_GT(parts.size(), 10u);
  for (const pb::EdgePolyline& part : parts) {
    pb::MeshEvent event;
    *event.mutable_edge() = part;
    EXPECT_LE(event.ByteSizeLong(), 4096u);
    EXPECT_EQ(part.chunk_count(), static_cast<int>(parts.size()));
    EXPECT_EQ(part.faces_size(), 1);
    EXPECT_TRUE(part.seam());
  }

  MeshResultBuilder builder;
  ASSERT_TRUE(builder.Add(StartedEvent(4)).ok());
  Stream(faces[0], nullptr, &builder);
  Stream(faces[1], nullptr, &builder);
  for (const EdgeLine& line : {shared, seam}) {
    for (pb::EdgePolyline& part : SplitEdgeLine(line, 4096)) {
      pb::MeshEvent event;
      *event.mutable_edge() = std::move(part);
      ASSERT_TRUE(builder.Add(event).ok());
    }
  }
  ASSERT_TRUE(builder.Add(SummaryEvent(4, 2)).ok());
  Result<MeshResult> result = builder.Finish();
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  ASSERT_EQ(result->edges.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const EdgeLine& sent = i == 0 ? shared : seam;
    const EdgeLine& got = result->edges[i];
    EXPECT_EQ(got.edge_id, sent.edge_id);
    EXPECT_EQ(got.nodes, sent.nodes);
    EXPECT_EQ(got.faces, sent.faces);
    EXPECT_EQ(got.seam, sent.seam);
    EXPECT_EQ(got.degenerate, sent.degenerate);
    EXPECT_EQ(got.sharp, sent.sharp);
    EXPECT_EQ(got.dihedral, sent.dihedral);
  }
}

TEST(SplitEdgeLineTest, BuilderRefusesDisorderedOrIncompleteEdges) {
  const std::vector<FaceMesh> faces = TwoWeldedFaces();
  EdgeLine line;
  line.edge_id = 3;
  for (int i = 0; i < 3000; ++i) line.nodes.push_back(i % 4);
  const std::vector<pb::EdgePolyline> parts = SplitEdgeLine(line, 4096);
  ASSERT_GT(parts.size(), 2u);
  const auto event = [](const pb::EdgePolyline& part) {
    pb::MeshEvent e;
    *e.mutable_edge() = part;
    return e;
  };
  {
    MeshResultBuilder builder;  // a skipped part
    ASSERT_TRUE(builder.Add(event(parts[0])).ok());
    EXPECT_EQ(builder.Add(event(parts[2])).code(), StatusCode::kInvalidArgument);
  }
  {
    MeshResultBuilder builder;  // edge ids must increase
    pb::EdgePolyline one = SplitEdgeLine(line)[0];
    ASSERT_TRUE(builder.Add(event(one)).ok());
    EXPECT_EQ(builder.Add(event(one)).code(), StatusCode::kInvalidArgument);
  }
  {
    MeshResultBuilder builder;  // the stream ends inside an edge
    ASSERT_TRUE(builder.Add(StartedEvent(4)).ok());
    Stream(faces[0], nullptr, &builder);
    Stream(faces[1], nullptr, &builder);
    ASSERT_TRUE(builder.Add(event(parts[0])).ok());
    ASSERT_TRUE(builder.Add(SummaryEvent(4, 2)).ok());
    EXPECT_EQ(builder.Finish().status().code(), StatusCode::kInvalidArgument);
  }
  {
    MeshResultBuilder builder;  // a node beyond the mesh
    ASSERT_TRUE(builder.Add(StartedEvent(4)).ok());
    Stream(faces[0], nullptr, &builder);
    Stream(faces[1], nullptr, &builder);
    EdgeLine beyond;
    beyond.edge_id = 1;
    beyond.nodes = {0, 7};
    ASSERT_TRUE(builder.Add(event(SplitEdgeLine(beyond)[0])).ok());
    ASSERT_TRUE(builder.Add(SummaryEvent(4, 2)).ok());
    EXPECT_EQ(builder.Finish().status().code(), StatusCode::kInvalidArgument);
  }
}

}  // namespace
}  // namespace rdmesh::server
