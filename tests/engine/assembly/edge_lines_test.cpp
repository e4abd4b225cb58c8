// MeshResult::edges (BuildEdgeLines): one polyline per B-rep edge of the mesh, on the nodes that
// the faces beside it share, with its faces and its seam / degenerate / sharp flags.

#include <gtest/gtest.h>

#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRep_Tool.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <cmath>
#include <gp_Vec.hxx>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "model/model.h"
#include "rdmesh/engine.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

// The invariants every run's edge lines keep, checked against the B-rep and the triangles.
void ExpectConsistentEdgeLines(const Model& model, const MeshResult& r) {
  const Mesh& mesh = r.mesh;
  // Faces beside each edge, and the undirected triangle sides of each face, from scratch.
  std::map<int, std::set<int>> edge_faces;
  for (int f = 1; f <= model.face_count(); ++f)
    for (TopExp_Explorer it(model.face(f), TopAbs_EDGE); it.More(); it.Next())
      edge_faces[model.edges.FindIndex(it.Current())].insert(f);
  std::map<int, std::set<std::pair<int, int>>> sides;
  for (int64_t t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      int a = mesh.triangles[3 * t + k], b = mesh.triangles[3 * t + (k + 1) % 3];
      sides[mesh.triangle_face[t]].insert({std::min(a, b), std::max(a, b)});
    }
  std::set<int> expected_edges;
  for (const auto& [e, faces] : edge_faces)
    for (int f : faces)
      if (sides.count(f)) expected_edges.insert(e);

  std::set<int> seen;
  int previous = 0;
  for (const EdgeLine& line : r.edges) {
    SCOPED_TRACE("edge " + std::to_string(line.edge_id));
    EXPECT_GT(line.edge_id, previous);  // ascending: every edge once
    previous = line.edge_id;
    seen.insert(line.edge_id);
    const TopoDS_Edge& edge = model.edge(line.edge_id);
    EXPECT_EQ(std::set<int>(line.faces.begin(), line.faces.end()), edge_faces[line.edge_id]);
    EXPECT_EQ(line.degenerate, BRep_Tool::Degenerated(edge) || line.nodes.size() < 2);
    ASSERT_FALSE(line.nodes.empty());
    // Ends on vertex nodes, interior on this edge's nodes in increasing t.
    EXPECT_EQ(mesh.node_dim[line.nodes.front()], 0);
    EXPECT_EQ(mesh.node_dim[line.nodes.back()], 0);
    for (size_t k = 1; k + 1 < line.nodes.size(); ++k) {
      int32_t node = line.nodes[k];
      EXPECT_EQ(mesh.node_dim[node], 1);
      EXPECT_EQ(mesh.node_entity[node], line.edge_id);
      if (k > 1) EXPECT_GT(mesh.node_param[2 * node], mesh.node_param[2 * line.nodes[k - 1]]);
    }
    if (!line.degenerate) {
      TopoDS_Vertex first, last;
      TopExp::Vertices(TopoDS::Edge(edge.Oriented(TopAbs_FORWARD)), first, last);
      for (auto [vertex, node] :
           {std::pair(first, line.nodes.front()), std::pair(last, line.nodes.back())}) {
        gp_Pnt p = BRep_Tool::Pnt(vertex);
        const double* q = &mesh.xyz[3 * node];
        EXPECT_LE(p.Distance(gp_Pnt(q[0], q[1], q[2])), 2 * BRep_Tool::Tolerance(vertex) + 1e-9);
      }
    }
    // Watertight: every segment is a triangle side in every meshed face beside the edge.
    for (int f : line.faces) {
      if (!sides.count(f) || line.degenerate) continue;
      for (size_t k = 0; k + 1 < line.nodes.size(); ++k) {
        int a = line.nodes[k], b = line.nodes[k + 1];
        EXPECT_TRUE(sides[f].count({std::min(a, b), std::max(a, b)}))
            << "segment " << k << " is not a side of face " << f;
      }
    }
    // Flags.
    if (line.seam || line.degenerate || line.faces.size() < 2) {
      EXPECT_EQ(line.dihedral, -1.0);
    } else {
      EXPECT_GE(line.dihedral, 0.0);
      EXPECT_LE(line.dihedral, 180.0);
    }
    const bool free = line.faces.size() == 1 && !line.seam && !line.degenerate;
    EXPECT_EQ(line.sharp, free || line.dihedral > kDefaultSharpEdgeAngle);
  }
  EXPECT_EQ(seen, expected_edges);
}

