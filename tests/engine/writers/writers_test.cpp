// Mesh writers on hand-made MeshResults of small models: every format reads back with the right
// counts, outward triangles, and the shared Model is left as it was.

#include <gtest/gtest.h>
#include <unistd.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom_Curve.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Writer.hxx>
#include <TDataStd_Name.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "model/model.h"
#include "rdmesh/engine.h"

namespace rdmesh {
namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream buffer;
  buffer << file.rdbuf();
  return buffer.str();
}

// A mesh of every face of a model made of boxes: per face, its 4 corners (vertex nodes), 4 edge
// midpoints (edge nodes) and its centre (a face node), fanned into 8 outward triangles. Nodes on
// vertices and edges are shared between faces, as the engine's assembled mesh does.
MeshResult MeshBoxes(const Model& model) {
  MeshResult result;
  Mesh& mesh = result.mesh;
  std::map<std::pair<int, int>, int> node_of;  // (dim, entity) -> node id (vertices, edges)
  auto add_node = [&mesh](const gp_Pnt& p, int dim, int entity, double p0, double p1) {
    mesh.xyz.insert(mesh.xyz.end(), {p.X(), p.Y(), p.Z()});
    mesh.node_dim.push_back(static_cast<int8_t>(dim));
    mesh.node_entity.push_back(entity);
    mesh.node_param.insert(mesh.node_param.end(), {p0, p1});
    return static_cast<int>(mesh.node_count() - 1);
  };
  for (int id = 1; id <= model.face_count(); ++id) {
    const TopoDS_Face& face = model.face(id);
    FaceMesh fm;
    fm.face_id = id;
    fm.surface_type = SurfaceType::kPlane;
    fm.status = FaceStatus::kOk;
    auto add_local = [&fm, &mesh](int global, const gp_Pnt2d& uv) {
      for (int k = 0; k < 3; ++k) fm.xyz.push_back(mesh.xyz[3 * global + k]);
      fm.uv.insert(fm.uv.end(), {uv.X(), uv.Y()});
      fm.global_ids.push_back(global);
      return static_cast<int>(fm.global_ids.size() - 1);
    };
    std::vector<int> loop;  // local ids around the outer wire
    for (BRepTools_WireExplorer it(BRepTools::OuterWire(face), face); it.More(); it.Next()) {
      const TopoDS_Edge& edge = it.Current();
      TopoDS_Vertex start = TopExp::FirstVertex(edge, /*CumOri=*/true);
      int vertex_id = model.vertices.FindIndex(start);
      auto [vertex_node, new_vertex] = node_of.try_emplace({0, vertex_id}, 0);
      if (new_vertex) vertex_node->second = add_node(BRep_Tool::Pnt(start), 0, vertex_id, 0, 0);
      loop.push_back(add_local(vertex_node->second, BRep_Tool::Parameters(start, face)));

      double first, last;
      Handle(Geom_Curve) curve = BRep_Tool::Curve(edge, first, last);
      double mid = 0.5 * (first + last);
      int edge_id = model.edges.FindIndex(edge);
      auto [edge_node, new_edge] = node_of.try_emplace({1, edge_id}, 0);
      if (new_edge) {
        gp_Pnt p = curve->Value(mid).Transformed(edge.Location().Transformation());
        edge_node->second = add_node(p, 1, edge_id, mid, 0);
      }
      Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, first, last);
      loop.push_back(add_local(edge_node->second, pcurve->Value(mid)));
    }
    double u0, u1, v0, v1;
    BRepTools::UVBounds(face, u0, u1, v0, v1);
    double u = 0.5 * (u0 + u1), v = 0.5 * (v0 + v1);
    gp_Pnt centre = BRepAdaptor_Surface(face).Value(u, v);
    int centre_local = add_local(add_node(centre, 2, id, u, v), gp_Pnt2d(u, v));

    // Outward: away from the centre of the 10x20x30 box the face belongs to (placed by the
    // face's location).
    gp_XYZ c = centre.XYZ();
    gp_XYZ a = gp_XYZ(fm.xyz[3 * loop[0]], fm.xyz[3 * loop[0] + 1], fm.xyz[3 * loop[0] + 2]);
    gp_XYZ b = gp_XYZ(fm.xyz[3 * loop[2]], fm.xyz[3 * loop[2] + 1], fm.xyz[3 * loop[2] + 2]);
    gp_XYZ normal = (a - c).Crossed(b - c);
    normal.Normalize();
    gp_Trsf to_world = face.Location().Transformation();
    gp_XYZ solid_centre = gp_Pnt(5.0, 10.0, 15.0).Transformed(to_world).XYZ();
    bool flip = normal.Dot(c - solid_centre) < 0;
    if (flip) normal.Reverse();
    for (size_t i = 0; i < loop.size(); ++i) {
      int p = loop[i], q = loop[(i + 1) % loop.size()];
      if (flip) std::swap(p, q);
      fm.triangles.insert(fm.triangles.end(), {centre_local, p, q});
    }
    for (int n = 0; n < fm.node_count(); ++n)
      fm.normals.insert(fm.normals.end(), {normal.X(), normal.Y(), normal.Z()});
    for (size_t t = 0; t < fm.triangles.size(); t += 3) {
      for (int k = 0; k < 3; ++k)
        mesh.triangles.push_back(static_cast<int32_t>(fm.global_ids[fm.triangles[t + k]]));
      mesh.triangle_face.push_back(id);
    }
    result.faces.push_back(std::move(fm));
  }
  result.summary.triangles = result.mesh.triangle_count();
  result.summary.nodes = result.mesh.node_count();
  result.summary.faces_ok = model.face_count();
  return result;
}

