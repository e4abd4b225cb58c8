#include "geometry/surface_type.h"

#include <BRepAdaptor_Surface.hxx>

namespace rdmesh {

SurfaceType FaceSurfaceType(const TopoDS_Face& face) {
  switch (BRepAdaptor_Surface(face, Standard_False).GetType()) {
    case GeomAbs_Plane:
      return SurfaceType::kPlane;
    case GeomAbs_Cylinder:
      return SurfaceType::kCylinder;
    case GeomAbs_Cone:
      return SurfaceType::kCone;
    case GeomAbs_Sphere:
      return SurfaceType::kSphere;
    case GeomAbs_Torus:
      return SurfaceType::kTorus;
    case GeomAbs_BezierSurface:
      return SurfaceType::kBezier;
    case GeomAbs_BSplineSurface:
      return SurfaceType::kBSpline;
    case GeomAbs_SurfaceOfRevolution:
      return SurfaceType::kRevolution;
    case GeomAbs_SurfaceOfExtrusion:
      return SurfaceType::kExtrusion;
    case GeomAbs_OffsetSurface:
      return SurfaceType::kOffset;
    default:
      return SurfaceType::kOther;
  }
}

}  // namespace rdmesh
