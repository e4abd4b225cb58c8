// Test-data generator: a BREP compound of N placed copies of one box (a single TShape under N
// locations), i.e. N instances that the engine meshes once and places N times. Used by the
// pytest suite to stream results of many millions of triangles in reasonable time.
//
//   make_instanced_brep OUT.brep COPIES [SIZE]

#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS_Compound.hxx>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <gp_Trsf.hxx>
#include <gp_Vec.hxx>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s OUT.brep COPIES [SIZE]\n", argv[0]);
    return 2;
  }
  const int copies = std::atoi(argv[2]);
  const double size = argc > 3 ? std::atof(argv[3]) : 10.0;
  if (copies < 1 || size <= 0) return 2;
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(size, size, size).Shape();
  const int side = static_cast<int>(std::ceil(std::cbrt(static_cast<double>(copies))));
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  for (int i = 0; i < copies; ++i) {
    gp_Trsf placement;
    placement.SetTranslation(gp_Vec(1.5 * size * (i % side), 1.5 * size * ((i / side) % side),
                                    1.5 * size * (i / (side * side))));
    builder.Add(compound, box.Moved(TopLoc_Location(placement)));
  }
  return BRepTools::Write(compound, argv[1]) ? 0 : 1;
}
