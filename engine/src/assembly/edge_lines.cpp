// BuildEdgeLines: every B-rep edge of an assembled mesh as a polyline of its nodes, with the
// faces beside it and whether it is a seam, degenerate or sharp.
//
// The polylines come from the node classification alone (edge nodes sorted by curve parameter
// between the nodes of the edge's vertices), so a mesh rebuilt from a remote run, which carries
// the classification but not the edge grids, gives the same lines as the run itself.

#include "assembly/edge_lines.h"

#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom_Surface.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "boundary/pcurves.h"
#include "core/parallel.h"
#include "model/model.h"
#include "rdmesh/engine.h"

namespace rdmesh {

namespace {

constexpr double kPi = 3.14159265358979323846;

// The outward unit normal of one face beside an edge, along the edge's pcurve on it (from the
// run's table), the surface looked up once.
class FaceNormalOnEdge {
 public:
  FaceNormalOnEdge(const FacePcurves& pcurves, int face_id, const TopoDS_Face& face, int edge_id,
                   const TopoDS_Edge& edge) {
    try {
      pcurve_ = pcurves.Find(face_id, face, edge_id, edge).curve;
      // The bare surface: an adaptor would first compute the face's (u,v) bounds.
      surface_ = BRep_Tool::Surface(face, location_);
      reversed_ = face.Orientation() == TopAbs_REVERSED;
    } catch (const Standard_Failure&) {
      pcurve_.Nullify();
    }
  }
  // At parameter t; nothing where the surface is singular or the face has no pcurve for the edge.
  std::optional<gp_Dir> At(double t) const {
    if (pcurve_.IsNull() || surface_.IsNull()) return std::nullopt;
    try {
      gp_Pnt2d uv = pcurve_->Value(t);
      gp_Pnt point;
      gp_Vec du, dv;
      surface_->D1(uv.X(), uv.Y(), point, du, dv);
      gp_Vec normal = du.Crossed(dv);
      if (normal.Magnitude() <= 1e-12 * std::max(1.0, du.Magnitude() * dv.Magnitude()))
        return std::nullopt;
      normal.Transform(location_.Transformation());
      if (reversed_) normal.Reverse();
      return gp_Dir(normal);
    } catch (const Standard_Failure&) {
      return std::nullopt;
    }
  }

 private:
  Handle(Geom2d_Curve) pcurve_;
  Handle(Geom_Surface) surface_;
  TopLoc_Location location_;
  bool reversed_ = false;
};

// Largest angle (degrees) between the faces' exact normals over the curve parameters `ts` (the
// edge's nodes); -1 when a normal is undefined at every parameter.
double Dihedral(const Model& model, const FacePcurves& pcurves, int edge_id,
                const TopoDS_Edge& edge, const std::vector<int32_t>& faces,
                const std::vector<double>& ts) {
  double largest = -1.0;
  std::vector<FaceNormalOnEdge> sides;
  for (int32_t f : faces) sides.emplace_back(pcurves, f, model.face(f), edge_id, edge);
  std::vector<gp_Dir> normals;
  for (double t : ts) {
    normals.clear();
    for (const FaceNormalOnEdge& side : sides) {
      std::optional<gp_Dir> normal = side.At(t);
      if (!normal) break;
      normals.push_back(*normal);
    }
    if (normals.size() != faces.size()) continue;  // singular here (a cone's apex)
    for (size_t i = 0; i < normals.size(); ++i)
      for (size_t j = i + 1; j < normals.size(); ++j)
        largest = std::max(largest, normals[i].Angle(normals[j]) * 180.0 / kPi);
  }
  return largest;
}

// The mesh node of vertex `v`; when the vertex has none (it was merged into a neighbour across
// an edge shorter than its tolerance), the vertex node nearest to its point.
std::optional<int32_t> VertexNode(const Model& model, const Mesh& mesh,
                                  const std::vector<int32_t>& vertex_node,
                                  const std::vector<int32_t>& vertex_nodes, int v) {
  if (v >= 1 && v < static_cast<int>(vertex_node.size()) && vertex_node[v] >= 0)
    return vertex_node[v];
  if (v < 1 || v > model.vertices.Extent() || vertex_nodes.empty()) return std::nullopt;
  gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(model.vertices(v)));
  int32_t best = vertex_nodes.front();
  double best_distance = std::numeric_limits<double>::infinity();
  for (int32_t node : vertex_nodes) {
    const double* q = &mesh.xyz[3 * static_cast<int64_t>(node)];
    double d = p.SquareDistance(gp_Pnt(q[0], q[1], q[2]));
    if (d < best_distance) best_distance = d, best = node;
  }
  return best;
}

}  // namespace

