#include "face/face_mesher.h"

#include <BRep_Tool.hxx>
#include <GeomLProp_SLProps.hxx>
#include <Geom_Surface.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "boundary/face_domain.h"
#include "face/cdt.h"
#include "face/first_triangulation.h"
#include "face/lattice_seeds.h"
#include "face/refine.h"
#include "face/refine_constants.h"
#include "face/unfold.h"
#include "face/work_mesh.h"
#include "geometry/offset_surface.h"
#include "geometry/surface.h"
#include "geometry/surface_type.h"
#include "model/model.h"
#include "rdmesh/options.h"

namespace rdmesh {

namespace {

FaceMesh Failed(FaceMesh f, const std::string& reason) {
  f.status = FaceStatus::kFailed;
  f.reason = reason;
  f.xyz.clear(), f.uv.clear(), f.normals.clear(), f.triangles.clear();
  f.triangle_deviation.clear();
  return f;
}

double TriangleArea(const FaceMesh& f, int t) {
  const int32_t* x = &f.triangles[3 * t];
  Vec3 p[3];
  for (int i = 0; i < 3; ++i) p[i] = {f.xyz[3 * x[i]], f.xyz[3 * x[i] + 1], f.xyz[3 * x[i] + 2]};
  return Area(p[0], p[1], p[2]);
}

// Compacts the live part of the working mesh into a FaceMesh, oriented outward. Triangles with
// two corners at one point (at a pole) vanish; with `drop_pole_edges` (a face with singular
// lines, whose ends are two edges' points, equal up to rounding) so do all on a pole edge.
// `deviation` holds the estimated deviation of each working-mesh triangle (RefineStats).
void Extract(const WorkMesh& m, const std::vector<double>& deviation, bool reversed,
             bool drop_pole_edges, FaceMesh* f, std::vector<NodeRef>* refs) {
  std::vector<int> index(m.node_count(), -1);
  f->xyz.reserve(3 * m.node_count());
  f->uv.reserve(2 * m.node_count());
  f->normals.reserve(3 * m.node_count());
  refs->reserve(m.node_count());
  f->triangles.reserve(3 * m.tri.size());
  f->triangle_deviation.reserve(m.tri.size());
  for (int t = 0; t < static_cast<int>(m.tri.size()); ++t) {
    if (!m.alive[t]) continue;
    const Tri& x = m.tri[t];
    const Vec3 &a = m.xyz[x[0]], &b = m.xyz[x[1]], &c = m.xyz[x[2]];
    auto same = [](const Vec3& p, const Vec3& q) { return p.x == q.x && p.y == q.y && p.z == q.z; };
    if (same(a, b) || same(b, c) || same(c, a)) continue;
    if (drop_pole_edges &&
        (m.kind[t][0] == EdgeKind::kSplittable || m.kind[t][1] == EdgeKind::kSplittable ||
         m.kind[t][2] == EdgeKind::kSplittable))
      continue;
    int32_t ids[3];
    for (int i = 0; i < 3; ++i) {
      int v = x[i];
      if (index[v] < 0) {
        index[v] = static_cast<int>(f->xyz.size() / 3);
        f->xyz.insert(f->xyz.end(), {m.xyz[v].x, m.xyz[v].y, m.xyz[v].z});
        f->uv.insert(f->uv.end(), {m.uv[v].x, m.uv[v].y});
        Vec3 n = reversed ? -m.normal[v] : m.normal[v];
        f->normals.insert(f->normals.end(), {n.x, n.y, n.z});
        NodeRef r = m.ref[v];
        if (r.dim == 2) r.entity = f->face_id;
        refs->push_back(r);
      }
      ids[i] = index[v];
    }
    if (reversed) std::swap(ids[1], ids[2]);
    f->triangles.insert(f->triangles.end(), {ids[0], ids[1], ids[2]});
    f->triangle_deviation.push_back(deviation[t]);
  }
}

// Where the surface's first derivatives leave the normal undefined (a pole, as a sphere's), the
// exact normal from OCCT's GeomLProp_SLProps (higher derivatives) instead of the refinement's
// estimate (Surface::Normal: the mean of four normals around the pole, about a degree off).
// Boundary nodes only, where poles lie; it changes no node or triangle. `f` is in the face's
// own (u,v): not for a face meshed on its B-spline conversion.
void ExactPoleNormals(const TopoDS_Face& face, const std::vector<NodeRef>& refs, FaceMesh* f) {
  TopLoc_Location location;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face, location);
  if (surface.IsNull() || refs.size() * 3 != f->normals.size() || refs.size() * 2 != f->uv.size())
    return;
  const gp_Trsf to_world = location.Transformation();
  for (size_t i = 0; i < refs.size(); ++i) {
    if (refs[i].dim > 1) continue;
    const double u = f->uv[2 * i], v = f->uv[2 * i + 1];
    gp_Pnt point;
    gp_Vec du, dv;
    surface->D1(u, v, point, du, dv);
    const double scale = du.SquareMagnitude() + dv.SquareMagnitude();
    if (scale > 0 && du.Crossed(dv).SquareMagnitude() > 1e-16 * scale * scale) continue;
    GeomLProp_SLProps props(surface, u, v, 2, Precision::Confusion());
    if (!props.IsNormalDefined()) continue;  // a cone's apex: no one normal
    gp_Vec exact(props.Normal());
    exact.Transform(to_world);
    double* n = &f->normals[3 * i];
    const gp_Vec estimate(n[0], n[1], n[2]);
    if (estimate.Magnitude() == 0.0) continue;
    double angle = exact.Angle(estimate);
    if (angle > M_PI / 2) exact.Reverse(), angle = M_PI - angle;
    if (angle > 5.0 * M_PI / 180.0) continue;  // not the pole the estimate is near
    n[0] = exact.X(), n[1] = exact.Y(), n[2] = exact.Z();
  }
}

// A view of an evaluator owned elsewhere (FaceSurfaces): the same values, one call further.
class LentSurface final : public Surface {
 public:
  explicit LentSurface(Surface* inner) : inner_(inner) {
    umin = inner_->umin, umax = inner_->umax, vmin = inner_->vmin, vmax = inner_->vmax;
    uknots = inner_->uknots, vknots = inner_->vknots;
    quadric = inner_->quadric;
    planar = inner_->planar;
  }
  Vec3 Point(double u, double v) override { return inner_->Point(u, v); }
  Vec3 Normal(double u, double v) override { return inner_->Normal(u, v); }