TopoDS_Shape Box() { return BRepPrimAPI_MakeBox(10.0, 20.0, 30.0).Shape(); }

class WritersTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rdmesh_writers_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) { return (dir_ / name).string(); }

  std::shared_ptr<const Model> LoadBrepBox() {
    std::string path = Path("box.brep");
    EXPECT_TRUE(BRepTools::Write(Box(), path.c_str()));
    auto model = LoadModel(path);
    EXPECT_TRUE(model.ok()) << model.status().ToString();
    return *model;
  }

  std::shared_ptr<const Model> LoadStepBox() {
    std::string path = Path("box.step");
    STEPControl_Writer writer;
    writer.Transfer(Box(), STEPControl_AsIs);
    EXPECT_EQ(writer.Write(path.c_str()), IFSelect_RetDone);
    auto model = LoadModel(path);
    EXPECT_TRUE(model.ok()) << model.status().ToString();
    return *model;
  }

  // Two placed instances of one box part, in an XCAF assembly written as STEP.
  std::shared_ptr<const Model> LoadInstancedPair() {
    Handle(TDocStd_Document) doc = new TDocStd_Document("MDTV-XCAF");
    XCAFApp_Application::GetApplication()->InitDocument(doc);
    Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    TDF_Label part = tool->AddShape(Box(), false);
    TDataStd_Name::Set(part, "brick");
    TDF_Label assembly = tool->NewShape();
    gp_Trsf shift;
    shift.SetTranslation(gp_Vec(100.0, 0.0, 0.0));
    tool->AddComponent(assembly, part, TopLoc_Location());
    tool->AddComponent(assembly, part, TopLoc_Location(shift));
    tool->UpdateAssemblies();
    std::string path = Path("pair.step");
    STEPCAFControl_Writer writer;
    EXPECT_TRUE(writer.Transfer(doc, STEPControl_AsIs));
    EXPECT_EQ(writer.Write(path.c_str()), IFSelect_RetDone);
    auto model = LoadModel(path);
    EXPECT_TRUE(model.ok()) << model.status().ToString();
    return *model;
  }

  fs::path dir_;
};

// Counts from a MSH 4.1 ASCII file, with checks of its structure.
struct MshCounts {
  int64_t nodes = 0, triangles = 0, parametric_blocks = 0, surface_blocks = 0;
  std::map<int, std::vector<int64_t>> lines;      // curve tag -> node tags of its line elements
  std::map<int64_t, std::vector<double>> params;  // node tag -> its parameters (parametric only)
  int64_t max_element_tag = 0;
};

