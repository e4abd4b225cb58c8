// boundary_probe: the distance from a point to one face's boundary edges, read three ways, for
// triaging a yardstick reading (bench/robustness/kicad_yardstick.py's TRIAGE).
//
//   boundary_probe MODEL.step FACE X Y Z
//
// FACE is 1-based in TopExp order (the yardstick's numbering). Prints BRepExtrema's distance to
// the face, then for each edge: Extrema_ExtPC over the edge's whole range, BRepExtrema's distance
// to the edge, and for a conic, Extrema_ExtPC over a short range (+-0.05) about the nearest foot,
// which is how the yardstick refines its boundary polylines. Where that short range misses the
// foot, the yardstick falls back to its polyline's vertices and reads a larger distance.
#include <BRepAdaptor_Curve.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <Extrema_ExtPC.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace {

// The nearest extremum of `ext`, or -1 when it found none.
int Nearest(const Extrema_ExtPC& ext) {
  if (!ext.IsDone()) return -1;
  int best = -1;
  for (int i = 1; i <= ext.NbExt(); ++i)
    if (best < 0 || ext.SquareDistance(i) < ext.SquareDistance(best)) best = i;
  return best;
}

double Distance(const TopoDS_Shape& shape, const gp_Pnt& p) {
  BRepExtrema_DistShapeShape dss(BRepBuilderAPI_MakeVertex(p).Vertex(), shape);
  return dss.IsDone() && dss.NbSolution() > 0 ? dss.Value() : -1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: boundary_probe MODEL.step FACE X Y Z\n");
    return 2;
  }
  STEPControl_Reader reader;
  if (reader.ReadFile(argv[1]) != IFSelect_RetDone || reader.TransferRoots() == 0) {
    std::fprintf(stderr, "boundary_probe: cannot read %s\n", argv[1]);
    return 1;
  }
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(reader.OneShape(), TopAbs_FACE, faces);
  const int index = std::atoi(argv[2]);
  if (index < 1 || index > faces.Extent()) {
    std::fprintf(stderr, "boundary_probe: no face %d (the model has %d)\n", index, faces.Extent());
    return 2;
  }
  const TopoDS_Face face = TopoDS::Face(faces(index));
  const gp_Pnt p(std::atof(argv[3]), std::atof(argv[4]), std::atof(argv[5]));
  std::printf("face %d: BRepExtrema %.6e\n", index, Distance(face, p));
  int k = 0;
  for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
    const TopoDS_Edge edge = TopoDS::Edge(ex.Current());
    ++k;
    BRepAdaptor_Curve curve(edge);
    const double t0 = curve.FirstParameter(), t1 = curve.LastParameter();
    const Extrema_ExtPC whole(p, curve, t0, t1);
    const int n = Nearest(whole);
    std::printf("edge %d (curve type %d, range [%.6f, %.6f]): Extrema_ExtPC %s, BRepExtrema %.6e\n",
                k, static_cast<int>(curve.GetType()), t0, t1,
                n < 0 ? "none" : std::to_string(std::sqrt(whole.SquareDistance(n))).c_str(),
                Distance(edge, p));
    const GeomAbs_CurveType type = curve.GetType();
    if (n < 0 || (type != GeomAbs_Circle && type != GeomAbs_Ellipse)) continue;
    const double foot = whole.Point(n).Parameter();
    const Extrema_ExtPC near(p, curve, foot - 0.05, foot + 0.05);
    const int m = Nearest(near);
    std::printf("  foot t = %.6f; Extrema_ExtPC over [%.4f, %.4f]: %s\n", foot, foot - 0.05,
                foot + 0.05,
                m < 0 ? "no extremum"
                      : ("nearest " + std::to_string(std::sqrt(near.SquareDistance(m))) +
                         " at t = " + std::to_string(near.Point(m).Parameter()))
                            .c_str());
  }
  return 0;
}