 private:
  Surface* inner_;
};

// The evaluator of a face: lent by `surfaces` when there are some, else made for this use.
std::unique_ptr<Surface> FaceSurface(const Model& model, const FacePcurves& pcurves, int face_id,
                                     bool nurbs, FaceSurfaces* surfaces) {
  if (surfaces) return surfaces->Lend(model, pcurves, face_id, nurbs);
  return MakeFaceSurface(model.face(face_id), nurbs, pcurves.Bounds(model, face_id));
}

// The largest tolerance of the face's edges.
double EdgeTolerance(const TopoDS_Face& face) {
  double tolerance = 0;
  for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next())
    tolerance = std::max(tolerance, BRep_Tool::Tolerance(TopoDS::Edge(ex.Current())));
  return tolerance;
}

// A face left unmeshed because the run was asked to stop (the run's status says why).
FaceMesh Stopped(FaceMesh f, const Context& context) {
  f = Failed(std::move(f), context.StopStatus().message());
  f.status = FaceStatus::kSkipped;
  return f;
}

}  // namespace

std::string BrepReason(double deviation, const BrepGaps& gaps, double missed) {
  char text[400];
  int n = std::snprintf(text, sizeof(text),
                        "the B-rep prevents the requested deviation %.3g: its edge tolerance is up "
                        "to %.3g",
                        deviation, gaps.tolerance);
  auto add = [&](const char* format, double value) {
    if (n > 0 && n < int(sizeof(text)))
      n += std::snprintf(text + n, sizeof(text) - n, format, value);
  };
  // Where the pcurves miss the edges' curves by more than the edges miss the surface, that is
  // what the face sees (a reader's projection on the wrong turn): the edges themselves may lie on
  // it.
  const bool trim = gaps.trim > deviation && gaps.trim > gaps.edges;
  if (gaps.edges > deviation || !trim)
    add(" and its edges lie up to %.3g off its surface", trim ? gaps.edges : gaps.Largest());
  if (trim)
    add(gaps.edges > deviation ? ", its pcurves up to %.3g from its edges' curves"
                               : " and its pcurves lie up to %.3g from its edges' curves",
        gaps.trim);
  if (missed > deviation + std::max(gaps.Largest(), gaps.tolerance))
    add("; beyond that, some triangles could not be refined to the criteria without folding (up "
        "to %.3g)",
        missed);
  return text;
}

std::string StuckFoldReason(int64_t folds, int64_t over) {
  char text[240];
  std::snprintf(text, sizeof(text),
                "some triangles could not be refined to the criteria without folding: %lld of the "
                "%lld over them kept their fold through %d splits in a row (as where the "
                "surface's normal reverses inside the face)",
                static_cast<long long>(folds), static_cast<long long>(over), kFoldRun);
  return text;
}

FaceSurfaces::FaceSurfaces(int face_count) : exact_(face_count), nurbs_(face_count) {}
FaceSurfaces::~FaceSurfaces() = default;

std::unique_ptr<Surface> FaceSurfaces::Lend(const Model& model, const FacePcurves& pcurves,
                                            int face_id, bool nurbs) {
  std::unique_ptr<Surface>& slot = (nurbs ? nurbs_ : exact_)[face_id - 1];
  if (!slot) slot = MakeFaceSurface(model.face(face_id), nurbs, pcurves.Bounds(model, face_id));
  return std::make_unique<LentSurface>(slot.get());
}

namespace {

// One face's meshing, as the named steps MeshFace runs in turn. Each step that can end the face
// early returns false and leaves `f` saying why (failed, or skipped when the run was stopped).
class FaceRun {
 public:
  // `vertices_to_surface`: the domain's vertex nodes at the surface's nearest points to the
  // vertices (MoveVertexNodesToSurface), for a face whose first mesh kept folds (RetryFolds).
  FaceRun(const Model& model, const FacePcurves& pcurves, int face_id,
          const std::vector<EdgeGrid>& grids, const FaceJob& job, Context* context, FaceMesh* f,
          bool vertices_to_surface = false)
      : vertices_to_surface_(vertices_to_surface),
        model_(model),
        pcurves_(pcurves),
        face_id_(face_id),
        grids_(grids),
        job_(job),
        context_(context),
        f_(*f),
        face_(model.face(face_id)),
        criteria_(job.criteria) {}