MshCounts ReadMsh(const std::string& path) {
  MshCounts counts;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "$MeshFormat");
  std::getline(in, line);
  EXPECT_EQ(line, "4.1 0 8");
  while (std::getline(in, line)) {
    if (line == "$Nodes") {
      int64_t blocks, nodes, min_tag, max_tag;
      in >> blocks >> nodes >> min_tag >> max_tag;
      counts.nodes = nodes;
      std::vector<bool> seen(nodes + 1, false);
      for (int64_t b = 0; b < blocks; ++b) {
        int dim, tag, parametric;
        int64_t count;
        in >> dim >> tag >> parametric >> count;
        EXPECT_TRUE(parametric == 0 || (parametric == 1 && dim > 0)) << dim << " " << parametric;
        counts.parametric_blocks += parametric;
        std::vector<int64_t> tags(count);
        for (int64_t& node : tags) {
          in >> node;
          EXPECT_TRUE(node >= 1 && node <= nodes && !seen[node]) << node;
          if (node >= 1 && node <= nodes) seen[node] = true;
        }
        for (int64_t node : tags) {
          double x;
          for (int k = 0; k < 3; ++k) in >> x;
          for (int k = 0; k < (parametric ? dim : 0); ++k) {
            in >> x;
            counts.params[node].push_back(x);
          }
        }
      }
      EXPECT_TRUE(in.good());
    } else if (line == "$Elements") {
      int64_t blocks, elements, min_tag, max_tag;
      in >> blocks >> elements >> min_tag >> max_tag;
      int64_t read = 0;
      for (int64_t b = 0; b < blocks; ++b) {
        int dim, tag, type;
        int64_t count;
        in >> dim >> tag >> type >> count;
        read += count;
        EXPECT_TRUE((dim == 2 && type == 2) || (dim == 1 && type == 1)) << dim << " " << type;
        if (dim == 1) {
          EXPECT_EQ(counts.lines.count(tag), 0u) << "two line blocks on curve " << tag;
          std::vector<int64_t>& polyline = counts.lines[tag];
          for (int64_t i = 0; i < count; ++i) {
            int64_t element, a, b2;
            in >> element >> a >> b2;
            EXPECT_EQ(element, ++counts.max_element_tag);
            EXPECT_TRUE(a >= 1 && a <= counts.nodes && b2 >= 1 && b2 <= counts.nodes);
            if (!polyline.empty()) EXPECT_EQ(polyline.back(), a);  // consecutive segments
            if (polyline.empty()) polyline.push_back(a);
            polyline.push_back(b2);
          }
          continue;
        }
        ++counts.surface_blocks;
        EXPECT_TRUE(counts.lines.empty()) << "triangles come first";
        for (int64_t i = 0; i < count; ++i) {
          int64_t element, a, b2, c;
          in >> element >> a >> b2 >> c;
          EXPECT_EQ(element, ++counts.max_element_tag);
          EXPECT_TRUE(a >= 1 && a <= counts.nodes && c >= 1 && c <= counts.nodes);
        }
        counts.triangles += count;
      }
      EXPECT_EQ(read, elements);
    }
  }
  return counts;
}

// Triangles drawn by a .glb scene (instances count), and the number of meshes stored.
struct GlbCounts {
  int64_t drawn_triangles = 0;
  size_t stored_meshes = 0;  // distinct index buffers
  nlohmann::json json;
};