TEST(EdgeLinesTest, BoxEdgesAreSharpAtNinetyDegrees) {
  auto model = LoadShape(BRepPrimAPI_MakeBox(10.0, 20.0, 30.0).Shape(), "edge_box");
  ASSERT_TRUE(model);
  MeshResult r = MeshOrDie(*model);
  ExpectConsistentEdgeLines(*model, r);
  ASSERT_EQ(r.edges.size(), 12u);
  for (const EdgeLine& line : r.edges) {
    EXPECT_EQ(line.faces.size(), 2u);
    EXPECT_FALSE(line.seam || line.degenerate);
    EXPECT_NEAR(line.dihedral, 90.0, 1e-9);
    EXPECT_TRUE(line.sharp);
  }
  MeshOptions blunt;
  blunt.sharp_edge_angle = 95.0;
  for (const EdgeLine& line : MeshOrDie(*model, blunt).edges) EXPECT_FALSE(line.sharp);
  // The sharp angle changes no triangle or node.
  EXPECT_EQ(MeshOrDie(*model, blunt).mesh.triangles, r.mesh.triangles);
  blunt.sharp_edge_angle = 181.0;
  EXPECT_EQ(MeshModel(*model, blunt).status().code(), StatusCode::kInvalidArgument);
}

TEST(EdgeLinesTest, CylinderSeamAndSphereSeamAndPoles) {
  auto cylinder = LoadShape(BRepPrimAPI_MakeCylinder(5.0, 10.0).Shape(), "edge_cylinder");
  ASSERT_TRUE(cylinder);
  MeshResult r = MeshOrDie(*cylinder);
  ExpectConsistentEdgeLines(*cylinder, r);
  ASSERT_EQ(r.edges.size(), 3u);  // two rims and the seam
  int seams = 0, rims = 0;
  for (const EdgeLine& line : r.edges) {
    if (line.seam) {
      ++seams;
      EXPECT_EQ(line.faces.size(), 1u);
      EXPECT_FALSE(line.sharp);
      continue;
    }
    ++rims;
    EXPECT_EQ(line.nodes.front(), line.nodes.back());  // a closed edge
    EXPECT_GE(line.nodes.size(), 4u);
    EXPECT_NEAR(line.dihedral, 90.0, 1e-6);
    EXPECT_TRUE(line.sharp);
  }
  EXPECT_EQ(seams, 1);
  EXPECT_EQ(rims, 2);

  auto sphere = LoadShape(BRepPrimAPI_MakeSphere(5.0).Shape(), "edge_sphere");
  ASSERT_TRUE(sphere);
  MeshResult s = MeshOrDie(*sphere);
  ExpectConsistentEdgeLines(*sphere, s);
  int degenerate = 0;
  for (const EdgeLine& line : s.edges) {
    degenerate += line.degenerate;
    EXPECT_FALSE(line.sharp);
  }
  EXPECT_EQ(degenerate, 2);
}