  // The evaluator and the face's boundary loops in (u,v), which must not cross.
  bool BuildDomain() {
    f_.surface_type = FaceSurfaceType(face_);
    surface_ = WithPointCache(FaceSurface(model_, pcurves_, face_id_, job_.nurbs, job_.surfaces));
    Status st = BuildFaceDomain(model_, pcurves_, face_id_, grids_, *surface_, &domain_);
    if (!st.ok()) return Fail(st.message());
    if (job_.moved_vertices && !job_.moved_vertices->empty()) {
      for (size_t i = 0; i < domain_.ref.size(); ++i) {
        if (domain_.ref[i].dim != 0) continue;
        auto it = job_.moved_vertices->find(domain_.ref[i].entity);
        if (it != job_.moved_vertices->end()) domain_.xyz[i] = it->second, moved_boundary_ = true;
      }
    }
    if (vertices_to_surface_ && MoveVertexNodesToSurface(*surface_, &domain_) == 0) return false;
    if (Stopping()) return Stop();
    std::vector<DomainConflict> conflicts = FindConflicts(domain_, context_);
    if (Stopping()) return Stop();
    bool no_area = !conflicts.empty();
    for (const DomainConflict& c : conflicts) no_area = no_area && c.b < 0;
    if (no_area && NoWidth()) return false;  // done: ok, with no triangles
    if (!conflicts.empty()) return Fail(DescribeConflict(domain_, conflicts.front()));
    if (job_.singular_lines && !job_.nurbs)
      AddSingularLines((*job_.singular_lines)[face_id_ - 1], &domain_);
    return true;
  }

  // A sphere or a torus meshed to a deviation alone starts from a lattice at about its final
  // density, settled before refinement; other faces from a coarse grid of seeds.
  void PlaceSeeds() {
    const bool deviation_alone =
        !job_.nurbs && criteria_.rd_tolerance == 0 && criteria_.max_length == 0;
    if (f_.surface_type == SurfaceType::kSphere && deviation_alone) {
      seeds_ = SphereLatticeSeeds(domain_, *surface_, criteria_.max_deviation,
                                  static_cast<size_t>(job_.max_triangles / 2));
    }
    // Not where an offset varies over the face: its band does too (a torus's outer half moved
    // off, its inner half on), and a lattice at either band took more triangles than the grid
    // (the (3, 1) torus at 1e-3 off the surface: 1,740 and 1,784 against 1,718).
    if (f_.surface_type == SurfaceType::kTorus && deviation_alone &&
        criteria_.deviation_scale == nullptr) {
      seeds_ = TorusLatticeSeeds(domain_, *surface_, criteria_.max_deviation,
                                 static_cast<size_t>(job_.max_triangles / 2));
    }
    settle_rounds_ = seeds_.empty() ? 0 : kLatticeSettleRounds;
    if (seeds_.empty()) seeds_ = SeedPoints(domain_, *surface_);
  }

  // The constrained triangulation of boundary and seeds in scaled (u,v), as a working mesh.
  bool Triangulate() {
    Status st = TriangulateDomain(domain_, seeds_, *surface_, context_, &mesh_);
    if (Stopping()) return Stop();
    if (!st.ok() && NoWidth()) return false;  // done: ok, with no triangles
    if (!st.ok()) return Fail(st.message());
    return true;
  }

  // A face whose boundary loops enclose no area in (u,v) and whose width (its exact area over
  // half its boundary's length) is within the deviation: its points lie within that of its
  // edges, which its neighbours mesh, so no triangles meet the request (a KiCad toroid's
  // cylinder face between two edges that lie on each other, issue 35).
  bool NoWidth() {
    const double deviation = job_.criteria.max_deviation;
    double perimeter = 0;  // along its edges' grids (the domain may have dropped a pinch)
    for (int e : model_.face_edges[face_id_ - 1]) {
      const std::vector<Vec3>& x = grids_[e - 1].xyz;
      for (size_t k = 1; k < x.size(); ++k) perimeter += Dist(x[k - 1], x[k]);
    }
    const double width = perimeter > 0 ? 2 * f_.exact_area / perimeter : HUGE_VAL;
    if (!(deviation > 0) || !(width <= deviation)) return false;
    f_.status = FaceStatus::kOk;
    f_.max_deviation = width;
    return true;
  }

  // A first triangulation that folds is unfolded first (flips, and bisections where flips are
  // not enough), then refined; where that stays stuck over the criteria, the triangulation as it
  // was is refined too, under a cap, and the better result kept; still stuck, so is one whose
  // triangles follow the surface's turn; a stuck result is then refined again from itself while
  // that helps. A run stop leaves the face skipped.
  bool Refine() {
    WorkMesh folded = mesh_;
    const bool unfolded =
        UnfoldInitialMesh(&mesh_, *surface_, domain_.scale_u, domain_.scale_v) > 0;
    status_ = RefineFace(&mesh_, *surface_, criteria_, domain_.scale_u, domain_.scale_v,
                         job_.max_triangles, job_.improve, context_, &stats_, settle_rounds_);
    if (unfolded && Stuck()) {
      const int64_t cap = kFoldedStartCap * std::max(stats_.refined_triangles, kFoldedStartMin);
      // A tie goes to the folded start: its own refinement is as good a mesh.
      KeepIfBetter(&folded, settle_rounds_, std::min(job_.max_triangles, cap), true);
    }
    // Before refining a stuck mesh again from itself (which can multiply its triangles without
    // getting anywhere): a first triangulation that follows the surface's turn. Not on a plane,
    // which does not turn: there it only costs seconds (four stuck planar faces of
    // BarrelJack_CUI_PJ-063AH took 13 s for the same mesh).
    if (Stuck() && !surface_->planar && !StuckOnFolds()) {
      WorkMesh start;
      const size_t max_seeds =
          std::max<size_t>(kTurnStartMinSeeds, kTurnStartSeedFactor * domain_.uv.size());
      status_ = TurnLimitedTriangulation(domain_, seeds_, *surface_, criteria_.min_normal_cos,
                                         kTurnStartMaxTurn, kTurnStartRounds, max_seeds, context_,
                                         &start);
      if (status_.ok()) {
        UnfoldInitialMesh(&start, *surface_, domain_.scale_u, domain_.scale_v);
        KeepIfBetter(&start, 0, RetryCap(start.TriangleCount()), false);
      } else if (!Stopping()) {
        status_ = Status::Ok();  // the triangulation that worked before stands
      }
    }
    // A fresh refiner counts every triangle as a first generation, whose splits may fold
    // children (kFoldingGenerations), which frees splits that the fold guard blocked.
    for (int round = 0; round < kStuckRetries && Stuck() && !StuckOnFolds(); ++round) {
      WorkMesh again = mesh_;
      if (!KeepIfBetter(&again, 0, RetryCap(), false)) break;
    }
    if (!status_.ok()) {
      f_.status = FaceStatus::kSkipped;
      f_.reason = status_.message();
      return false;
    }
    if (Stopping()) return Stop();
    return true;
  }

