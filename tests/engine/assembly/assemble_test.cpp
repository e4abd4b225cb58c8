// Assembly (assemble.h) on hand-made face meshes: boundary nodes with the same B-rep
// classification become one node, everything else stays apart, and only ok faces count.
#include "assembly/assemble.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace rdmesh {
namespace {

NodeRef Vertex(int id) { return {0, id, 0.0}; }
NodeRef OnEdge(int id, double t) { return {1, id, t}; }
NodeRef Interior() { return {2, 0, 0.0}; }

// A face whose nodes sit at `xyz` (3 per node) and that has the given triangles; uv is the
// node's x and y, and every triangle deviates by 0.1 * its index.
FaceMesh Face(int id, std::vector<double> xyz, std::vector<int32_t> triangles) {
  FaceMesh f;
  f.face_id = id;
  f.status = FaceStatus::kOk;
  f.xyz = std::move(xyz);
  for (size_t i = 0; i < f.xyz.size(); i += 3) f.uv.insert(f.uv.end(), {f.xyz[i], f.xyz[i + 1]});
  f.triangles = std::move(triangles);
  for (int64_t k = 0; k < f.triangle_count(); ++k) f.triangle_deviation.push_back(0.1 * k);
  return f;
}

// Two faces of a square folded along its diagonal from vertex 1 (0,0,0) to vertex 2 (1,1,0),
// which edge 7 joins with a grid node at t = 0.5; each face has one interior node.
void TwoFaces(std::vector<FaceMesh>* faces, std::vector<std::vector<NodeRef>>* refs) {
  // Face 1: vertex 1, vertex 2, the edge node, an interior node.
  faces->push_back(Face(1, {0, 0, 0, 1, 1, 0, 0.5, 0.5, 0, 0.8, 0.3, 0}, {0, 3, 2, 2, 3, 1}));
  refs->push_back({Vertex(1), Vertex(2), OnEdge(7, 0.5), Interior()});
  // Face 2 lists the shared nodes in another order: the edge node, vertex 2, vertex 1.
  faces->push_back(Face(2, {0.5, 0.5, 0, 1, 1, 0, 0, 0, 0, 0.2, 0.7, 0}, {0, 1, 3, 2, 0, 3}));
  refs->push_back({OnEdge(7, 0.5), Vertex(2), Vertex(1), Interior()});
}

TEST(AssembleTest, SharedBoundaryNodesBecomeOneNode) {
  std::vector<FaceMesh> faces;
  std::vector<std::vector<NodeRef>> refs;
  TwoFaces(&faces, &refs);
  Mesh mesh;
  Assemble(&faces, refs, &mesh);
  // 3 shared boundary nodes and 2 interior nodes.
  ASSERT_EQ(mesh.node_count(), 5);
  ASSERT_EQ(faces[0].global_ids, (std::vector<int64_t>{0, 1, 2, 3}));
  EXPECT_EQ(faces[1].global_ids, (std::vector<int64_t>{2, 1, 0, 4}));
  EXPECT_EQ(mesh.node_dim, (std::vector<int8_t>{0, 0, 1, 2, 2}));
  EXPECT_EQ(mesh.node_entity, (std::vector<int32_t>{1, 2, 7, 1, 2}));  // interior: the face id
  // Edge nodes carry t, interior nodes (u,v), vertices nothing.
  EXPECT_EQ(mesh.node_param, (std::vector<double>{0, 0, 0, 0, 0.5, 0, 0.8, 0.3, 0.2, 0.7}));
  EXPECT_EQ(mesh.triangles, (std::vector<int32_t>{0, 3, 2, 2, 3, 1, 2, 1, 4, 0, 2, 4}));
  EXPECT_EQ(mesh.triangle_face, (std::vector<int32_t>{1, 1, 2, 2}));
  EXPECT_EQ(mesh.triangle_deviation, (std::vector<double>{0, 0.1, 0, 0.1}));
  // A node's coordinates are its first face's.
  EXPECT_EQ(mesh.xyz[3 * 4], 0.2);
  EXPECT_EQ(mesh.xyz[3 * 4 + 1], 0.7);
}

TEST(AssembleTest, EdgeNodesMergeOnlyAtTheSameEdgeAndBitIdenticalParameter) {
  std::vector<FaceMesh> faces;
  std::vector<std::vector<NodeRef>> refs;
  TwoFaces(&faces, &refs);
  refs[1][0].t = std::nextafter(0.5, 1.0);  // one ulp away
  Mesh mesh;
  Assemble(&faces, refs, &mesh);
  EXPECT_EQ(mesh.node_count(), 6);
  refs[1][0] = OnEdge(8, 0.5);  // the same t on another edge
  Assemble(&faces, refs, &mesh);
  EXPECT_EQ(mesh.node_count(), 6);
  refs[1][0] = Vertex(7);  // a vertex with the edge's id
  Assemble(&faces, refs, &mesh);
  EXPECT_EQ(mesh.node_count(), 6);
}

TEST(AssembleTest, FailedFacesAndCollapsedTrianglesAreLeftOut) {
  std::vector<FaceMesh> faces;
  std::vector<std::vector<NodeRef>> refs;
  TwoFaces(&faces, &refs);
  faces[0].status = FaceStatus::kFailed;
  faces[0].global_ids = {9, 9, 9, 9};  // stale ids from an earlier assembly go
  // Face 2's interior node becomes a second node of vertex 1 (as at a pole): its triangle with
  // both collapses, the other one stays.
  refs[1][3] = Vertex(1);
  Mesh mesh;
  Assemble(&faces, refs, &mesh);
  EXPECT_TRUE(faces[0].global_ids.empty());
  EXPECT_EQ(faces[1].global_ids, (std::vector<int64_t>{0, 1, 2, 2}));
  EXPECT_EQ(mesh.node_count(), 3);
  EXPECT_EQ(mesh.triangles, (std::vector<int32_t>{0, 1, 2}));
  EXPECT_EQ(mesh.triangle_face, (std::vector<int32_t>{2}));
  EXPECT_EQ(mesh.triangle_deviation, (std::vector<double>{0}));
}

TEST(AssembleTest, TriangleDeviationsOnlyWhenEveryOkFaceHasThem) {
  std::vector<FaceMesh> faces;
  std::vector<std::vector<NodeRef>> refs;
  TwoFaces(&faces, &refs);
  faces[1].triangle_deviation.clear();
  Mesh mesh;
  Assemble(&faces, refs, &mesh);
  EXPECT_EQ(mesh.triangle_count(), 4);
  EXPECT_TRUE(mesh.triangle_deviation.empty());
  // A failed face without them does not count.
  faces[1].status = FaceStatus::kFailed;
  Assemble(&faces, refs, &mesh);
  EXPECT_EQ(mesh.triangle_count(), 2);
  EXPECT_EQ(mesh.triangle_deviation.size(), 2u);
}

// A strip of `n` faces; face k has 50 nodes on edge `first + k` (t = 0..49), 50 on the next
// edge and one interior node. With `shared`, face k's second edge is face k + 1's first.
void Strip(int n, bool shared, std::vector<FaceMesh>* faces,
           std::vector<std::vector<NodeRef>>* refs) {
  for (int k = 0; k < n; ++k) {
    const int e0 = shared ? k + 1 : 2 * k + 1;
    std::vector<double> xyz;
    std::vector<int32_t> triangles;
    std::vector<NodeRef> r;
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i < 50; ++i) {
        xyz.insert(xyz.end(), {static_cast<double>(i), static_cast<double>(e0 + side), 0.0});
        r.push_back(OnEdge(e0 + side, i));
      }
    xyz.insert(xyz.end(), {25.0, e0 + 0.5, 0.0});
    r.push_back(Interior());
    for (int i = 0; i + 1 < 50; ++i) triangles.insert(triangles.end(), {i, i + 1, 100});
    faces->push_back(Face(k + 1, std::move(xyz), std::move(triangles)));
    refs->push_back(std::move(r));
  }
}