GlbCounts ReadGlb(const std::string& path) {
  GlbCounts counts;
  std::string bytes = ReadBytes(path);
  EXPECT_GE(bytes.size(), 20u);
  if (bytes.size() < 20) return counts;
  EXPECT_EQ(bytes.substr(0, 4), "glTF");
  uint32_t version, length, chunk_length;
  std::memcpy(&version, &bytes[4], 4);
  std::memcpy(&length, &bytes[8], 4);
  std::memcpy(&chunk_length, &bytes[12], 4);
  EXPECT_EQ(version, 2u);
  EXPECT_EQ(length, bytes.size());
  EXPECT_EQ(bytes.substr(16, 4), "JSON");
  counts.json = nlohmann::json::parse(bytes.substr(20, chunk_length));
  const nlohmann::json& json = counts.json;
  std::set<int> index_accessors;  // OCCT shares the buffers of an instanced part's meshes
  for (const auto& mesh : json["meshes"])
    for (const auto& primitive : mesh["primitives"])
      if (primitive.value("mode", 4) == 4) index_accessors.insert(primitive["indices"].get<int>());
  counts.stored_meshes = index_accessors.size();
  std::function<void(int)> visit = [&](int node) {
    const nlohmann::json& n = json["nodes"][node];
    if (n.contains("mesh"))
      for (const auto& primitive : json["meshes"][n["mesh"].get<int>()]["primitives"])
        if (primitive.value("mode", 4) == 4)  // triangles; the edges are LINES (mode 1)
          counts.drawn_triangles +=
              json["accessors"][primitive["indices"].get<int>()]["count"].get<int64_t>() / 3;
    if (n.contains("children"))
      for (const auto& child : n["children"]) visit(child.get<int>());
  };
  for (const auto& node : json["scenes"][json.value("scene", 0)]["nodes"]) visit(node.get<int>());
  return counts;
}

// Positions and triangles of a .obj file (1-based "f a//a b//b c//c" lines).
struct Obj {
  std::vector<gp_XYZ> positions;
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::vector<int>> lines;  // 1-based "l a b c" records
  int64_t normals = 0;
};

Obj ReadObj(const std::string& path) {
  Obj obj;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string tag;
    fields >> tag;
    if (tag == "v") {
      double x, y, z;
      fields >> x >> y >> z;
      obj.positions.emplace_back(x, y, z);
    } else if (tag == "f") {
      std::array<int, 3> t;
      std::string corner;
      for (int k = 0; k < 3; ++k) {
        fields >> corner;
        t[k] = std::stoi(corner.substr(0, corner.find('/')));
      }
      EXPECT_FALSE(fields >> corner) << "not a triangle: " << line;
      obj.triangles.push_back(t);
    } else if (tag == "l") {
      obj.lines.emplace_back();
      for (int index; fields >> index;) obj.lines.back().push_back(index);
    } else if (tag == "vn") {
      ++obj.normals;
    }
  }
  return obj;
}

// Every triangle's normal points away from the centre of the box it lies on.
void ExpectOutward(const std::vector<gp_XYZ>& xyz, const std::vector<std::array<int, 3>>& tris,
                   const std::vector<gp_XYZ>& box_centres) {
  for (const auto& t : tris) {
    gp_XYZ a = xyz[t[0]], b = xyz[t[1]], c = xyz[t[2]];
    gp_XYZ centroid = (a + b + c) / 3.0;
    gp_XYZ centre = box_centres[0];
    for (const gp_XYZ& candidate : box_centres)
      if ((candidate - centroid).Modulus() < (centre - centroid).Modulus()) centre = candidate;
    EXPECT_GT((b - a).Crossed(c - a).Dot(centroid - centre), 0.0);
  }
}

TEST_F(WritersTest, HandMadeMeshIsWatertightAndOutward) {
  auto model = LoadBrepBox();
  MeshResult result = MeshBoxes(*model);
  EXPECT_EQ(result.mesh.node_count(), 8 + 12 + 6);
  EXPECT_EQ(result.mesh.triangle_count(), 48);
  std::vector<gp_XYZ> xyz;
  for (int64_t i = 0; i < result.mesh.node_count(); ++i)
    xyz.emplace_back(result.mesh.xyz[3 * i], result.mesh.xyz[3 * i + 1],
                     result.mesh.xyz[3 * i + 2]);
  std::vector<std::array<int, 3>> tris;
  std::map<std::pair<int, int>, int> directed_edges;
  for (int64_t t = 0; t < result.mesh.triangle_count(); ++t) {
    const int32_t* v = &result.mesh.triangles[3 * t];
    tris.push_back({v[0], v[1], v[2]});
    for (int k = 0; k < 3; ++k) ++directed_edges[{v[k], v[(k + 1) % 3]}];
  }
  ExpectOutward(xyz, tris, {gp_XYZ(5, 10, 15)});
  for (const auto& [edge, count] : directed_edges) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed_edges.count({edge.second, edge.first}), 1u);  // closed and consistent
  }
}