  // --off-surface: a face that bends one way is meshed as its offset toward its outer side by
  // kOffSurfaceShare of the deviation, to twice that: an interpolating mesh of the offset then
  // lies on both sides of the surface, within the deviation, with about half the triangles. The
  // first triangulation's triangles and nodes sample the bend. On a plane or a saddle the face
  // stays on its surface and says why (true); false when the offset's triangulation fails.
  bool LeaveSurface() {
    const double deviation = job_.criteria.max_deviation;
    if (!(deviation > 0) || surface_->planar) return KeepOn("a plane does not bend");
    // A face whose edges lie off it beyond the request stays on its surface: its triangles
    // along them already lean that far, and an offset only adds to it (brepnet_132907's tori at
    // 1e-4: 3.48x the request off the surface, 3.08x on it).
    const BrepGaps gaps = MeasureBrepGaps(*surface_, deviation);
    if (gaps.Largest() > deviation) return KeepOn(BrepReason(deviation, gaps, 0));
    // Its offset would tear where the normal reverses.
    if (!domain_.line_segments.empty()) return KeepOn("its surface collapses along a line");
    const int side = job_.bend_sides ? (*job_.bend_sides)[face_id_ - 1] : 0;
    if (side != 0) {
      offset_ = side * kOffSurfaceShare * deviation;
      base_ = std::move(surface_);
      surface_ = WithPointCache(MakeOffsetSurface(base_.get(), offset_));
      OffCriteria();
    } else if (!OffsetWhereItBendsOneWay(deviation)) {
      return KeepOn("it bends both ways (a saddle) or not at all");
    }
    seeds_.clear();
    PlaceSeeds();
    if (!Triangulate()) return false;
    MoveOwnBoundary();
    return true;
  }

