#include "face/cdt.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <list>
#include <map>

namespace rdmesh {

namespace {

struct FaceInfo {
  int nesting_level = -1;
  bool in_domain() const { return nesting_level % 2 == 1; }
};

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using Fbb = CGAL::Triangulation_face_base_with_info_2<FaceInfo, Kernel>;
using Fb = CGAL::Constrained_triangulation_face_base_2<Kernel, Fbb>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Itag = CGAL::No_constraint_intersection_requiring_constructions_tag;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, Itag>;
using Point = Cdt::Point;

// Flood fill from the infinite face: crossing a constraint raises the nesting level, but for
// `inner` ones (sorted pairs of vertex infos, which are point index + 1).
void MarkDomains(Cdt& cdt, const std::vector<std::pair<int, int>>& inner) {
  auto bounds = [&](const Cdt::Edge& e) {
    if (!cdt.is_constrained(e)) return false;
    if (inner.empty()) return true;
    const int a = e.first->vertex(Cdt::cw(e.second))->info();
    const int b = e.first->vertex(Cdt::ccw(e.second))->info();
    return !std::binary_search(inner.begin(), inner.end(),
                               std::make_pair(std::min(a, b), std::max(a, b)));
  };
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info().nesting_level = -1;
  std::list<Cdt::Edge> border;
  auto fill = [&](Cdt::Face_handle start, int level) {
    if (start->info().nesting_level != -1) return;
    std::list<Cdt::Face_handle> queue = {start};
    while (!queue.empty()) {
      Cdt::Face_handle fh = queue.front();
      queue.pop_front();
      if (fh->info().nesting_level != -1) continue;
      fh->info().nesting_level = level;
      for (int i = 0; i < 3; ++i) {
        Cdt::Edge e(fh, i);
        Cdt::Face_handle n = fh->neighbor(i);
        if (n->info().nesting_level == -1) {
          if (bounds(e))
            border.push_back(e);
          else
            queue.push_back(n);
        }
      }
    }
  };
  fill(cdt.infinite_face(), 0);
  while (!border.empty()) {
    Cdt::Edge e = border.front();
    border.pop_front();
    Cdt::Face_handle n = e.first->neighbor(e.second);
    if (n->info().nesting_level == -1) fill(n, e.first->info().nesting_level + 1);
  }
}

}  // namespace

Status ConstrainedTriangulation(const std::vector<Vec2>& points,
                                const std::vector<std::array<int, 2>>& segments,
                                const std::vector<std::array<int, 2>>& inner,
                                const Context* context, CdtResult* result) {
  result->triangles.clear();
  result->constrained.clear();
  try {
    Cdt cdt;
    std::vector<Cdt::Vertex_handle> handles(points.size());
    // One insertion can flip a long fan (points in boundary order, many on one line or circle),
    // which under a sanitizer takes a tenth of a second and more on a dense boundary: poll at
    // every insertion (a deadline test ran 3.3 s late under ASan when polling every 16th).
    for (size_t i = 0; i < points.size(); ++i) {
      if (context && context->ShouldStop()) return context->StopStatus();
      size_t before = cdt.number_of_vertices();
      handles[i] = cdt.insert(Point(points[i].x, points[i].y));
      if (cdt.number_of_vertices() == before)
        return Status(StatusCode::kInternal, "two boundary nodes coincide in (u,v)");
      handles[i]->info() = static_cast<int>(i) + 1;
    }
    for (const auto* list : {&segments, &inner}) {
      for (const auto& s : *list) {
        if (context && context->ShouldStop()) return context->StopStatus();
        if (s[0] == s[1]) continue;
        cdt.insert_constraint(handles[s[0]], handles[s[1]]);
      }
    }
    std::vector<std::pair<int, int>> inner_pairs;
    for (const auto& s : inner)
      inner_pairs.push_back({std::min(s[0], s[1]) + 1, std::max(s[0], s[1]) + 1});
    std::sort(inner_pairs.begin(), inner_pairs.end());
    if (cdt.number_of_vertices() != points.size())
      return Status(StatusCode::kInternal, "the boundary loops overlap in (u,v)");
    // Points all on one line leave no face to mark (and CGAL's faces are not set up for it).
    if (cdt.dimension() < 2)
      return Status(StatusCode::kInternal, "the boundary loops enclose no area in (u,v)");
    MarkDomains(cdt, inner_pairs);
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      if (!f->info().in_domain()) continue;
      std::array<int, 3> t;
      std::array<bool, 3> c;
      for (int i = 0; i < 3; ++i) {
        t[i] = f->vertex(i)->info() - 1;
        c[i] = f->is_constrained(i);
      }
      if (t[0] < 0 || t[1] < 0 || t[2] < 0)
        return Status(StatusCode::kInternal, "the triangulation made a point of its own");
      result->triangles.push_back(t);
      result->constrained.push_back(c);
    }
  } catch (const Cdt::Intersection_of_constraints_exception&) {
    return Status(StatusCode::kInternal, "boundary loops intersect in (u,v)");
  } catch (const std::exception& e) {
    return Status(StatusCode::kInternal, std::string("triangulation failed: ") + e.what());
  }
  if (result->triangles.empty())
    return Status(StatusCode::kInternal, "the boundary loops enclose no area in (u,v)");
  return Status::Ok();
}

}  // namespace rdmesh