// The normals the writers and the service hand out are the surface's exact ones at every node,
// the sphere's poles included (where the first derivatives vanish: the refinement's estimate
// there, a mean of normals around the pole, was about a degree off).
TEST(FaceNormalsTest, ExactAtEveryNodePolesIncluded) {
  auto sphere = LoadShape(BRepPrimAPI_MakeSphere(5.0).Shape(), "normals_sphere");
  ASSERT_TRUE(sphere);
  MeshResult r = MeshOrDie(*sphere);
  int poles = 0;
  for (const FaceMesh& face : r.faces) {
    ASSERT_EQ(face.normals.size(), face.xyz.size());
    for (int64_t i = 0; i < face.node_count(); ++i) {
      const gp_Vec radial(face.xyz[3 * i], face.xyz[3 * i + 1], face.xyz[3 * i + 2]);
      const gp_Vec normal(face.normals[3 * i], face.normals[3 * i + 1], face.normals[3 * i + 2]);
      EXPECT_NEAR(normal.Magnitude(), 1.0, 1e-12);
      EXPECT_LT(normal.Angle(radial), 1e-6) << "node " << i << " at z " << radial.Z();
      poles += std::abs(std::abs(radial.Z()) - 5.0) < 1e-9;
    }
  }
  EXPECT_GE(poles, 2);
}

// The lines BuildEdgeLines makes from the mesh alone, asking OCCT for every pcurve and seam, are
// the run's own (built from its pcurve table), bit for bit.
void ExpectRebuiltLinesSame(const Model& model, const MeshResult& r) {
  auto again = BuildEdgeLines(model, r.mesh);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  ASSERT_EQ(again->size(), r.edges.size());
  for (size_t i = 0; i < r.edges.size(); ++i) {
    const EdgeLine &a = (*again)[i], &b = r.edges[i];
    EXPECT_EQ(a.edge_id, b.edge_id);
    EXPECT_EQ(a.nodes, b.nodes) << "edge " << b.edge_id;
    EXPECT_EQ(a.faces, b.faces) << "edge " << b.edge_id;
    EXPECT_EQ(a.seam, b.seam) << "edge " << b.edge_id;
    EXPECT_EQ(a.degenerate, b.degenerate) << "edge " << b.edge_id;
    EXPECT_EQ(a.sharp, b.sharp) << "edge " << b.edge_id;
    EXPECT_EQ(a.dihedral, b.dihedral) << "edge " << b.edge_id;
  }
}

TEST(EdgeLinesTest, RebuiltFromTheMeshAlone) {
  auto model = LoadShape(BRepPrimAPI_MakeCylinder(5.0, 10.0).Shape(), "edge_rebuilt");
  ASSERT_TRUE(model);
  MeshResult r = MeshOrDie(*model);
  ExpectRebuiltLinesSame(*model, r);
  Mesh unclassified = r.mesh;
  unclassified.node_param.clear();
  EXPECT_EQ(BuildEdgeLines(*model, unclassified).status().code(), StatusCode::kInternal);
}

TEST(EdgeLinesTest, FaceSubsetHasTheEdgesOfItsFaces) {
  auto model = LoadShape(BRepPrimAPI_MakeBox(10.0, 20.0, 30.0).Shape(), "edge_subset");
  ASSERT_TRUE(model);
  MeshOptions options;
  options.face_ids = {1};
  MeshResult r = MeshOrDie(*model, options);
  ExpectConsistentEdgeLines(*model, r);
  EXPECT_EQ(r.edges.size(), 4u);
}

class EdgeLinesCorpusTest : public ::testing::TestWithParam<const char*> {};

TEST_P(EdgeLinesCorpusTest, EveryEdgeOnceOnSharedNodes) {
  auto model = LoadModel(std::string(RDMESH_TEST_DATA) + "/" + GetParam());
  ASSERT_TRUE(model.ok()) << model.status().ToString();
  MeshResult r = MeshOrDie(**model);
  ExpectConsistentEdgeLines(**model, r);
  EXPECT_FALSE(r.edges.empty());
  ExpectRebuiltLinesSame(**model, r);
}

// Test names are the parameter index: 0 nist_mbe_pmi_11, 1 cq_red_cube_blue_cylinder, ...
INSTANTIATE_TEST_SUITE_P(Data, EdgeLinesCorpusTest,
                         ::testing::Values("nist_mbe_pmi_11.stp", "cq_red_cube_blue_cylinder.step",
                                           "axom_sliced_cylinder.step", "pyocc_eight_cyl.stp"));

}  // namespace
}  // namespace rdmesh
