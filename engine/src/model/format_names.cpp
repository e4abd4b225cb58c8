#include "rdmesh/format_names.h"

#include "rdmesh/mesh.h"

namespace rdmesh {

const char* SurfaceTypeName(SurfaceType type) {
  switch (type) {
    case SurfaceType::kPlane:
      return "plane";
    case SurfaceType::kCylinder:
      return "cylinder";
    case SurfaceType::kCone:
      return "cone";
    case SurfaceType::kSphere:
      return "sphere";
    case SurfaceType::kTorus:
      return "torus";
    case SurfaceType::kBezier:
      return "bezier";
    case SurfaceType::kBSpline:
      return "bspline";
    case SurfaceType::kRevolution:
      return "revolution";
    case SurfaceType::kExtrusion:
      return "extrusion";
    case SurfaceType::kOffset:
      return "offset";
    case SurfaceType::kOther:
      return "other";
  }
  return "other";
}

const char* FaceStatusName(FaceStatus status) {
  switch (status) {
    case FaceStatus::kOk:
      return "ok";
    case FaceStatus::kFailed:
      return "failed";
    case FaceStatus::kSkipped:
      return "skipped";
  }
  return "unknown";
}

const char* ReaderName(ModelFormat format) {
  switch (format) {
    case ModelFormat::kStep:
      return "the STEP reader";
    case ModelFormat::kIges:
      return "the IGES reader";
    case ModelFormat::kBrep:
      return "the BREP reader";
    case ModelFormat::kAuto:
      break;
  }
  return "the model reader";
}

}  // namespace rdmesh