  // A face that bends one way in parts only (a B-spline bent like a sphere but for a saddle
  // near its rim; a torus's outer half): the offset varies over it, kOffSurfaceShare of the
  // deviation toward the outer side where it bends one way and 0 where it bends both ways, and
  // so does the band the refinement may use, twice the offset where it moved and the deviation
  // where it did not: an interpolating mesh stays within the deviation on both sides in either.
  // Read on a grid of the (u,v) bounds, each node's side by BendSide; a node keeps its side only
  // when its neighbours have the same, so that the offset's ramp lies where the surface bends one
  // way. False where no node keeps one.
  bool OffsetWhereItBendsOneWay(double deviation) {
    Surface& s = *surface_;
    if (s.quadric.kind != Surface::Quadric::Kind::kNone) return false;
    const int n = kOffsetFieldCells, row = n + 1;
    const double du = (s.umax - s.umin) / n, dv = (s.vmax - s.vmin) / n;
    if (!(du > 0) || !(dv > 0)) return false;
    const double hu = kBendStep * (s.umax - s.umin), hv = kBendStep * (s.vmax - s.vmin);
    std::vector<int> sides(row * row, 0);
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        // Inside the bounds by a difference step, so that no sample leaves them.
        const Vec2 q = {std::clamp(s.umin + i * du, s.umin + 2 * hu, s.umax - 2 * hu),
                        std::clamp(s.vmin + j * dv, s.vmin + 2 * hv, s.vmax - 2 * hv)};
        sides[i * row + j] = BendSide(s, {q}, hu, hv, kBendTolerance);
      }
    }
    auto inside = [&](int i, int j) { return i >= 0 && i <= n && j >= 0 && j <= n; };
    std::vector<int> kept_side(row * row, 0);
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        const int side = sides[i * row + j];
        bool same = side != 0;
        for (int a = i - 1; same && a <= i + 1; ++a)
          for (int b = j - 1; same && b <= j + 1; ++b)
            same = !inside(a, b) || sides[a * row + b] == side;
        if (same) kept_side[i * row + j] = side;
      }
    }
    // Along the boundary the offset is 0 in the cells it crosses and ramps up over the next:
    // a triangle from an edge's chord (which spends its own part of the band) to a node moved
    // off would add the offset to it. The nodes of a seam or a pole stay on the surface too
    // (MoveOwnBoundary): the surface may bend the other way along them.
    for (const auto& segment : domain_.segments) {
      const Vec2 a = domain_.uv[segment[0]], d = domain_.uv[segment[1]] - a;
      const int pieces = 1 + static_cast<int>(2 * std::hypot(d.x / du, d.y / dv));
      for (int m = 0; m <= pieces; ++m) {
        const Vec2 q = a + (static_cast<double>(m) / pieces) * d;
        const int i = static_cast<int>(std::floor((q.x - s.umin) / du));
        const int j = static_cast<int>(std::floor((q.y - s.vmin) / dv));
        for (int ii = std::max(i, 0); ii <= std::min(i + 1, n); ++ii)
          for (int jj = std::max(j, 0); jj <= std::min(j + 1, n); ++jj)
            kept_side[ii * row + jj] = 0;
      }
    }
    offsets_ = UvGrid{s.umin, s.vmin, du, dv, n, n, {}};
    scales_ = offsets_;
    offsets_.values.assign(sides.size(), 0.0);
    scales_.values.assign(sides.size(), 0.5 / kOffSurfaceShare);  // the deviation, of 2x share
    int kept[2] = {0, 0};  // nodes moved toward -normal, +normal
    for (size_t k = 0; k < kept_side.size(); ++k) {
      if (kept_side[k] == 0) continue;
      offsets_.values[k] = kept_side[k] * kOffSurfaceShare * deviation;
      scales_.values[k] = 1.0;
      ++kept[kept_side[k] > 0];
    }
    if (kept[0] + kept[1] == 0) {
      offsets_ = scales_ = UvGrid();
      return false;
    }
    offset_ = (kept[1] >= kept[0] ? 1 : -1) * kOffSurfaceShare * deviation;
    base_ = std::move(surface_);
    surface_ = WithPointCache(MakeFieldOffsetSurface(base_.get(), &offsets_));
    OffCriteria();
    char text[160];
    std::snprintf(text, sizeof(text),
                  "moved where it bends one way (%d of %d grid points), on the surface elsewhere",
                  kept[0] + kept[1], static_cast<int>(sides.size()));
    f_.offset_reason = text;
    return true;
  }

  // The criteria of the offset's refinement: twice the offset's band (where it varies, scaled
  // to the deviation where it stays on), and the face's own surface to check against.
  void OffCriteria() {
    criteria_.max_deviation = 2 * kOffSurfaceShare * job_.criteria.max_deviation;
    criteria_.deviation_scale = offsets_.values.empty() ? nullptr : &scales_;
    criteria_.own_surface = base_.get();
    criteria_.own_deviation = job_.criteria.max_deviation;
  }

  // Boundary nodes that no other face shares move off the surface with the interior: those of
  // a seam, a degenerate edge or an open shell's free edge (edges of this face alone), and the
  // vertices only such edges meet at. On the sphere (a seam from pole to pole) a strip along the
  // seam would otherwise be meshed to the whole deviation. The nodes of one vertex, or of one
  // degenerate edge (a pole), stay one point.
  void MoveOwnBoundary() {
    auto own = [&](int e) {
      const std::vector<int>& faces = model_.edge_faces[e - 1];
      return faces.size() == 1 && faces[0] == face_id_;
    };
    std::map<int, bool> own_vertex;
    for (int e : model_.face_edges[face_id_ - 1]) {
      TopoDS_Vertex ends[2];
      TopExp::Vertices(model_.edge(e), ends[0], ends[1]);
      for (const TopoDS_Vertex& v : ends) {
        const int id = v.IsNull() ? 0 : model_.vertices.FindIndex(v);
        if (id == 0) continue;
        auto it = own_vertex.emplace(id, true).first;
        it->second = it->second && own(e);
      }
    }
    std::map<std::pair<int, int>, Vec3> point;  // (dim, id) of a vertex or a degenerate edge
    for (int v = 0; v < mesh_.node_count(); ++v) {
      const NodeRef& r = mesh_.ref[v];
      if (!mesh_.fixed[v] || r.dim > 1) continue;
      if (r.dim == 0 ? !own_vertex[r.entity] : !own(r.entity)) continue;
      const Vec3 moved = surface_->Point(mesh_.uv[v].x, mesh_.uv[v].y);
      if (r.dim == 0 || BRep_Tool::Degenerated(model_.edge(r.entity)))
        mesh_.xyz[v] = point.emplace(std::make_pair(r.dim, r.entity), moved).first->second;
      else
        mesh_.xyz[v] = moved;
    }
  }

  // The offset's mesh measured against the face's own surface both ways (from points of the
  // triangles, DenseDeviation, and from points of the surface, SurfaceSideDeviation): the
  // refinement's measures were of the offset. Within the deviation, the measures replace the
  // refinement's (true); else false, and the face goes back on its surface.
  bool OffSurfaceHolds() {
    if (!base_) return true;
    const double limit = job_.criteria.max_deviation;
    std::vector<double> deviation(mesh_.tri.size(), 0.0);
    double worst = 0;
    for (int t = 0; t < static_cast<int>(mesh_.tri.size()); ++t) {
      if (!mesh_.alive[t]) continue;
      const Tri& tri = mesh_.tri[t];
      if (mesh_.pole_axis[tri[0]] + mesh_.pole_axis[tri[1]] + mesh_.pole_axis[tri[2]] > -3)
        continue;  // a pole triangle stands for no patch of its own
      Vec2 where;
      const double d = BothWaysDeviation(mesh_, t, *base_, limit, &where);
      deviation[t] = d, worst = std::max(worst, d);
      if (worst > limit) {
        char text[160];
        std::snprintf(text, sizeof(text),
                      "off the surface it measured %.3g against the requested %.3g", worst, limit);
        KeepOn(text);
        return false;
      }
    }
    stats_.deviation = std::move(deviation), stats_.max_deviation = worst;
    return true;
  }

  // The face meshed on its surface too, where its boundary allows it (no edge moved off its
  // curve with it): that mesh stays when it takes no more triangles. An edge that stays on its
  // curve spends part of the offset's band on its chords, which can cost more than leaving the
  // surface gains (a cylinder cut by an ellipse).
  bool KeepFewer() {
    if (!base_ || moved_boundary_) return true;
    WorkMesh off_mesh = mesh_;
    RefineStats off_stats = stats_;
    std::unique_ptr<Surface> off_surface = std::move(surface_);  // evaluates through base_
    const double offset = offset_;
    if (!BackOnSurface()) return false;
    const int on = mesh_.TriangleCount(), off = off_mesh.TriangleCount();
    if (on <= off && !Stuck()) {
      char text[160];
      std::snprintf(text, sizeof(text), "off it took %d triangles, on it %d", off, on);
      KeepOn(text);
      return true;
    }
    base_ = std::move(surface_), surface_ = std::move(off_surface);
    mesh_ = std::move(off_mesh), stats_ = std::move(off_stats), offset_ = offset;
    OffCriteria();
    return true;
  }

  // Meshes the face again on its own surface, after OffSurfaceHolds.
  bool BackOnSurface() {
    surface_ = std::move(base_);
    criteria_ = job_.criteria;
    offset_ = 0;
    seeds_.clear();
    stats_ = RefineStats();
    PlaceSeeds();
    return Triangulate() && Refine();
  }

  // A face the refinement left with folded triangles (slivers no split cures, a boundary whose
  // chords cross) has its free edges flipped while that removes folds: a fold is worse than any
  // deviation. Each triangle is then measured again, so the face reports what it holds.
  void RepairFolds() {
    const int folds = CountFolds(mesh_);
    if (folds == 0) return;
    WorkMesh trial = mesh_;
    if (UnfoldFlips(&trial) == 0 || CountFolds(trial) >= folds) return;
    mesh_ = std::move(trial);
    const double limit = job_.criteria.max_deviation;
    stats_.deviation.assign(mesh_.tri.size(), 0.0);
    stats_.max_deviation = 0;
    for (int t = 0; t < static_cast<int>(mesh_.tri.size()); ++t) {
      if (!mesh_.alive[t]) continue;
      double d;
      if (base_) {
        Vec2 where;
        d = BothWaysDeviation(mesh_, t, *base_, limit, &where);
      } else {
        Vec2 uv[3];
        Vec3 p[3];
        mesh_.MeasureCorners(mesh_.tri[t], uv, p);
        d = MeasureTriangle(*surface_, uv, p, job_.criteria).deviation;
      }
      stats_.deviation[t] = d;
      stats_.max_deviation = std::max(stats_.max_deviation, d);
    }
    if (limit > 0)
      stats_.max_violation = std::max(stats_.max_violation, stats_.max_deviation / limit);
  }

  // Triangles whose 3D points fold against the surface's normals at their corners.
  int Folds() const { return CountFolds(mesh_); }

  // The face's triangles, oriented as the face, with exact normals (at poles too) and the
  // working mesh's node references.
  bool Extract(std::vector<NodeRef>* refs) {
    rdmesh::Extract(mesh_, stats_.deviation, face_.Orientation() == TopAbs_REVERSED,
                    !domain_.line_segments.empty(), &f_, refs);
    if (f_.triangles.empty()) return Fail("no triangles survived");
    if (Stopping()) return Stop();
    if (!job_.nurbs) ExactPoleNormals(face_, *refs, &f_);
    f_.max_deviation = stats_.max_deviation;
    f_.offset = offset_ == 0 ? 0.0 : face_.Orientation() == TopAbs_REVERSED ? -offset_ : offset_;
    f_.status = FaceStatus::kOk;
    return true;
  }

  // Why a meshed face may miss the request: the B-rep itself keeps it from the requested
  // deviation where its edges lie off the surface by more (BoundaryGap, or past the surface's own
  // range: BoundaryGapPastSurface, or from the face's trim: EdgeTrimGap), or where its edges'
  // tolerance is coarser and the face misses it or its edges' chords do (edge grids are not
  // refined below an edge's tolerance: edge_grids.cpp); else the triangle cap, or triangles no
  // split could bring within criteria.
  void ExplainShortfall() {
    const double deviation = job_.criteria.max_deviation;
    Surface& surface = base_ ? *base_ : *surface_;
    const BrepGaps gaps = MeasureBrepGaps(surface, deviation);
    const double gap = gaps.Largest();
    const bool missed = stats_.max_violation > 1.0 + 1e-9;
    const bool coarse =
        gaps.tolerance > deviation && (missed || BoundaryChordHeight(domain_, surface) > deviation);
    if (gap > deviation) f_.max_deviation = std::max(f_.max_deviation, gap);
    if (stats_.budget_hit)
      f_.reason = "stopped at the per-face triangle cap";
    else if (deviation > 0 && (gap > deviation || coarse))
      f_.reason = BrepReason(deviation, gaps, missed ? stats_.max_deviation : 0);
    else if (missed && stats_.stuck_folds > 0)
      f_.reason = StuckFoldReason(stats_.stuck_folds, stats_.over);
    else if (missed)
      f_.reason = "some triangles could not be refined to the criteria without folding";
  }

 private:
  // How far the face's edges lie off its own `surface`, as far as the B-rep sets it, against the
  // requested `deviation`: its boundary nodes along the normal (BoundaryGap), past the surface's
  // range (BoundaryGapPastSurface), and, where the edges' tolerance (into *tolerance) is coarser
  // than the deviation, the trim from the edges' 3D curves (EdgeTrimGap). 0 without a deviation.
  // Not the run's own moves off the surface: edges and vertices moved with their faces.
  BrepGaps MeasureBrepGaps(Surface& surface, double deviation) const {
    BrepGaps gaps;
    if (!(deviation > 0)) return gaps;
    std::vector<double> moved(domain_.uv.size(), 0.0);
    for (size_t i = 0; i < moved.size(); ++i) {
      const NodeRef& r = domain_.ref[i];
      if (r.dim == 1) moved[i] = grids_[r.entity - 1].moved;
      if (r.dim == 0 && job_.moved_vertices && job_.moved_vertices->count(r.entity)) {
        const gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(model_.vertices(r.entity)));
        moved[i] = Dist(domain_.xyz[i], Vec3{p.X(), p.Y(), p.Z()});
      }
    }
    gaps.edges = BoundaryGap(domain_, surface, moved);
    if (!job_.nurbs)
      gaps.edges = std::max(gaps.edges, BoundaryGapPastSurface(face_, domain_, moved));
    gaps.tolerance = EdgeTolerance(face_);
    // Seen from the surface, the mesh's boundary (the edges' 3D curves) misses the face's trim
    // (the pcurves) by as much as they lie apart, which the edge tolerance allows.
    if (gaps.tolerance > deviation) gaps.trim = EdgeTrimGap(face_, deviation);
    return gaps;
  }
  bool Stopping() const { return context_ && context_->ShouldStop(); }
  bool Stop() {
    f_ = Stopped(std::move(f_), *context_);
    return false;
  }
  bool KeepOn(const std::string& why) {
    f_.offset_reason = "kept on the surface: " + why;
    return true;
  }
  bool Fail(const std::string& reason) {
    f_ = Failed(std::move(f_), reason);
    return false;
  }
  // A retry of a stuck face may take this many times the triangles it has, or its own start has
  // (a face whose normal flips inside, SSO-8's twisted B-spline patches, issue 35, refined again
  // from itself toward the 20 M cap for minutes); one that reaches the cap is not kept
  // (KeepIfBetter). A stuck refinement that stopped early (kFoldRun) does not starve a start
  // larger than its result.
  int64_t RetryCap(int64_t start_triangles = 0) const {
    const int64_t base = std::max<int64_t>({mesh_.TriangleCount(), start_triangles, kRetryMin});
    return std::min<int64_t>(job_.max_triangles, kRetryCap * base);
  }
  // Refinement ended within its budget but over the criteria.
  bool Stuck() const {
    return status_.ok() && stats_.max_violation > 1.0 + 1e-9 && !stats_.budget_hit;
  }
  // Stuck on folds no start removes: nearly every triangle over the criteria (at least
  // kStuckFoldsPatch of them) holds a fold that splits only hand on. A first triangulation's fan
  // across a turn, which another start avoids, folds a few triangles; a twisted patch folds
  // dozens (Crystal_HC33-U's faces of revolution: 36 of 36; SSO-8's bow-ties: 164 of 171), and
  // another start only refines it again, to four times the triangles (0.7-1.1 s a face).
  bool StuckOnFolds() const {
    return Stuck() && stats_.over >= kStuckFoldsPatch && stats_.stuck_folds * 10 >= stats_.over * 9;
  }
  // Refines `candidate` (under `cap` triangles) and keeps it when it lowers the worst violation,
  // or with `ties` keeps it as bad (and, under a cap of its own, when it did not reach it).
  bool KeepIfBetter(WorkMesh* candidate, int settle, int64_t cap, bool ties) {
    RefineStats again;
    status_ = RefineFace(candidate, *surface_, criteria_, domain_.scale_u, domain_.scale_v, cap,
                         job_.improve, context_, &again, settle);
    if (!status_.ok()) return false;
    if (ties ? !(again.max_violation <= stats_.max_violation)
             : !(again.max_violation < stats_.max_violation))
      return false;
    if (cap < job_.max_triangles && again.budget_hit) return false;
    mesh_ = std::move(*candidate), stats_ = again;
    return true;
  }

  const bool vertices_to_surface_;
  const Model& model_;
  const FacePcurves& pcurves_;
  const int face_id_;
  const std::vector<EdgeGrid>& grids_;
  const FaceJob& job_;
  Context* context_;
  FaceMesh& f_;
  const TopoDS_Face& face_;
  FaceCriteria criteria_;  // the job's, or its offset's (LeaveSurface)
  std::unique_ptr<Surface> surface_;
  std::unique_ptr<Surface> base_;  // the face's own surface while surface_ is its offset
  double offset_ = 0;              // along the surface's Normal(): S + offset_ n is meshed
  UvGrid offsets_, scales_;        // an offset that varies (OffsetWhereItBendsOneWay): S +
                                   // offsets_ n is meshed, to the deviation times scales_
  bool moved_boundary_ = false;    // a vertex of the domain moved with its edges
  FaceDomain domain_;
  std::vector<Vec2> seeds_;
  int settle_rounds_ = 0;
  WorkMesh mesh_;
  RefineStats stats_;
  Status status_;
};