TEST_F(WritersTest, EveryFormatReadsBack) {
  auto model = LoadBrepBox();
  MeshResult result = MeshBoxes(*model);
  const int64_t triangles = result.mesh.triangle_count();
  const int64_t nodes = result.mesh.node_count();

  ASSERT_TRUE(WriteMesh(*model, result, Path("box.msh")).ok());
  MshCounts msh = ReadMsh(Path("box.msh"));
  EXPECT_EQ(msh.nodes, nodes);
  EXPECT_EQ(msh.triangles, triangles);
  EXPECT_EQ(msh.surface_blocks, 6);
  EXPECT_EQ(msh.parametric_blocks, 0);  // plain nodes by default
  EXPECT_EQ(msh.lines.size(), 12u);     // one line block per edge, two segments each
  for (const auto& [edge, polyline] : msh.lines) EXPECT_EQ(polyline.size(), 3u) << edge;

  WriteOptions parametric;
  parametric.msh_parametric = true;
  parametric.edges = false;
  ASSERT_TRUE(WriteMesh(*model, result, Path("box_uv.msh"), parametric).ok());
  MshCounts msh_uv = ReadMsh(Path("box_uv.msh"));
  EXPECT_EQ(msh_uv.triangles, triangles);
  EXPECT_EQ(msh_uv.parametric_blocks, 12 + 6);  // one block per edge and per face
  EXPECT_TRUE(msh_uv.lines.empty());
  // Every edge and face node reads back with its t or (u, v), bit for bit.
  int64_t with_params = 0;
  for (int64_t i = 0; i < nodes; ++i) {
    int dim = result.mesh.node_dim[i];
    const std::vector<double>& read = msh_uv.params[i + 1];
    ASSERT_EQ(read.size(), static_cast<size_t>(dim)) << i;
    for (int k = 0; k < dim; ++k) EXPECT_EQ(read[k], result.mesh.node_param[2 * i + k]) << i;
    with_params += dim > 0;
  }
  EXPECT_EQ(with_params, 12 + 6);

  ASSERT_TRUE(WriteMesh(*model, result, Path("box.STL")).ok());
  std::string stl = ReadBytes(Path("box.STL"));
  ASSERT_EQ(stl.size(), 84u + 50u * triangles);
  uint32_t stl_count;
  std::memcpy(&stl_count, &stl[80], 4);
  EXPECT_EQ(stl_count, triangles);
  for (int64_t t = 0; t < triangles; ++t) {
    float f[12];  // normal, 3 corners
    std::memcpy(f, &stl[84 + 50 * t], sizeof(f));
    gp_XYZ normal(f[0], f[1], f[2]), a(f[3], f[4], f[5]), b(f[6], f[7], f[8]),
        c(f[9], f[10], f[11]);
    EXPECT_NEAR(normal.Modulus(), 1.0, 1e-6);
    EXPECT_GT(normal.Dot((b - a).Crossed(c - a)), 0.0);
    EXPECT_GT(normal.Dot((a + b + c) / 3.0 - gp_XYZ(5, 10, 15)), 0.0);
  }

  // Per-triangle deviations (a hand-made mesh has none; these need all their digits).
  for (int64_t t = 0; t < triangles; ++t)
    result.mesh.triangle_deviation.push_back(1e-3 * static_cast<double>(t + 1) / 7.0);
  ASSERT_TRUE(WriteMesh(*model, result, Path("box.ply")).ok());
  std::ifstream ply(Path("box.ply"));
  std::string line;
  int64_t ply_vertices = -1, ply_faces = -1;
  bool ply_deviation = false;
  while (std::getline(ply, line) && line != "end_header") {
    ply_deviation = ply_deviation || line == "property double deviation";
    std::sscanf(line.c_str(), "element vertex %ld", &ply_vertices);
    std::sscanf(line.c_str(), "element face %ld", &ply_faces);
  }
  // Vertices per face: each face has its own copy of its 9 nodes, with the face's exact
  // normal (a box face's normal is its axis), and node_id gives back the watertight mesh.
  EXPECT_EQ(ply_vertices, 6 * 9);
  ASSERT_EQ(ply_faces, triangles);
  ASSERT_TRUE(ply_deviation);
  ASSERT_EQ(static_cast<int64_t>(result.mesh.triangle_deviation.size()), triangles);
  std::vector<int64_t> node_of(ply_vertices);
  std::vector<gp_XYZ> normal_of(ply_vertices);
  std::set<int64_t> node_ids;
  for (int64_t i = 0; i < ply_vertices; ++i) {
    double x, y, z, nx, ny, nz;
    int64_t node;
    ply >> x >> y >> z >> nx >> ny >> nz >> node;
    ASSERT_TRUE(node >= 0 && node < nodes) << node;
    EXPECT_EQ(x, result.mesh.xyz[3 * node]);
    EXPECT_EQ(z, result.mesh.xyz[3 * node + 2]);
    EXPECT_NEAR(std::abs(nx) + std::abs(ny) + std::abs(nz), 1.0, 1e-6);  // an axis
    EXPECT_NEAR(std::sqrt(nx * nx + ny * ny + nz * nz), 1.0, 1e-6);
    node_of[i] = node;
    normal_of[i] = gp_XYZ(nx, ny, nz);
    node_ids.insert(node);
  }
  EXPECT_EQ(static_cast<int64_t>(node_ids.size()), nodes);
  std::map<int64_t, int> face_of_vertex;
  for (int64_t t = 0; t < triangles; ++t) {
    int count, face_id;
    int64_t corner[3];
    double deviation;
    ply >> count >> corner[0] >> corner[1] >> corner[2] >> face_id >> deviation;
    EXPECT_EQ(count, 3);
    EXPECT_EQ(face_id, result.mesh.triangle_face[t]);
    EXPECT_EQ(deviation, result.mesh.triangle_deviation[t]);  // shortest round-trip text
    const int32_t* mesh_corner = &result.mesh.triangles[3 * t];
    auto at = [&](int32_t node) {
      const double* p = &result.mesh.xyz[3 * static_cast<int64_t>(node)];
      return gp_XYZ(p[0], p[1], p[2]);
    };
    gp_XYZ a = at(mesh_corner[0]), b = at(mesh_corner[1]), c = at(mesh_corner[2]);
    for (int k = 0; k < 3; ++k) {
      ASSERT_TRUE(corner[k] >= 0 && corner[k] < ply_vertices);
      EXPECT_EQ(node_of[corner[k]], mesh_corner[k]);  // the same triangle, node for node
      // The face's normal: along the triangle's own and outward.
      EXPECT_NEAR(normal_of[corner[k]].Dot((b - a).Crossed(c - a).Normalized()), 1.0, 1e-9);
      auto [it, added] = face_of_vertex.try_emplace(corner[k], face_id);
      EXPECT_EQ(it->second, face_id) << "a vertex shared by two faces";
    }
  }
  EXPECT_TRUE(ply.good());

  ASSERT_TRUE(WriteMesh(*model, result, Path("box.vtu")).ok());
  std::string vtu = ReadBytes(Path("box.vtu"));
  EXPECT_NE(vtu.find("NumberOfPoints=\"" + std::to_string(6 * 9) + "\" NumberOfCells=\"" +
                     std::to_string(triangles) + "\""),
            std::string::npos);
  EXPECT_NE(vtu.find("Name=\"node_id\""), std::string::npos);
  EXPECT_NE(vtu.find("Name=\"face_id\""), std::string::npos);
  EXPECT_NE(vtu.find("Name=\"deviation\""), std::string::npos);
  EXPECT_NE(vtu.find("Name=\"Normals\""), std::string::npos);

  ASSERT_TRUE(WriteMesh(*model, result, Path("box.obj")).ok());
  Obj obj = ReadObj(Path("box.obj"));
  EXPECT_EQ(static_cast<int64_t>(obj.triangles.size()), triangles);
  std::vector<gp_XYZ> obj_xyz = {gp_XYZ()};  // 1-based
  obj_xyz.insert(obj_xyz.end(), obj.positions.begin(), obj.positions.end());
  ExpectOutward(obj_xyz, obj.triangles, {gp_XYZ(5, 10, 15)});
  // The 12 edges as polylines on vertex records of their own (20 edge and vertex nodes), which
  // lie where the mesh's nodes are; every vertex has its normal.
  auto lines = BuildEdgeLines(*model, result.mesh);
  ASSERT_TRUE(lines.ok());
  ASSERT_EQ(obj.lines.size(), 12u);
  EXPECT_EQ(static_cast<int64_t>(obj.positions.size()), 6 * 9 + 8 + 12);
  EXPECT_EQ(obj.normals, static_cast<int64_t>(obj.positions.size()));
  for (size_t i = 0; i < obj.lines.size(); ++i) {
    ASSERT_EQ(obj.lines[i].size(), (*lines)[i].nodes.size());
    for (size_t k = 0; k < obj.lines[i].size(); ++k) {
      int index = obj.lines[i][k];
      ASSERT_TRUE(index > 6 * 9 && index < static_cast<int>(obj_xyz.size())) << index;
      const double* node = &result.mesh.xyz[3 * (*lines)[i].nodes[k]];
      EXPECT_EQ(obj_xyz[index].X(), node[0]);
      EXPECT_EQ(obj_xyz[index].Z(), node[2]);
    }
  }
  WriteOptions no_edges;
  no_edges.edges = false;
  ASSERT_TRUE(WriteMesh(*model, result, Path("plain.obj"), no_edges).ok());
  EXPECT_TRUE(ReadObj(Path("plain.obj")).lines.empty());
  EXPECT_EQ(ReadObj(Path("plain.obj")).positions.size(), 6u * 9u);
  ASSERT_TRUE(WriteMesh(*model, result, Path("plain.msh"), no_edges).ok());
  EXPECT_TRUE(ReadMsh(Path("plain.msh")).lines.empty());

  ASSERT_TRUE(WriteMesh(*model, result, Path("box.glb")).ok());
  GlbCounts glb = ReadGlb(Path("box.glb"));
  EXPECT_EQ(glb.drawn_triangles, triangles);
}