TEST(AssembleTest, ManyFacesGiveTheSameMeshOnAnyThreadCount) {
  for (bool shared : {true, false}) {
    SCOPED_TRACE(shared ? "shared edges" : "no edge shared");
    std::vector<FaceMesh> faces;
    std::vector<std::vector<NodeRef>> refs;
    Strip(60, shared, &faces, &refs);
    Mesh one;
    Assemble(&faces, refs, &one, 1);
    const std::vector<int64_t> ids = faces[59].global_ids;
    // Shared: 61 edges of 50 nodes; apart: 120 (more nodes than the node map starts with room
    // for); and 60 interior nodes.
    EXPECT_EQ(one.node_count(), (shared ? 61 : 120) * 50 + 60);
    EXPECT_EQ(one.triangle_count(), 60 * 49);
    for (int threads : {2, 3, 0}) {
      Mesh many;
      Assemble(&faces, refs, &many, threads);
      EXPECT_EQ(faces[59].global_ids, ids);
      EXPECT_EQ(many.xyz, one.xyz);
      EXPECT_EQ(many.triangles, one.triangles);
      EXPECT_EQ(many.triangle_face, one.triangle_face);
      EXPECT_EQ(many.triangle_deviation, one.triangle_deviation);
      EXPECT_EQ(many.node_dim, one.node_dim);
      EXPECT_EQ(many.node_entity, one.node_entity);
      EXPECT_EQ(many.node_param, one.node_param);
    }
  }
}

}  // namespace
}  // namespace rdmesh
