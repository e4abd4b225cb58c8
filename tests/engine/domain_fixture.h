#pragma once
// Edge grids and face domains of a loaded model, through the engine's own stages, and a face
// whose edge grids are too coarse for it: for the tests of face domains and of healing.

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>
#include <gp_Pln.hxx>
#include <memory>
#include <vector>

#include "boundary/edge_grids.h"
#include "boundary/face_domain.h"
#include "boundary/pcurves.h"
#include "geometry/surface.h"
#include "model/model.h"

namespace rdmesh::testing {

/// Every face id of the model.
inline std::vector<int> AllFaces(const Model& model) {
  std::vector<int> faces(model.face_count());
  for (int f = 1; f <= model.face_count(); ++f) faces[f - 1] = f;
  return faces;
}

/// The pcurves of every face, as a run looks them up.
inline FacePcurves Pcurves(const Model& model) {
  return FacePcurves::Build(model, AllFaces(model), 1, nullptr);
}

/// The edge grids of every edge at an absolute max deviation, on one thread.
inline std::vector<EdgeGrid> Grids(const Model& model, double max_deviation) {
  GridCriteria criteria;
  criteria.max_deviation = max_deviation;
  std::vector<EdgeGrid> grids;
  EXPECT_TRUE(BuildEdgeGrids(model, Pcurves(model), criteria, 1, {}, nullptr, &grids).ok());
  return grids;
}

/// The (u,v) domain of face `face_id` on its exact surface.
inline Status Domain(const Model& model, int face_id, const std::vector<EdgeGrid>& grids,
                     FaceDomain* domain) {
  const FacePcurves pcurves = Pcurves(model);
  std::unique_ptr<Surface> surface =
      MakeFaceSurface(model.face(face_id), false, pcurves.Bounds(model, face_id));
  return BuildFaceDomain(model, pcurves, face_id, grids, *surface, domain);
}

/// A disc of radius 1 whose plane is a surface trimmed to y <= 0.9: the rim's pcurve runs past
/// the surface's own range for |x| < 0.44, up to 0.1 beyond it, where OCCT extends the plane while
/// the face ends at y = 0.9 (as a B-spline's edges may run past its knot range).
inline TopoDS_Face DiscPastItsSurface() {
  Handle(Geom_Surface) plane =
      new Geom_RectangularTrimmedSurface(new Geom_Plane(gp_Pln(gp::XOY())), -2.0, 2.0, -2.0, 0.9);
  BRepBuilderAPI_MakeFace make(
      plane, BRepBuilderAPI_MakeWire(
                 BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp::Origin(), gp::DZ()), 1.0)).Edge())
                 .Wire());
  return make.IsDone() ? make.Face() : TopoDS_Face();
}

/// A disc of radius 1.5875 with a concentric hole of radius 1.0795 (a face of a real assembly).
/// At a deviation of 1 both circles get the 3 segments a closed edge needs at least, and the two
/// triangles cross.
inline TopoDS_Shape DiscWithHole() {
  gp_Ax2 axis(gp::Origin(), gp::DZ());
  TopoDS_Wire outer =
      BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(gp_Circ(axis, 1.5875)).Edge()).Wire();
  TopoDS_Wire hole =
      BRepBuilderAPI_MakeWire(
          BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp::Origin(), gp::DZ(), -gp::DX()), 1.0795))
              .Edge())
          .Wire();
  hole.Reverse();
  BRepBuilderAPI_MakeFace make(gp_Pln(gp::XOY()), outer);
  make.Add(hole);
  return make.Face();
}

}  // namespace rdmesh::testing