TEST_F(WritersTest, StepModelThroughItsDocument) {
  auto model = LoadStepBox();
  ASSERT_FALSE(model->doc.IsNull());
  MeshResult result = MeshBoxes(*model);
  ASSERT_TRUE(WriteMesh(*model, result, Path("box.obj")).ok());
  Obj obj = ReadObj(Path("box.obj"));
  EXPECT_EQ(static_cast<int64_t>(obj.triangles.size()), result.mesh.triangle_count());
  std::vector<gp_XYZ> obj_xyz = {gp_XYZ()};
  obj_xyz.insert(obj_xyz.end(), obj.positions.begin(), obj.positions.end());
  ExpectOutward(obj_xyz, obj.triangles, {gp_XYZ(5, 10, 15)});
  ASSERT_TRUE(WriteMesh(*model, result, Path("box.glb")).ok());
  EXPECT_EQ(ReadGlb(Path("box.glb")).drawn_triangles, result.mesh.triangle_count());
}

TEST_F(WritersTest, InstancesShareOneGltfMesh) {
  auto model = LoadInstancedPair();
  ASSERT_EQ(model->face_count(), 12);
  MeshResult result = MeshBoxes(*model);
  const int64_t triangles = result.mesh.triangle_count();
  ASSERT_EQ(triangles, 96);

  ASSERT_TRUE(WriteMesh(*model, result, Path("pair.glb")).ok());
  GlbCounts glb = ReadGlb(Path("pair.glb"));
  EXPECT_EQ(glb.drawn_triangles, triangles);
  EXPECT_EQ(glb.stored_meshes, 1u);  // stored once, placed twice
  EXPECT_NE(glb.json.dump().find("brick"), std::string::npos);
  // The stored mesh's _FACE_ID are the lent instance's (faces 1..6); the node that draws it at
  // the other instance maps them to that instance's faces, each the lent face moved by +100 x.
  int mapped_nodes = 0;
  for (const auto& node : glb.json["nodes"]) {
    if (!node.contains("mesh")) continue;
    if (!node.contains("extras")) continue;
    ++mapped_nodes;
    const auto& map = node["extras"]["rdmesh"]["face_ids"];
    ASSERT_EQ(map.size(), 6u);
    std::set<int> to;
    for (const auto& [from, own] : map.items()) {
      const int lent = std::stoi(from), face = own.get<int>();
      EXPECT_TRUE(lent >= 1 && lent <= 6) << lent;
      to.insert(face);
      std::set<std::array<double, 3>> moved, own_corners;
      for (TopExp_Explorer it(model->face(lent), TopAbs_VERTEX); it.More(); it.Next()) {
        gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(it.Current()));
        moved.insert({std::round(p.X() + 100.0), std::round(p.Y()), std::round(p.Z())});
      }
      for (TopExp_Explorer it(model->face(face), TopAbs_VERTEX); it.More(); it.Next()) {
        gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(it.Current()));
        own_corners.insert({std::round(p.X()), std::round(p.Y()), std::round(p.Z())});
      }
      EXPECT_EQ(own_corners, moved) << lent << " -> " << face;
    }
    EXPECT_EQ(to, (std::set<int>{7, 8, 9, 10, 11, 12}));
  }
  EXPECT_EQ(mapped_nodes, 1);

  ASSERT_TRUE(WriteMesh(*model, result, Path("pair.obj")).ok());
  Obj obj = ReadObj(Path("pair.obj"));
  EXPECT_EQ(static_cast<int64_t>(obj.triangles.size()), triangles);
  std::vector<gp_XYZ> obj_xyz = {gp_XYZ()};
  obj_xyz.insert(obj_xyz.end(), obj.positions.begin(), obj.positions.end());
  ExpectOutward(obj_xyz, obj.triangles, {gp_XYZ(5, 10, 15), gp_XYZ(105, 10, 15)});

  ASSERT_TRUE(WriteMesh(*model, result, Path("pair.msh")).ok());
  EXPECT_EQ(ReadMsh(Path("pair.msh")).triangles, triangles);
}

