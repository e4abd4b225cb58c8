// The whole pipeline on real B-reps: OCCT primitives (sphere, cylinder, torus) and the bundled
// corpus models. Checks the promises: every face meshed, watertight, outward, within the asked
// deviation, economical on the analytic shapes, identical at any thread count, budgets kept.

#include <gtest/gtest.h>
#include <unistd.h>

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <GC_MakeCircle.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <gp_Circ.hxx>
#include <map>
#include <string>

#include "rdmesh/engine.h"
#include "shape_fixture.h"

namespace rdmesh {
namespace {

// Edges used by one triangle (free) and by more than two (non-manifold).
std::pair<int, int> OpenAndNonManifoldEdges(const Mesh& mesh) {
  std::map<std::pair<int, int>, int> uses;
  for (size_t k = 0; k < mesh.triangles.size(); k += 3)
    for (int i = 0; i < 3; ++i) {
      int a = mesh.triangles[k + i], b = mesh.triangles[k + (i + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  int open = 0, nonmanifold = 0;
  for (const auto& [edge, n] : uses) open += n == 1, nonmanifold += n > 2;
  return {open, nonmanifold};
}

// Triangles whose normal opposes the face's outward normal at their nodes.
int Inverted(const MeshResult& r) {
  int bad = 0;
  for (const FaceMesh& f : r.faces) {
    for (size_t k = 0; k < f.triangles.size(); k += 3) {
      const int32_t* t = &f.triangles[k];
      auto p = [&](int i) {
        return std::array<double, 3>{f.xyz[3 * t[i]], f.xyz[3 * t[i] + 1], f.xyz[3 * t[i] + 2]};
      };
      auto a = p(0), b = p(1), c = p(2);
      double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                     u[0] * v[1] - u[1] * v[0]};
      double dot = 0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) dot += n[j] * f.normals[3 * t[i] + j];
      bad += dot < 0;
    }
  }
  return bad;
}

TEST(PipelineTest, UnitSphereNearTheOptimum) {
  auto model = LoadShape(BRepPrimAPI_MakeSphere(1.0).Shape(), "sphere");
  ASSERT_TRUE(model);
  MeshOptions options;  // 1e-3 of the diagonal
  MeshResult r = MeshOrDie(*model, options);
  const double delta = 1e-3 * GetModelInfo(*model).diagonal;
  const double optimum = 2 * 2.418 / delta;  // METHOD.md: Hausdorff ~ 2.418 / n on a unit sphere
  std::printf("unit sphere: %lld triangles, %.3fx the optimum %.0f\n",
              static_cast<long long>(r.summary.triangles), r.summary.triangles / optimum, optimum);
  // 1.27x before spheres started from a lattice (lattice_seeds), 1.17x since.
  EXPECT_LE(r.summary.triangles, 1.2 * optimum);
  EXPECT_GE(r.summary.triangles, optimum);
  EXPECT_LE(r.summary.estimated_deviation, delta * (1 + 1e-9));
  EXPECT_EQ(OpenAndNonManifoldEdges(r.mesh), std::make_pair(0, 0));
  EXPECT_EQ(Inverted(r), 0);
}

TEST(PipelineTest, CylinderNeedsNoInteriorNodes) {
  auto model = LoadShape(BRepPrimAPI_MakeCylinder(1.0, 4.0).Shape(), "cylinder");
  ASSERT_TRUE(model);
  MeshResult r = MeshOrDie(*model, MeshOptions());
  // 32 segments per circle at 1e-3 of the diagonal: 64 lateral + 2 x 30 cap triangles = 124.
  EXPECT_LE(r.summary.triangles, 130);
  EXPECT_EQ(OpenAndNonManifoldEdges(r.mesh), std::make_pair(0, 0));
  EXPECT_EQ(Inverted(r), 0);
  for (const FaceMesh& f : r.faces) {
    EXPECT_EQ(f.status, FaceStatus::kOk) << f.reason;
    if (f.surface_type == SurfaceType::kPlane) {
      // A planar face keeps only its boundary nodes.
      for (size_t i = 0; i < f.global_ids.size(); ++i)
        EXPECT_LT(r.mesh.node_dim[f.global_ids[i]], 2);
    }
  }
}

TEST(PipelineTest, TorusWatertightWithinDeviation) {
  auto model = LoadShape(BRepPrimAPI_MakeTorus(3.0, 1.0).Shape(), "torus");
  ASSERT_TRUE(model);
  MeshResult r = MeshOrDie(*model, MeshOptions());
  EXPECT_EQ(r.summary.faces_failed, 0);
  EXPECT_EQ(OpenAndNonManifoldEdges(r.mesh), std::make_pair(0, 0));
  EXPECT_EQ(Inverted(r), 0);
  EXPECT_LE(r.summary.estimated_deviation, 1.2e-3 * GetModelInfo(*model).diagonal);
}

TEST(PipelineTest, ConeApexTrianglesFaceOutward) {
  // Whole and half cones: the surface normal at the apex depends on the direction it is
  // approached from, which must not make the fold guard accept inverted apex triangles.
  for (double angle : {2 * M_PI, M_PI}) {
    auto model = LoadShape(BRepPrimAPI_MakeCone(1.0, 0.0, 1.7, angle).Shape(), "cone");
    ASSERT_TRUE(model);
    MeshResult r = MeshOrDie(*model, MeshOptions());
    EXPECT_EQ(r.summary.faces_failed, 0);
    EXPECT_EQ(OpenAndNonManifoldEdges(r.mesh), std::make_pair(0, 0));
    EXPECT_EQ(Inverted(r), 0) << "angle " << angle;
    EXPECT_LE(r.summary.estimated_deviation, 1.2e-3 * GetModelInfo(*model).diagonal);
  }
}

TEST(PipelineTest, ArcWhoseEndsNearlyMeetIsDiscretised) {
  // A disk bounded by a circular arc of radius 10 that stops 1e-5 short of closing and a
  // 1e-5 line that closes it, with a tolerance of 1e-4 on both edges. The arc's end-to-end chord
  // is below its tolerance, but the arc is 63 long; the line is a point.
  const double radius = 10, gap = 1e-5 / radius;
  gp_Circ circle(gp::XOY(), radius);
  TopoDS_Edge arc = BRepBuilderAPI_MakeEdge(circle, 0.0, 2 * M_PI - gap);
  TopoDS_Edge line = BRepBuilderAPI_MakeEdge(
      gp_Pnt(radius * std::cos(-gap), radius * std::sin(-gap), 0), gp_Pnt(radius, 0, 0));
  BRepBuilderAPI_MakeWire wire(arc, line);
  ASSERT_TRUE(wire.IsDone());
  TopoDS_Face face = BRepBuilderAPI_MakeFace(wire.Wire(), true);
  BRep_Builder builder;
  for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next())
    builder.UpdateEdge(TopoDS::Edge(ex.Current()), 1e-4);
  for (TopExp_Explorer ex(face, TopAbs_VERTEX); ex.More(); ex.Next())
    builder.UpdateVertex(TopoDS::Vertex(ex.Current()), 1e-4);
  auto model = LoadShape(face, "near_closed_arc");
  ASSERT_TRUE(model);
  MeshResult r = MeshOrDie(*model, MeshOptions());
  ASSERT_EQ(r.faces.size(), 1u);
  const FaceMesh& f = r.faces[0];
  EXPECT_EQ(f.status, FaceStatus::kOk) << f.reason;
  // 1e-3 of the diagonal (~28.3) on radius 10: about 37 segments around the circle.
  EXPECT_GE(f.triangle_count(), 30);
  EXPECT_NEAR(f.area, M_PI * radius * radius, 0.01 * M_PI * radius * radius);
  EXPECT_EQ(OpenAndNonManifoldEdges(r.mesh).second, 0);
}

TEST(PipelineTest, AskingForAPlacedCopyAloneMeshesIt) {
  // Two placements of one box: faces 7..12 are copies of faces 1..6.
  auto model = LoadShape(PlacedTwice(BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape(), 5), "two_boxes");
  ASSERT_TRUE(model);
  ASSERT_EQ(GetModelInfo(*model).faces, 12);
  MeshOptions options;
  options.face_ids = {7};
  MeshResult r = MeshOrDie(*model, options);
  EXPECT_EQ(r.faces[6].status, FaceStatus::kOk) << r.faces[6].reason;
  EXPECT_EQ(r.faces[6].triangle_count(), 2);
  EXPECT_EQ(r.faces[0].status, FaceStatus::kSkipped);
  EXPECT_EQ(r.summary.triangles, 2);
}

TEST(PipelineTest, PlacedCopiesAreTheirRepresentativeMoved) {
  // Three placements of one cylinder: faces 4..6 and 7..9 are copies of faces 1..3, and the two
  // copies of a face match their boundary against one representative domain.
  TopoDS_Shape cylinder = BRepPrimAPI_MakeCylinder(2.0, 3.0).Shape();
  TopoDS_Compound three;
  BRep_Builder builder;
  builder.MakeCompound(three);
  for (int k = 0; k < 3; ++k) {
    gp_Trsf shift;
    shift.SetTranslation(gp_Vec(10.0 * k, 0, 0));
    builder.Add(three, cylinder.Moved(TopLoc_Location(shift)));
  }
  auto model = LoadShape(three, "three_cylinders");
  ASSERT_TRUE(model);
  ASSERT_EQ(GetModelInfo(*model).faces, 9);
  ASSERT_EQ(GetModelInfo(*model).unique_faces, 3);
  MeshOptions options;
  options.max_deviation = 1e-3;
  MeshResult r = MeshOrDie(*model, options);
  EXPECT_EQ(OpenAndNonManifoldEdges(r.mesh), std::make_pair(0, 0));
  for (int f = 4; f <= 9; ++f) {
    const FaceMesh& copy = r.faces[f - 1];
    const FaceMesh& rep = r.faces[(f - 1) % 3];
    ASSERT_EQ(copy.status, FaceStatus::kOk) << copy.reason;
    EXPECT_EQ(copy.triangles, rep.triangles);
    ASSERT_EQ(copy.xyz.size(), rep.xyz.size());
    const double dx = 10.0 * ((f - 1) / 3);
    for (size_t i = 0; i < copy.xyz.size(); i += 3) {
      EXPECT_NEAR(copy.xyz[i], rep.xyz[i] + dx, 1e-9);
      EXPECT_NEAR(copy.xyz[i + 1], rep.xyz[i + 1], 1e-9);
      EXPECT_NEAR(copy.xyz[i + 2], rep.xyz[i + 2], 1e-9);
    }
  }
}

class CorpusTest : public ::testing::TestWithParam<const char*> {};

TEST_P(CorpusTest, EveryFaceMeshedWatertightOutward) {
  auto model = LoadData(GetParam());
  ASSERT_TRUE(model);
  MeshResult r = MeshOrDie(*model, MeshOptions());
  for (const FaceMesh& f : r.faces) {
    EXPECT_EQ(f.status, FaceStatus::kOk) << "face " << f.face_id << ": " << f.reason;
    EXPECT_GT(f.triangle_count(), 0) << "face " << f.face_id;
  }
  if (GetModelInfo(*model).closed) EXPECT_EQ(OpenAndNonManifoldEdges(r.mesh), std::make_pair(0, 0));
  EXPECT_EQ(Inverted(r), 0);
  EXPECT_GT(r.mesh.triangle_count(), 0);
}

// Every triangle carries the refinement's estimated deviation: one per triangle, within the
// asked deviation, its largest per face the face's max_deviation, and the assembled mesh's array
// the faces' in face order.
TEST_P(CorpusTest, TriangleDeviationsAddUpToTheFaceEstimate) {
  auto model = LoadData(GetParam());
  ASSERT_TRUE(model);
  MeshResult r = MeshOrDie(*model, MeshOptions());
  std::vector<double> assembled;
  int positive = 0;
  for (const FaceMesh& f : r.faces) {
    ASSERT_EQ(static_cast<int64_t>(f.triangle_deviation.size()), f.triangle_count())
        << "face " << f.face_id;
    double worst = 0;
    for (double d : f.triangle_deviation) {
      EXPECT_GE(d, 0.0);
      worst = std::max(worst, d);
      positive += d > 0;
    }
    EXPECT_EQ(worst, f.max_deviation) << "face " << f.face_id;
    EXPECT_LE(worst, r.summary.requested_deviation * (1 + 1e-9)) << "face " << f.face_id;
    assembled.insert(assembled.end(), f.triangle_deviation.begin(), f.triangle_deviation.end());
  }
  EXPECT_GT(positive, 0);  // curved faces deviate
  ASSERT_EQ(static_cast<int64_t>(r.mesh.triangle_deviation.size()), r.mesh.triangle_count());
  // No triangle collapses at a pole in these models: the arrays are the same.
  if (assembled.size() == r.mesh.triangle_deviation.size())
    EXPECT_EQ(assembled, r.mesh.triangle_deviation);
  EXPECT_EQ(*std::max_element(r.mesh.triangle_deviation.begin(), r.mesh.triangle_deviation.end()),
            r.summary.estimated_deviation);
}

TEST_P(CorpusTest, SameMeshAtAnyThreadCount) {
  auto model = LoadData(GetParam());
  ASSERT_TRUE(model);
  MeshOptions one, two;
  one.threads = 1;
  two.threads = 2;
  MeshResult a = MeshOrDie(*model, one), b = MeshOrDie(*model, two);
  EXPECT_EQ(a.mesh.xyz, b.mesh.xyz);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.mesh.triangle_face, b.mesh.triangle_face);
  EXPECT_EQ(a.mesh.triangle_deviation, b.mesh.triangle_deviation);
}

INSTANTIATE_TEST_SUITE_P(Data, CorpusTest,
                         ::testing::Values("nist_mbe_pmi_11.stp", "cq_red_cube_blue_cylinder.step",
                                           "axom_sliced_cylinder.step", "pyocc_eight_cyl.stp"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

TEST(PipelineTest, BudgetIsKeptAndDeviationFallsAsItGrows) {
  auto model = LoadData("nist_mbe_pmi_11.stp");
  ASSERT_TRUE(model);
  double previous = INFINITY;
  for (int64_t budget : {400, 1000, 2500}) {
    MeshOptions options;
    options.max_triangles = budget;
    MeshResult r = MeshOrDie(*model, options);
    EXPECT_LE(r.summary.triangles, budget);
    EXPECT_LT(r.summary.estimated_deviation, previous) << "budget " << budget;
    previous = r.summary.estimated_deviation;
  }
}

TEST(PipelineTest, BadOptionsAreRejected) {
  auto model = LoadShape(BRepPrimAPI_MakeSphere(1.0).Shape(), "sphere_bad");
  ASSERT_TRUE(model);
  MeshOptions options;
  options.max_deviation = -1;
  EXPECT_EQ(MeshModel(*model, options).status().code(), StatusCode::kInvalidArgument);
  options = MeshOptions();
  options.face_ids = {7};
  EXPECT_EQ(MeshModel(*model, options).status().code(), StatusCode::kInvalidArgument);
}

TEST(PipelineTest, CancelStopsTheRun) {
  auto model = LoadData("nist_mbe_pmi_11.stp");
  ASSERT_TRUE(model);
  Context context;
  context.Cancel();
  EXPECT_EQ(MeshModel(*model, MeshOptions(), &context).status().code(), StatusCode::kCancelled);
}

// A caller's deadline that passes before options.timeout_seconds ends the run as
// kDeadlineExceeded: the engine's own timeout must not replace it with a later one.
TEST(PipelineTest, CallersEarlierDeadlineWinsOverTimeoutSeconds) {
  auto model = LoadData("nist_mbe_pmi_11.stp");
  ASSERT_TRUE(model);
  Context context;
  context.SetDeadline(std::chrono::steady_clock::now() - std::chrono::milliseconds(1));
  MeshOptions options;
  options.timeout_seconds = 3600;
  EXPECT_EQ(MeshModel(*model, options, &context).status().code(), StatusCode::kDeadlineExceeded);
}

// Absurd options (a deviation, an RD tolerance or an edge length far below the model's size)
// ask for more work than any deadline allows: the run stops within a second or so of it, in
// whatever stage it is, as kDeadlineExceeded.
struct AbsurdCase {
  const char* name;
  const char* file;
  MeshOptions options;
  double timeout;
};

// ctest lists parameterised tests with their parameter: print the case's name, not its bytes.
void PrintTo(const AbsurdCase& c, std::ostream* os) { *os << c.name; }

MeshOptions Absurd(double deviation, double rd, double max_length, int threads) {
  MeshOptions options;
  options.max_deviation = deviation;
  options.rd_tolerance = rd;
  options.max_edge_length = max_length;
  options.threads = threads;
  return options;
}

class AbsurdOptionsTest : public ::testing::TestWithParam<AbsurdCase> {};

// How soon after the deadline the run ends is asserted in Release builds. Sanitizer builds
// check the status and the lower bound only: there the run ended 2.1 s and 7.1 s late on a busy
// machine (ASan, two runs), in stretches that take milliseconds in Release.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kTimedDeadline = false;
#else
constexpr bool kTimedDeadline = true;
#endif

TEST_P(AbsurdOptionsTest, StopsSoonAfterTheDeadline) {
  const AbsurdCase& c = GetParam();
  auto model = LoadData(c.file);
  ASSERT_TRUE(model);
  MeshOptions options = c.options;
  options.timeout_seconds = c.timeout;
  auto start = std::chrono::steady_clock::now();
  auto result = MeshModel(*model, options);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(result.status().code(), StatusCode::kDeadlineExceeded) << result.status().ToString();
  EXPECT_GE(seconds, c.timeout * 0.99);
  if (kTimedDeadline) {
    EXPECT_LT(seconds, c.timeout + 2.0)
        << "stopped " << seconds - c.timeout << " s after the deadline";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Deadline, AbsurdOptionsTest,
    ::testing::Values(
        AbsurdCase{"deviation_1e_12", "axom_sliced_cylinder.step", Absurd(1e-12, 0, 0, 0), 1.0},
        AbsurdCase{"deviation_1e_12_one_thread", "axom_sliced_cylinder.step",
                   Absurd(1e-12, 0, 0, 1), 1.0},
        AbsurdCase{"rd_1e_12", "axom_sliced_cylinder.step", Absurd(0, 1e-12, 0, 0), 1.0},
        AbsurdCase{"max_edge_1e_9", "axom_sliced_cylinder.step", Absurd(0, 0, 1e-9, 0), 1.0},
        // Late enough to reach the faces: the triangulation of ~10^5 boundary nodes and the
        // collapse pass ran 88 s past this deadline before they polled the context.
        AbsurdCase{"deviation_1e_12_in_faces", "axom_sliced_cylinder.step", Absurd(1e-12, 0, 0, 0),
                   10.0}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace rdmesh