// A face whose mesh `run` kept folds beside a vertex that lies along the surface away from its
// pcurve ends (a B-rep whose vertex tolerance covers the gap) meshed again with its vertex nodes
// at the surface's nearest points (into `g`): that run, when it folds fewer triangles, else null.
// Only where folds are left: elsewhere the pcurve ends serve as well (on the planes around
// Fuseholder_Schurter_0031.7701's vertex, moved, the mesh lay 0.11 off the face, not 0.087).
std::unique_ptr<FaceRun> RetryFolds(const Model& model, const FacePcurves& pcurves, int face_id,
                                    const std::vector<EdgeGrid>& grids, const FaceJob& job,
                                    Context* context, const FaceRun& run, FaceMesh* g) {
  const int folds = run.Folds();
  if (folds == 0) return nullptr;
  try {
    auto again = std::make_unique<FaceRun>(model, pcurves, face_id, grids, job, context, g, true);
    if (!again->BuildDomain()) return nullptr;
    again->PlaceSeeds();
    if (!again->Triangulate() || !again->Refine()) return nullptr;
    again->RepairFolds();
    if (again->Folds() < folds) return again;
  } catch (const Standard_Failure&) {
  }
  return nullptr;  // the first mesh stands
}

}  // namespace

FaceMesh MeshFace(const Model& model, const FacePcurves& pcurves, int face_id,
                  const std::vector<EdgeGrid>& grids, const FaceJob& job, Context* context,
                  std::vector<NodeRef>* refs) {
  auto t0 = std::chrono::steady_clock::now();
  FaceMesh f;
  f.face_id = face_id;
  f.exact_area = model.face_area[face_id - 1];
  refs->clear();
  try {
    FaceRun run(model, pcurves, face_id, grids, job, context, &f);
    if (!run.BuildDomain()) return f;
    run.PlaceSeeds();
    if (!run.Triangulate()) return f;
    if (job.off_surface && !run.LeaveSurface()) return f;
    if (!run.Refine()) return f;
    if (job.off_surface && !run.OffSurfaceHolds() && !run.BackOnSurface()) return f;
    if (job.off_surface && !run.KeepFewer()) return f;
    run.RepairFolds();
    FaceMesh g = f;
    std::unique_ptr<FaceRun> again =
        job.off_surface ? nullptr
                        : RetryFolds(model, pcurves, face_id, grids, job, context, run, &g);
    if (context && context->ShouldStop()) return Stopped(std::move(f), *context);
    FaceRun& chosen = again ? *again : run;
    FaceMesh& out = again ? g : f;
    if (!chosen.Extract(refs)) return out;
    chosen.ExplainShortfall();
    if (again) f = std::move(g);
  } catch (const Standard_Failure& e) {
    return Failed(f, std::string("OCCT: ") + (e.GetMessageString() && *e.GetMessageString()
                                                  ? e.GetMessageString()
                                                  : e.DynamicType()->Name()));
  } catch (const std::exception& e) {
    return Failed(f, e.what());
  }
  for (int t = 0; t < f.triangle_count(); ++t) f.area += TriangleArea(f, t);
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return f;
}