TEST_F(WritersTest, ModelKeepsItsOwnTriangulations) {
  auto model = LoadBrepBox();
  MeshResult result = MeshBoxes(*model);
  result.faces[2].status = FaceStatus::kFailed;  // face 3 lends nothing
  TopLoc_Location location;
  for (int id = 1; id <= model->face_count(); ++id)
    EXPECT_TRUE(BRep_Tool::Triangulation(model->face(id), location).IsNull());
  ASSERT_TRUE(WriteMesh(*model, result, Path("box.glb")).ok());
  ASSERT_TRUE(WriteMesh(*model, result, Path("box.obj")).ok());
  for (int id = 1; id <= model->face_count(); ++id)
    EXPECT_TRUE(BRep_Tool::Triangulation(model->face(id), location).IsNull());
  EXPECT_EQ(ReadGlb(Path("box.glb")).drawn_triangles, 5 * 8);
}

TEST_F(WritersTest, Errors) {
  auto model = LoadBrepBox();
  MeshResult result = MeshBoxes(*model);
  for (const std::string& ext : SupportedOutputFormats()) {
    std::string path = Path("missing_dir/out" + ext);
    Status status = WriteMesh(*model, result, path);
    EXPECT_EQ(status.code(), StatusCode::kIoError) << ext << ": " << status.ToString();
    EXPECT_NE(status.message().find(path), std::string::npos) << status.message();
  }
  Status unknown = WriteMesh(*model, result, Path("out.xyz"));
  EXPECT_EQ(unknown.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(unknown.message().find(".msh"), std::string::npos);

  MeshResult broken = result;
  broken.mesh.triangles[5] = 9999;
  EXPECT_EQ(WriteMesh(*model, broken, Path("broken.stl")).code(), StatusCode::kInternal);
  MeshResult unclassified = result;
  unclassified.mesh.node_dim.clear();
  EXPECT_EQ(WriteMesh(*model, unclassified, Path("u.msh")).code(), StatusCode::kInternal);
}

TEST_F(WritersTest, EmptyMeshWritesValidFiles) {
  auto model = LoadBrepBox();
  MeshResult result;
  result.faces.resize(model->face_count());
  for (const std::string& ext : SupportedOutputFormats())
    EXPECT_TRUE(WriteMesh(*model, result, Path("empty" + ext)).ok()) << ext;
  EXPECT_EQ(ReadMsh(Path("empty.msh")).triangles, 0);
}

}  // namespace
}  // namespace rdmesh