Result<std::vector<EdgeLine>> BuildEdgeLines(const Model& model, const Mesh& mesh,
                                             double sharp_angle, int threads) {
  return BuildEdgeLines(model, mesh, sharp_angle, threads, FacePcurves());  // all from OCCT
}

Result<std::vector<EdgeLine>> BuildEdgeLines(const Model& model, const Mesh& mesh,
                                             double sharp_angle, int threads,
                                             const FacePcurves& pcurves) {
  const int64_t nodes = mesh.node_count();
  if (mesh.node_dim.size() != static_cast<size_t>(nodes) ||
      mesh.node_entity.size() != static_cast<size_t>(nodes) ||
      mesh.node_param.size() != 2 * static_cast<size_t>(nodes))
    return Status(StatusCode::kInternal, "the mesh lacks node classification (node_dim, ...)");
  const int ne = model.edge_count();
  const int nv = model.vertices.Extent();

  // Nodes by entity: vertex -> node, edge -> (t, node).
  std::vector<int32_t> vertex_node(nv + 1, -1), vertex_nodes;
  std::vector<std::vector<std::pair<double, int32_t>>> edge_nodes(ne + 1);
  for (int64_t i = 0; i < nodes; ++i) {
    int entity = mesh.node_entity[i];
    auto node = static_cast<int32_t>(i);
    if (mesh.node_dim[i] == 0 && entity >= 1 && entity <= nv) {
      if (vertex_node[entity] < 0) vertex_node[entity] = node;
      vertex_nodes.push_back(node);
    } else if (mesh.node_dim[i] == 1 && entity >= 1 && entity <= ne) {
      edge_nodes[entity].push_back({mesh.node_param[2 * i], node});
    }
  }

  // Faces with triangles, and the faces beside each edge.
  std::vector<bool> meshed(model.face_count() + 1, false);
  for (int32_t f : mesh.triangle_face)
    if (f >= 1 && f <= model.face_count()) meshed[f] = true;

  // Each edge on its own (its slot, its own nodes), then in edge id order.
  std::vector<std::optional<EdgeLine>> built(ne);
  const ParallelRunner runner(threads);
  runner.For(1, ne + 1, [&](int e) {
    try {  // an edge OCCT cannot answer for is left out, the others still get lines
      const TopoDS_Edge& edge = model.edge(e);
      EdgeLine line;
      line.edge_id = e;
      bool any_meshed = false;
      for (int f : model.edge_faces[e - 1]) {  // each once, ascending
        line.faces.push_back(f);
        any_meshed = any_meshed || meshed[f];
        line.seam = line.seam || pcurves.IsSeam(f, model.face(f), e, edge);
      }
      if (!any_meshed) return;

      TopoDS_Vertex first, last;
      TopExp::Vertices(TopoDS::Edge(edge.Oriented(TopAbs_FORWARD)), first, last);
      std::optional<int32_t> start =
          VertexNode(model, mesh, vertex_node, vertex_nodes,
                     first.IsNull() ? 0 : model.vertices.FindIndex(first));
      std::optional<int32_t> end = VertexNode(model, mesh, vertex_node, vertex_nodes,
                                              last.IsNull() ? 0 : model.vertices.FindIndex(last));
      if (!start || !end) return;  // a mesh without vertex nodes: nothing to anchor the line
      std::vector<std::pair<double, int32_t>>& inner = edge_nodes[e];
      std::sort(inner.begin(), inner.end());
      line.nodes.push_back(*start);
      for (const auto& [t, node] : inner) line.nodes.push_back(node);
      line.nodes.push_back(*end);
      line.nodes.erase(std::unique(line.nodes.begin(), line.nodes.end()), line.nodes.end());

      line.degenerate = BRep_Tool::Degenerated(edge) || line.nodes.size() < 2;
      if (!line.degenerate && !line.seam && line.faces.size() >= 2) {
        double first_t, last_t;
        BRep_Tool::Range(edge, first_t, last_t);
        std::vector<double> ts = {first_t};
        for (const auto& [t, node] : inner) ts.push_back(t);
        ts.push_back(last_t);
        line.dihedral = Dihedral(model, pcurves, e, edge, line.faces, ts);
      }
      const bool free = line.faces.size() == 1 && !line.seam && !line.degenerate;
      line.sharp = free || line.dihedral > sharp_angle;
      built[e - 1] = std::move(line);
    } catch (const Standard_Failure&) {
    }
  });
  std::vector<EdgeLine> lines;
  for (std::optional<EdgeLine>& line : built)
    if (line) lines.push_back(std::move(*line));
  return lines;
}

}  // namespace rdmesh