Result<FaceDomain> CopySource(const Model& model, const FacePcurves& pcurves, int rep_id,
                              const std::vector<EdgeGrid>& grids) {
  try {
    std::unique_ptr<Surface> surface =
        MakeFaceSurface(model.face(rep_id), false, pcurves.Bounds(model, rep_id));
    FaceDomain domain;
    if (!BuildFaceDomain(model, pcurves, rep_id, grids, *surface, &domain).ok())
      return Status(StatusCode::kFaceFailed, "instance boundary differs");
    return domain;
  } catch (const Standard_Failure& e) {
    return Status(StatusCode::kInternal, std::string("OCCT: ") + e.DynamicType()->Name());
  } catch (const std::exception& e) {
    return Status(StatusCode::kInternal, e.what());
  }
}

FaceMesh PlaceCopy(const Model& model, const FacePcurves& pcurves, int face_id, const FaceMesh& rep,
                   const std::vector<NodeRef>& rep_refs, const Result<FaceDomain>& source,
                   const std::vector<EdgeGrid>& grids, std::vector<NodeRef>* refs) {
  FaceMesh f = rep;
  f.face_id = face_id;
  f.exact_area = model.face_area[face_id - 1];
  *refs = rep_refs;
  if (rep.status != FaceStatus::kOk) return f;
  try {
    // Boundary nodes: the copy's own domain lists them in the same order as the
    // representative's (same TShape), with its own exact points and ids.
    std::unique_ptr<Surface> surface =
        MakeFaceSurface(model.face(face_id), false, pcurves.Bounds(model, face_id));
    FaceDomain mine;
    Status st = BuildFaceDomain(model, pcurves, face_id, grids, *surface, &mine);
    if (st.ok() && !source.ok()) return Failed(f, source.status().message());
    if (!st.ok() || mine.uv.size() != source->uv.size())
      return Failed(f, "instance boundary differs");
    const FaceDomain& theirs = *source;
    const gp_Trsf& trsf = model.face_placement[face_id - 1];
    for (int i = 0; i < f.node_count(); ++i) {
      NodeRef& r = (*refs)[i];
      if (r.dim == 2) {
        gp_Pnt p(f.xyz[3 * i], f.xyz[3 * i + 1], f.xyz[3 * i + 2]);
        p.Transform(trsf);
        f.xyz[3 * i] = p.X(), f.xyz[3 * i + 1] = p.Y(), f.xyz[3 * i + 2] = p.Z();
        r.entity = face_id;
      } else {
        // Find this node among the representative's boundary nodes by (u,v).
        // Pole nodes added by refinement are not in the domain: match them by their vertex.
        size_t k = 0;
        for (; k < theirs.uv.size(); ++k)
          if (theirs.uv[k].x == f.uv[2 * i] && theirs.uv[k].y == f.uv[2 * i + 1]) break;
        if (k == theirs.uv.size() && r.dim == 0)
          for (k = 0; k < theirs.ref.size(); ++k)
            if (theirs.ref[k].dim == 0 && theirs.ref[k].entity == r.entity) break;
        if (k == theirs.uv.size()) return Failed(f, "instance boundary node not found");
        r = mine.ref[k];
        f.xyz[3 * i] = mine.xyz[k].x, f.xyz[3 * i + 1] = mine.xyz[k].y,
                  f.xyz[3 * i + 2] = mine.xyz[k].z;
      }
      gp_Vec n(f.normals[3 * i], f.normals[3 * i + 1], f.normals[3 * i + 2]);
      n.Transform(trsf);
      if (model.face_flipped[face_id - 1]) n.Reverse();
      f.normals[3 * i] = n.X(), f.normals[3 * i + 1] = n.Y(), f.normals[3 * i + 2] = n.Z();
    }
    if (model.face_flipped[face_id - 1])
      for (size_t t = 0; t + 2 < f.triangles.size(); t += 3)
        std::swap(f.triangles[t + 1], f.triangles[t + 2]);
  } catch (const Standard_Failure& e) {
    return Failed(f, std::string("OCCT: ") + e.DynamicType()->Name());
  } catch (const std::exception& e) {
    return Failed(f, e.what());
  }
  return f;
}

}  // namespace rdmesh
