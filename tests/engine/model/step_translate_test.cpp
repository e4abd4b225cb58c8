// rdmesh's own STEP translator (model/step/translate.h): geometry built with OCCT's
// parameterisation (against StepToGeom on the same entities), topology and units on a hand-built
// cube, broken and unsupported files, and every bundled and corpus STEP file against OCCT's
// reader: the same solids, faces, edges and vertices, numbered alike, the same surface type and
// area per face, the same box and document.

#include <gtest/gtest.h>

#include <BRepBndLib.hxx>
#include <BRepGProp.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Quantity_ColorRGBA.hxx>
#include <STEPControl_Reader.hxx>
#include <StepData_GlobalFactors.hxx>
#include <StepData_StepModel.hxx>
#include <StepGeom_Curve.hxx>
#include <StepGeom_Surface.hxx>
#include <StepToGeom.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "model/model_readers.h"
#include "model/step/entities.h"
#include "model/step/equivalence.h"
#include "model/step/geometry.h"
#include "model/step/translate.h"

namespace rdmesh::step {
namespace {

namespace fs = std::filesystem;

std::string Header() {
  return "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
         "FILE_NAME('t.step','2024-01-01T00:00:00',(''),(''),'','','');\n"
         "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n";
}

std::string Wrap(const std::string& data) {
  return Header() + data + "ENDSEC;\nEND-ISO-10303-21;\n";
}

// The engine's STEP read through OCCT's reader alone (RDMESH_STEP_READER=occt for the call; the
// engine reads with this translator by default since d5cad75), checked to have come from OCCT.
Result<ReadShape> ReadWithOcct(const std::string& bytes, const std::string& path,
                               const std::string& name) {
  const char* before = std::getenv("RDMESH_STEP_READER");
  const std::string saved = before != nullptr ? before : "";
  setenv("RDMESH_STEP_READER", "occt", 1);
  Result<ReadShape> read = ReadModelBytes(bytes, ModelFormat::kStep, path, name, nullptr);
  if (before != nullptr) {
    setenv("RDMESH_STEP_READER", saved.c_str(), 1);
  } else {
    unsetenv("RDMESH_STEP_READER");
  }
  if (read.ok()) EXPECT_EQ(read->reader, "occt");
  return read;
}

File ParseOk(const std::string& bytes) {
  Result<File> file = Parse(bytes);
  EXPECT_TRUE(file.ok()) << file.status().ToString();
  return file.ok() ? std::move(*file) : File();
}

// The bytes of the file at `path`.
std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

Result<Translated> Translate(const std::string& bytes, int threads = 0) {
  Result<File> file = Parse(bytes);
  if (!file.ok()) return file.status();
  TranslateOptions options;
  options.threads = threads;
  return TranslateStep(*file, options, nullptr);
}

// ---------------------------------------------------------------------------------------------
// Geometry: ours against StepToGeom on the same entities, evaluated to the last bit.

class GeometryParity : public ::testing::Test {
 protected:
  // Parses `data` both ways: with our parser, and into OCCT's StepData model.
  void Load(const std::string& data) {
    text_ = Wrap(data);
    file_ = ParseOk(text_);
    std::istringstream stream(text_);
    ASSERT_EQ(reader_.ReadStream("t.step", stream), IFSelect_RetDone);
    model_ = reader_.StepModel();
    entities_ = std::make_unique<Entities>(file_);
    geometry_ = std::make_unique<Geometry>(*entities_);
    StepData_GlobalFactors::Intance().InitializeFactors(1., 1., 1.);
  }

  Handle(Standard_Transient) Occt(uint64_t id) const {
    for (int i = 1; i <= model_->NbEntities(); ++i)
      if (model_->IdentLabel(model_->Value(i)) == static_cast<int>(id)) return model_->Value(i);
    return nullptr;
  }

  // The same curve type, parameter range and points (bit for bit) at nine parameters.
  void ExpectSameCurve(uint64_t id) {
    SCOPED_TRACE("#" + std::to_string(id));
    Handle(Geom_Curve) ours;
    try {
      ours = geometry_->Curve(id, 0, units_);
    } catch (const Unsupported& u) {
      FAIL() << u.what;
    }
    Handle(Geom_Curve) theirs = StepToGeom::MakeCurve(Handle(StepGeom_Curve)::DownCast(Occt(id)));
    ASSERT_FALSE(theirs.IsNull());
    ASSERT_FALSE(ours.IsNull());
    EXPECT_STREQ(ours->DynamicType()->Name(), theirs->DynamicType()->Name());
    EXPECT_EQ(ours->IsPeriodic(), theirs->IsPeriodic());
    double first = theirs->FirstParameter(), last = theirs->LastParameter();
    if (Precision::IsInfinite(first)) first = -10.;
    if (Precision::IsInfinite(last)) last = 10.;
    EXPECT_EQ(ours->FirstParameter(), theirs->FirstParameter());
    EXPECT_EQ(ours->LastParameter(), theirs->LastParameter());
    for (int k = 0; k <= 8; ++k) {
      const double t = first + (last - first) * k / 8.;
      const gp_Pnt a = ours->Value(t), b = theirs->Value(t);
      EXPECT_EQ(a.X(), b.X()) << "t=" << t;
      EXPECT_EQ(a.Y(), b.Y()) << "t=" << t;
      EXPECT_EQ(a.Z(), b.Z()) << "t=" << t;
    }
  }

  void ExpectSameSurface(uint64_t id) {
    SCOPED_TRACE("#" + std::to_string(id));
    Handle(Geom_Surface) ours;
    try {
      ours = geometry_->Surface(id, 0, units_);
    } catch (const Unsupported& u) {
      FAIL() << u.what;
    }
    Handle(Geom_Surface) theirs =
        StepToGeom::MakeSurface(Handle(StepGeom_Surface)::DownCast(Occt(id)));
    ASSERT_FALSE(theirs.IsNull());
    ASSERT_FALSE(ours.IsNull());
    EXPECT_STREQ(ours->DynamicType()->Name(), theirs->DynamicType()->Name());
    double u1, u2, v1, v2;
    theirs->Bounds(u1, u2, v1, v2);
    auto clamp = [](double x, double fallback) { return Precision::IsInfinite(x) ? fallback : x; };
    u1 = clamp(u1, -3.), u2 = clamp(u2, 3.), v1 = clamp(v1, -3.), v2 = clamp(v2, 3.);
    for (int i = 0; i <= 4; ++i) {
      for (int j = 0; j <= 4; ++j) {
        const double u = u1 + (u2 - u1) * i / 4., v = v1 + (v2 - v1) * j / 4.;
        const gp_Pnt a = ours->Value(u, v), b = theirs->Value(u, v);
        EXPECT_EQ(a.X(), b.X()) << "u=" << u << " v=" << v;
        EXPECT_EQ(a.Y(), b.Y()) << "u=" << u << " v=" << v;
        EXPECT_EQ(a.Z(), b.Z()) << "u=" << u << " v=" << v;
      }
    }
  }

  void ExpectSameCurve2d(uint64_t id) {
    SCOPED_TRACE("#" + std::to_string(id));
    Handle(Geom2d_Curve) ours;
    try {
      ours = geometry_->Curve2d(id, 0, units_);
    } catch (const Unsupported& u) {
      FAIL() << u.what;
    }
    Handle(Geom2d_Curve) theirs =
        StepToGeom::MakeCurve2d(Handle(StepGeom_Curve)::DownCast(Occt(id)));
    ASSERT_FALSE(theirs.IsNull());
    ASSERT_FALSE(ours.IsNull());
    EXPECT_STREQ(ours->DynamicType()->Name(), theirs->DynamicType()->Name());
    double first = theirs->FirstParameter(), last = theirs->LastParameter();
    if (Precision::IsInfinite(first)) first = -10.;
    if (Precision::IsInfinite(last)) last = 10.;
    for (int k = 0; k <= 8; ++k) {
      const double t = first + (last - first) * k / 8.;
      EXPECT_EQ(ours->Value(t).X(), theirs->Value(t).X());
      EXPECT_EQ(ours->Value(t).Y(), theirs->Value(t).Y());
    }
  }

  std::string text_;
  File file_;
  STEPControl_Reader reader_;
  Handle(StepData_StepModel) model_;
  std::unique_ptr<Entities> entities_;
  std::unique_ptr<Geometry> geometry_;
  UnitFactors units_;
};

// Placements with awkward, unnormalised directions: StepToGeom normalises twice and builds the
// axes twice; the last bits must agree.
const char* kPlacements =
    "#1=CARTESIAN_POINT('',(1.25,-3.5,7.));\n"
    "#2=DIRECTION('',(0.3,0.7,-0.2));\n"
    "#3=DIRECTION('',(0.9,-0.1,0.4));\n"
    "#4=AXIS2_PLACEMENT_3D('',#1,#2,#3);\n"
    "#5=AXIS2_PLACEMENT_3D('',#1,#2,$);\n"
    "#6=DIRECTION('',(-0.62054464425872,0.339004932827,0.7071067811866));\n"
    "#7=VECTOR('',#6,2.5);\n"
    "#8=CARTESIAN_POINT('',(0.,0.,0.));\n"
    "#9=AXIS1_PLACEMENT('',#1,#6);\n";

TEST_F(GeometryParity, CurvesMatchStepToGeom) {
  Load(std::string(kPlacements) +
       "#10=LINE('',#1,#7);\n"
       "#11=CIRCLE('',#4,2.75);\n"
       "#12=ELLIPSE('',#4,3.,1.5);\n"
       "#13=ELLIPSE('',#5,1.5,3.);\n"
       "#14=HYPERBOLA('',#4,2.,1.);\n"
       "#15=PARABOLA('',#4,0.75);\n"
       "#20=CARTESIAN_POINT('',(0.,0.,0.));\n"
       "#21=CARTESIAN_POINT('',(1.,2.,0.5));\n"
       "#22=CARTESIAN_POINT('',(2.,-1.,1.));\n"
       "#23=CARTESIAN_POINT('',(3.,0.5,0.));\n"
       "#24=CARTESIAN_POINT('',(4.,1.,-1.));\n"
       "#30=B_SPLINE_CURVE_WITH_KNOTS('',3,(#20,#21,#22,#23,#24),.UNSPECIFIED.,.F.,.F.,(4,1,4),"
       "(0.,0.4,1.),.UNSPECIFIED.);\n"
       // Knots to merge (0.4 twice) and a first multiplicity above degree + 1 (trimmed).
       "#31=B_SPLINE_CURVE_WITH_KNOTS('',2,(#20,#21,#22,#23,#24),.UNSPECIFIED.,.F.,.F.,(4,1,1,2),"
       "(0.,0.4,0.4,1.),.UNSPECIFIED.);\n"
       "#32=(BOUNDED_CURVE()B_SPLINE_CURVE(2,(#20,#21,#22,#23,#24),.UNSPECIFIED.,.F.,.F.)"
       "B_SPLINE_CURVE_WITH_KNOTS((3,1,1,3),(0.,0.3,0.7,1.),.UNSPECIFIED.)CURVE()"
       "GEOMETRIC_REPRESENTATION_ITEM()RATIONAL_B_SPLINE_CURVE((1.,0.8,1.3,0.9,1.))"
       "REPRESENTATION_ITEM(''));\n"
       // A closed, periodic-looking descriptor.
       "#33=B_SPLINE_CURVE_WITH_KNOTS('',2,(#20,#21,#22,#23),.UNSPECIFIED.,.T.,.F.,"
       "(1,1,1,1,1,1,1),(0.,1.,2.,3.,4.,5.,6.),.UNSPECIFIED.);\n"
       "#40=TRIMMED_CURVE('',#11,(PARAMETER_VALUE(0.5)),(PARAMETER_VALUE(2.)),.T.,.PARAMETER.);\n"
       "#41=TRIMMED_CURVE('',#10,(#21),(#24),.T.,.CARTESIAN.);\n"
       "#42=TRIMMED_CURVE('',#30,(0.1),(0.9),.F.,.UNSPECIFIED.);\n"
       "#43=POLYLINE('',(#20,#21,#22,#23));\n");
  for (uint64_t id : {10, 11, 12, 13, 14, 15, 30, 31, 32, 33, 40, 41, 42, 43}) ExpectSameCurve(id);
}

TEST_F(GeometryParity, SurfacesMatchStepToGeom) {
  std::string data = std::string(kPlacements) +
                     "#10=PLANE('',#4);\n"
                     "#11=CYLINDRICAL_SURFACE('',#4,2.5);\n"
                     "#12=CONICAL_SURFACE('',#4,1.5,0.3);\n"
                     "#13=SPHERICAL_SURFACE('',#5,4.);\n"
                     "#14=TOROIDAL_SURFACE('',#4,5.,1.25);\n"
                     "#15=CIRCLE('',#4,2.);\n"
                     "#16=SURFACE_OF_LINEAR_EXTRUSION('',#15,#7);\n"
                     "#17=SURFACE_OF_REVOLUTION('',#15,#9);\n"
                     "#18=OFFSET_SURFACE('',#11,0.25,.F.);\n"
                     "#19=RECTANGULAR_TRIMMED_SURFACE('',#11,0.5,2.,-1.,3.,.T.,.T.);\n";
  // A 4x3 B-spline surface, polynomial and rational.
  int id = 100;
  std::string rows;
  for (int i = 0; i < 4; ++i) {
    rows += i == 0 ? "(" : ",(";
    for (int j = 0; j < 3; ++j) {
      data += "#" + std::to_string(id) + "=CARTESIAN_POINT('',(" + std::to_string(i) + ".," +
              std::to_string(j) + ".," + std::to_string((i * 7 + j * 3) % 5) + ".));\n";
      rows += (j == 0 ? "#" : ",#") + std::to_string(id++);
    }
    rows += ")";
  }
  data += "#20=B_SPLINE_SURFACE_WITH_KNOTS('',3,2,(" + rows +
          "),.UNSPECIFIED.,.F.,.F.,.F.,(4,4),(3,3),(0.,1.),(0.,2.),.UNSPECIFIED.);\n";
  data += "#21=(BOUNDED_SURFACE()B_SPLINE_SURFACE(2,2,(" + rows +
          "),.UNSPECIFIED.,.F.,.F.,.F.)B_SPLINE_SURFACE_WITH_KNOTS((3,1,3),(3,3),(0.,0.5,1.),"
          "(0.,1.),.UNSPECIFIED.)GEOMETRIC_REPRESENTATION_ITEM()RATIONAL_B_SPLINE_SURFACE(("
          "(1.,1.,1.),(1.,0.7,1.),(1.,1.2,1.),(1.,1.,1.)))REPRESENTATION_ITEM('')SURFACE());\n";
  Load(data);
  for (uint64_t s : {10, 11, 12, 13, 14, 16, 17, 18, 19, 20, 21}) ExpectSameSurface(s);
}

TEST_F(GeometryParity, PcurvesMatchStepToGeom) {
  Load(
      "#1=CARTESIAN_POINT('',(0.5,1.5));\n"
      "#2=DIRECTION('',(0.6,0.8));\n"
      "#3=VECTOR('',#2,2.);\n"
      "#4=LINE('',#1,#3);\n"
      "#5=AXIS2_PLACEMENT_2D('',#1,#2);\n"
      "#6=CIRCLE('',#5,1.25);\n"
      "#7=ELLIPSE('',#5,1.,2.);\n"
      "#8=CARTESIAN_POINT('',(0.,0.));\n"
      "#9=CARTESIAN_POINT('',(1.,2.));\n"
      "#10=CARTESIAN_POINT('',(3.,1.));\n"
      "#11=B_SPLINE_CURVE_WITH_KNOTS('',2,(#8,#9,#10),.UNSPECIFIED.,.F.,.F.,(3,3),(0.,1.),"
      ".UNSPECIFIED.);\n"
      "#12=TRIMMED_CURVE('',#6,(PARAMETER_VALUE(0.25)),(PARAMETER_VALUE(1.5)),.T.,"
      ".PARAMETER.);\n"
      "#13=POLYLINE('',(#8,#9,#10));\n");
  for (uint64_t id : {4, 6, 7, 11, 12, 13}) ExpectSameCurve2d(id);
}

// ---------------------------------------------------------------------------------------------
// A unit cube written by hand: topology, units, product, colour.

struct CubeOptions {
  bool inch = false;
  bool colour = true;
  std::string extra;  ///< appended to the DATA section
};

// The cube [0,1]^3 as one MANIFOLD_SOLID_BREP of 6 planar faces, 12 line edges, 8 vertices,
// in an ADVANCED_BREP_SHAPE_REPRESENTATION of product 'cube'. Entity #1000 is the solid.
std::string CubeFile(const CubeOptions& options) {
  std::string d;
  int next = 1;
  auto add = [&](const std::string& body) {
    const int id = next++;
    d += "#" + std::to_string(id) + "=" + body + ";\n";
    return "#" + std::to_string(id);
  };
  auto pnt = [&](int x, int y, int z) {
    return add("CARTESIAN_POINT('',(" + std::to_string(x) + ".," + std::to_string(y) + ".," +
               std::to_string(z) + ".))");
  };
  auto dir = [&](int x, int y, int z) {
    return add("DIRECTION('',(" + std::to_string(x) + ".," + std::to_string(y) + ".," +
               std::to_string(z) + ".))");
  };
  std::array<std::string, 8> vertices;
  for (int i = 0; i < 8; ++i)
    vertices[i] = add("VERTEX_POINT(''," + pnt(i & 1, (i >> 1) & 1, (i >> 2) & 1) + ")");
  // Edges between vertices one bit apart, from the one without the bit.
  std::string edges[8][8];
  for (int a = 0; a < 8; ++a) {
    for (int bit = 0; bit < 3; ++bit) {
      if (a & (1 << bit)) continue;
      const int b = a | (1 << bit);
      const std::string axis = dir(bit == 0, bit == 1, bit == 2);
      const std::string line = add("LINE(''," + pnt(a & 1, (a >> 1) & 1, (a >> 2) & 1) + "," +
                                   add("VECTOR(''," + axis + ",1.)") + ")");
      edges[a][b] = edges[b][a] =
          add("EDGE_CURVE(''," + vertices[a] + "," + vertices[b] + "," + line + ",.T.)");
    }
  }
  std::vector<std::string> faces;
  for (int k = 0; k < 3; ++k) {
    const int i = k == 0 ? 1 : 0, j = k == 2 ? 1 : 2;
    const int sign = k == 1 ? -1 : 1;  // e_i x e_j = sign e_k
    for (int s = 0; s < 2; ++s) {
      std::vector<int> cycle;
      for (const auto& [bi, bj] : std::vector<std::pair<int, int>>{{0, 0}, {1, 0}, {1, 1}, {0, 1}})
        cycle.push_back((s << k) | (bi << i) | (bj << j));
      const int outward = s ? 1 : -1;
      if (sign != outward) std::reverse(cycle.begin(), cycle.end());
      std::string oriented;
      for (size_t c = 0; c < 4; ++c) {
        const int p = cycle[c], q = cycle[(c + 1) % 4];
        oriented += (c ? "," : "") + add("ORIENTED_EDGE('',*,*," + edges[p][q] + "," +
                                         (p < q ? ".T." : ".F.") + ")");
      }
      const std::string loop = add("EDGE_LOOP('',(" + oriented + "))");
      const std::string bound = add("FACE_OUTER_BOUND(''," + loop + ",.T.)");
      const std::string normal =
          dir(k == 0 ? outward : 0, k == 1 ? outward : 0, k == 2 ? outward : 0);
      const std::string xdir = dir(i == 0, i == 1, i == 2);
      const int corner = s << k;
      const std::string placement =
          add("AXIS2_PLACEMENT_3D(''," + pnt(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1) +
              "," + normal + "," + xdir + ")");
      const std::string plane = add("PLANE(''," + placement + ")");
      faces.push_back(add("ADVANCED_FACE('',(" + bound + ")," + plane + ",.T.)"));
    }
  }
  std::string shell_faces;
  for (size_t f = 0; f < faces.size(); ++f) shell_faces += (f ? "," : "") + faces[f];
  const std::string shell = add("CLOSED_SHELL('',(" + shell_faces + "))");
  d += "#1000=MANIFOLD_SOLID_BREP('cube'," + shell + ");\n";
  d += "#1001=APPLICATION_CONTEXT('automotive design');\n"
       "#1002=PRODUCT_CONTEXT('',#1001,'mechanical');\n"
       "#1003=PRODUCT('cube','cube','',(#1002));\n"
       "#1004=PRODUCT_DEFINITION_FORMATION('','',#1003);\n"
       "#1005=PRODUCT_DEFINITION_CONTEXT('part definition',#1001,'design');\n"
       "#1006=PRODUCT_DEFINITION('design','',#1004,#1005);\n"
       "#1007=PRODUCT_DEFINITION_SHAPE('','',#1006);\n"
       "#1008=SHAPE_DEFINITION_REPRESENTATION(#1007,#1009);\n"
       "#1009=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#1000),#1010);\n"
       "#1010=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#1014))"
       "GLOBAL_UNIT_ASSIGNED_CONTEXT((#1011,#1012,#1013))REPRESENTATION_CONTEXT('',''));\n"
       "#1012=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));\n"
       "#1013=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());\n"
       "#1014=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#1011,"
       "'distance_accuracy_value','');\n";
  if (options.inch) {
    d += "#1011=(CONVERSION_BASED_UNIT('INCH',#1016)LENGTH_UNIT()NAMED_UNIT(#1017));\n"
         "#1015=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));\n"
         "#1016=LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#1015);\n"
         "#1017=DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.);\n";
  } else {
    d += "#1011=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));\n";
  }
  if (options.colour) {
    d += "#1020=COLOUR_RGB('',1.,0.,0.);\n"
         "#1021=FILL_AREA_STYLE_COLOUR('',#1020);\n"
         "#1022=FILL_AREA_STYLE('',(#1021));\n"
         "#1023=SURFACE_STYLE_FILL_AREA(#1022);\n"
         "#1024=SURFACE_SIDE_STYLE('',(#1023));\n"
         "#1025=SURFACE_STYLE_USAGE(.BOTH.,#1024);\n"
         "#1026=PRESENTATION_STYLE_ASSIGNMENT((#1025));\n"
         "#1027=STYLED_ITEM('color',(#1026),#1000);\n"
         "#1028=MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#1027),#1010);\n";
  }
  return Wrap(d + options.extra);
}

// The id of the first LINE in `text` (an edge's curve in CubeFile).
int EdgeLineId(const std::string& text) {
  const size_t at = text.find("=LINE(");
  const size_t hash = text.rfind('#', at);
  return std::atoi(text.c_str() + hash + 1);
}

ShapeSummary OcctSummary(const std::string& bytes, ReadShape* out = nullptr) {
  Result<ReadShape> occt = ReadWithOcct(bytes, "", "t.step");
  EXPECT_TRUE(occt.ok()) << occt.status().ToString();
  if (!occt.ok()) return ShapeSummary();
  if (out != nullptr) *out = *occt;
  return Summarize(*occt);
}

TEST(StepTranslateTest, CubeSharesEdgesAndMatchesOcct) {
  const std::string text = CubeFile({});
  Result<Translated> ours = Translate(text);
  ASSERT_TRUE(ours.ok()) << ours.status().ToString();
  ASSERT_TRUE(ours->supported) << ours->unsupported;
  const TopoDS_Shape& shape = ours->read.shape;
  TopTools_IndexedMapOfShape solids, faces, edges, vertices;
  TopExp::MapShapes(shape, TopAbs_SOLID, solids);
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  TopExp::MapShapes(shape, TopAbs_EDGE, edges);
  TopExp::MapShapes(shape, TopAbs_VERTEX, vertices);
  EXPECT_EQ(solids.Extent(), 1);
  EXPECT_EQ(faces.Extent(), 6);
  EXPECT_EQ(edges.Extent(), 12);
  EXPECT_EQ(vertices.Extent(), 8);
  // One TopoDS edge per EDGE_CURVE, bounding two faces: the mesh stays watertight.
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  for (int i = 1; i <= edge_faces.Extent(); ++i) EXPECT_EQ(edge_faces(i).Extent(), 2);
  GProp_GProps volume;
  BRepGProp::VolumeProperties(shape, volume);
  EXPECT_NEAR(volume.Mass(), 1.0, 1e-12);
  EXPECT_EQ(ours->read.length_unit, "mm");
  EXPECT_EQ(ours->read.unit_scale_mm, 1.0);
  EXPECT_EQ(ours->items, 1);
  EXPECT_EQ(ours->items_healed_by_face, 1);

  // The part's name and colour, as OCCT's reader sets them.
  Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(ours->read.doc->Main());
  TDF_LabelSequence free;
  tool->GetFreeShapes(free);
  ASSERT_EQ(free.Length(), 1);
  Handle(TDataStd_Name) name;
  ASSERT_TRUE(free.First().FindAttribute(TDataStd_Name::GetID(), name));
  EXPECT_EQ(TCollection_AsciiString(name->Get()), TCollection_AsciiString("cube"));
  Quantity_ColorRGBA colour;
  ASSERT_TRUE(XCAFDoc_DocumentTool::ColorTool(ours->read.doc->Main())
                  ->GetColor(free.First(), XCAFDoc_ColorSurf, colour));
  EXPECT_DOUBLE_EQ(colour.GetRGB().Red(), 1.0);
  EXPECT_DOUBLE_EQ(colour.GetRGB().Green(), 0.0);

  const Comparison comparison = Compare(Summarize(ours->read), OcctSummary(text));
  EXPECT_TRUE(comparison.equivalent) << comparison.difference;
  EXPECT_EQ(comparison.worst_area_rel, 0.0);
  EXPECT_EQ(comparison.numbering_difference, "");
}

TEST(StepTranslateTest, CurveSetBesideTheSolidMatchesOcct) {
  // A GEOMETRIC_CURVE_SET of a point, a circle (with a curve colour) and a trimmed line in the
  // solid's representation, both curves in a hidden layer: a compound of a vertex and two edges
  // beside the solid, the colour on the circle's edge, the layer on both edges.
  CubeOptions options;
  options.extra =
      "#1030=GEOMETRIC_CURVE_SET('',(#1,#1031,#1032));\n"
      "#1031=CIRCLE('',#1033,0.5);\n"
      "#1032=TRIMMED_CURVE('',#1036,(PARAMETER_VALUE(0.)),(PARAMETER_VALUE(2.)),.T.,"
      ".PARAMETER.);\n"
      "#1033=AXIS2_PLACEMENT_3D('',#1,#1034,#1035);\n"
      "#1034=DIRECTION('',(0.,0.,1.));\n"
      "#1035=DIRECTION('',(1.,0.,0.));\n"
      "#1036=LINE('',#1,#1037);\n"
      "#1037=VECTOR('',#1035,1.);\n"
      "#1040=STYLED_ITEM('',(#1041),#1031);\n"
      "#1041=PRESENTATION_STYLE_ASSIGNMENT((#1042));\n"
      "#1042=CURVE_STYLE('',#1043,POSITIVE_LENGTH_MEASURE(0.1),#1044);\n"
      "#1043=DRAUGHTING_PRE_DEFINED_CURVE_FONT('continuous');\n"
      "#1044=COLOUR_RGB('',0.,0.,1.);\n"
      "#1045=MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#1040),#1010);\n"
      "#1050=PRESENTATION_LAYER_ASSIGNMENT('wires','',(#1031,#1032));\n"
      "#1051=INVISIBILITY((#1050));\n";
  std::string text = CubeFile(options);
  const std::string from = "#1009=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#1000)";
  text.replace(text.find(from), from.size(),
               "#1009=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#1000,#1030)");
  Result<Translated> ours = Translate(text);
  ASSERT_TRUE(ours.ok()) << ours.status().ToString();
  ASSERT_TRUE(ours->supported) << ours->unsupported;
  const ShapeSummary summary = Summarize(ours->read);
  EXPECT_EQ(summary.solids, 1);
  EXPECT_EQ(summary.faces, 6);
  EXPECT_EQ(summary.edges, 14);
  bool coloured_edge = false, layered = false;
  for (const std::string& line : summary.document) {
    if (line.find("sub-shape '' curve=(0.000000 0.000000 1.000000") != std::string::npos)
      coloured_edge = true;
    if (line.find("layers='wires' (hidden)") != std::string::npos) layered = true;
  }
  EXPECT_TRUE(coloured_edge);
  EXPECT_TRUE(layered);
  const Comparison comparison = Compare(summary, OcctSummary(text));
  EXPECT_TRUE(comparison.equivalent) << comparison.difference;
  EXPECT_EQ(comparison.numbering_difference, "");
  EXPECT_EQ(comparison.tolerance_difference, "");

  // A curve that is both in a set and an edge's curve is not reproduced.
  std::string shared = text;
  shared.replace(
      shared.find("#1030=GEOMETRIC_CURVE_SET('',(#1,#1031,#1032))"),
      std::string("#1030=GEOMETRIC_CURVE_SET('',(#1,#1031,#1032))").size(),
      "#1030=GEOMETRIC_CURVE_SET('',(#1,#1031,#" + std::to_string(EdgeLineId(text)) + "))");
  Result<Translated> refused = Translate(shared);
  ASSERT_TRUE(refused.ok()) << refused.status().ToString();
  EXPECT_FALSE(refused->supported);
  EXPECT_NE(refused->unsupported.find("used elsewhere"), std::string::npos) << refused->unsupported;
}

TEST(StepTranslateTest, InchesScaleToMillimetres) {
  const std::string text = CubeFile({/*inch=*/true});
  Result<Translated> ours = Translate(text);
  ASSERT_TRUE(ours.ok()) << ours.status().ToString();
  ASSERT_TRUE(ours->supported) << ours->unsupported;
  EXPECT_EQ(ours->read.length_unit, "inch");
  EXPECT_EQ(ours->read.unit_scale_mm, 25.4);
  Bnd_Box box;
  BRepBndLib::Add(ours->read.shape, box);
  double x0, y0, z0, x1, y1, z1;
  box.Get(x0, y0, z0, x1, y1, z1);
  EXPECT_NEAR(x1 - x0, 25.4, 1e-5);
  const Comparison comparison = Compare(Summarize(ours->read), OcctSummary(text));
  EXPECT_TRUE(comparison.equivalent) << comparison.difference;
}

TEST(StepTranslateTest, ThreadCountDoesNotChangeTheResult) {
  const fs::path path = fs::path(RDMESH_TEST_DATA) / "pyocc_eight_cyl.stp";
  const std::string bytes = ReadBytes(path);
  Result<Translated> one = Translate(bytes, 1);
  Result<Translated> two = Translate(bytes, 2);
  ASSERT_TRUE(one.ok() && two.ok());
  ASSERT_TRUE(one->supported && two->supported);
  const Comparison comparison = Compare(Summarize(one->read), Summarize(two->read));
  EXPECT_TRUE(comparison.equivalent) << comparison.difference;
  EXPECT_EQ(comparison.worst_area_rel, 0.0);
  EXPECT_EQ(comparison.numbering_difference, "");
}

// A face whose fixing cuts a shared edge's range (ShapeFix_SplitTool::CutEdge, where a wire's
// edges cross near a vertex) keeps its item healed face by face: the faces after it are fixed
// again with the edge cut and the tolerances raised as OCCT's run leaves them, and the result is
// OCCT's, edge tolerances too, on one thread or two.
TEST(StepTranslateTest, CutSharedEdgeKeepsTheItemHealedFaceByFace) {
  const fs::path path = fs::path(RDMESH_SHARED_DIR) / "corpus" / "gmsh_samplecrankshaft4a.stp";
  if (!fs::exists(path)) GTEST_SKIP() << path << " is missing";
  const std::string bytes = ReadBytes(path);
  Result<Translated> two = Translate(bytes, 2);
  Result<Translated> one = Translate(bytes, 1);
  ASSERT_TRUE(one.ok() && two.ok());
  ASSERT_TRUE(one->supported && two->supported);
  EXPECT_EQ(two->items, 1);
  EXPECT_EQ(two->items_healed_by_face, 1) << two->heal_note;
  EXPECT_EQ(two->items_in_order, 1);
  EXPECT_GE(two->faces_fixed_again, 1);
  const Comparison comparison = Compare(Summarize(two->read), OcctSummary(bytes));
  EXPECT_TRUE(comparison.equivalent) << comparison.difference;
  EXPECT_EQ(comparison.worst_area_rel, 0.0);
  EXPECT_EQ(comparison.numbering_difference, "");
  EXPECT_EQ(comparison.tolerance_difference, "");
  const Comparison threads = Compare(Summarize(one->read), Summarize(two->read));
  EXPECT_TRUE(threads.equivalent) << threads.difference;
  EXPECT_EQ(threads.worst_area_rel, 0.0);
  EXPECT_EQ(threads.tolerance_difference, "");
}

// ---------------------------------------------------------------------------------------------
// Broken and unsupported files.

TEST(StepTranslateTest, DanglingReferenceIsAParseErrorNamingBoth) {
  std::string text = CubeFile({});
  // The first EDGE_CURVE's line goes missing.
  const size_t at = text.find("=LINE(");
  ASSERT_NE(at, std::string::npos);
  const size_t start = text.rfind('\n', at) + 1;
  const std::string id = text.substr(start, at - start);
  text.erase(start, text.find('\n', at) - start + 1);
  Result<Translated> ours = Translate(text);
  ASSERT_FALSE(ours.ok());
  EXPECT_EQ(ours.status().code(), StatusCode::kParseError);
  EXPECT_NE(ours.status().message().find("EDGE_CURVE refers to " + id), std::string::npos)
      << ours.status().message();
}

TEST(StepTranslateTest, ReferenceCycleIsAParseError) {
  // A trimmed curve whose basis curve is itself, used by an edge.
  std::string text = CubeFile({});
  const size_t at = text.find("=LINE(");
  const size_t start = text.rfind('\n', at) + 1;
  const std::string id = text.substr(start, at - start);
  const size_t end = text.find('\n', at);
  text.replace(start, end - start, id + "=TRIMMED_CURVE(''," + id + ",(0.),(1.),.T.,.PARAMETER.);");
  Result<Translated> ours = Translate(text);
  ASSERT_FALSE(ours.ok());
  EXPECT_EQ(ours.status().code(), StatusCode::kParseError);
  EXPECT_NE(ours.status().message().find("cycle"), std::string::npos) << ours.status().message();
}

TEST(StepTranslateTest, NoProductIsAParseError) {
  Result<Translated> ours = Translate(Wrap("#1=CARTESIAN_POINT('',(0.,0.,0.));\n"));
  ASSERT_FALSE(ours.ok());
  EXPECT_EQ(ours.status().code(), StatusCode::kParseError);
}

// What the translator does not reproduce makes the file unsupported, with the entity named.
TEST(StepTranslateTest, UnsupportedConstructsAreNamed) {
  struct Case {
    std::string from, to, expect;
  };
  std::string text = CubeFile({});
  const size_t at = text.find("=LINE(");
  const size_t start = text.rfind('\n', at) + 1;
  const std::string line_id = text.substr(start, at - start);
  const std::vector<Case> cases = {
      // A curve OCCT builds but the translator does not.
      {line_id + "=LINE(", line_id + "=OFFSET_CURVE_3D('',#1,1.,.F.,#2);\n#9999=LINE(",
       line_id + " OFFSET_CURVE_3D"},
      // A degree beyond OCCT's limit.
      {line_id + "=LINE(",
       line_id + "=B_SPLINE_CURVE_WITH_KNOTS('',40,(#1,#1),.UNSPECIFIED.,.F.,.F.,(41,41),"
                 "(0.,1.),.UNSPECIFIED.);\n#9999=LINE(",
       "degree"},
      // A multiplicity no B-spline has.
      {line_id + "=LINE(",
       line_id + "=B_SPLINE_CURVE_WITH_KNOTS('',1,(#1,#1),.UNSPECIFIED.,.F.,.F.,"
                 "(2,99999999999),(0.,1.),.UNSPECIFIED.);\n#9999=LINE(",
       "multiplicity"},
      // A composite curve in a wireframe item beside the solid.
      {"#1009=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#1000)",
       "#1009=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#1000,#1030)", "COMPOSITE_CURVE"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.expect);
    std::string broken = text;
    const size_t where = broken.find(c.from);
    ASSERT_NE(where, std::string::npos);
    broken.replace(where, c.from.size(), c.to);
    if (c.expect == "COMPOSITE_CURVE")
      broken.insert(broken.find("ENDSEC;\nEND-ISO"),
                    "#1030=GEOMETRIC_CURVE_SET('',(#1,#1031));\n"
                    "#1031=COMPOSITE_CURVE('',(),.F.);\n");
    Result<Translated> ours = Translate(broken);
    ASSERT_TRUE(ours.ok()) << ours.status().ToString();
    EXPECT_FALSE(ours->supported);
    EXPECT_NE(ours->unsupported.find(c.expect), std::string::npos) << ours->unsupported;
  }
}

TEST(StepTranslateTest, StopsWhenTheContextSaysSo) {
  Result<File> file = Parse(CubeFile({}));
  ASSERT_TRUE(file.ok());
  Context context;
  context.Cancel();
  Result<Translated> ours = TranslateStep(*file, TranslateOptions{}, &context);
  ASSERT_FALSE(ours.ok());
  EXPECT_EQ(ours.status().code(), StatusCode::kCancelled);
}

// ---------------------------------------------------------------------------------------------
// Every bundled and corpus file: unsupported, or OCCT's read to the last bit of each face's area,
// with the same numbering.

void ExpectEquivalentOrUnsupported(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".step" || ext == ".stp") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  int supported = 0;
  double worst = 0;
  for (const fs::path& path : files) {
    SCOPED_TRACE(path.string());
    const std::string bytes = ReadBytes(path);
    Result<ReadShape> occt = ReadWithOcct(bytes, path.string(), path.filename().string());
    Result<Translated> ours = Translate(bytes);
    if (!occt.ok()) {
      // A file OCCT's reader refuses is refused or unsupported here too.
      EXPECT_TRUE(!ours.ok() || !ours->supported);
      continue;
    }
    ASSERT_TRUE(ours.ok()) << ours.status().ToString();
    if (!ours->supported) continue;
    ++supported;
    const Comparison comparison = Compare(Summarize(ours->read), Summarize(*occt));
    EXPECT_TRUE(comparison.equivalent) << comparison.difference;
    EXPECT_EQ(comparison.numbering_difference, "");
    EXPECT_EQ(ours->read.length_unit, occt->length_unit);
    EXPECT_EQ(ours->read.unit_scale_mm, occt->unit_scale_mm);
    worst = std::max(worst, comparison.worst_area_rel);
  }
  std::printf("%s: %d of %zu files supported, worst relative face area difference %.3g\n",
              dir.c_str(), supported, files.size(), worst);
}

TEST(StepTranslateTest, BundledFilesMatchOcct) {
  ExpectEquivalentOrUnsupported(fs::path(RDMESH_TEST_DATA));
}

TEST(StepTranslateTest, CorpusMatchesOcct) {
  const fs::path corpus = fs::path(RDMESH_SHARED_DIR) / "corpus";
  if (!fs::is_directory(corpus)) GTEST_SKIP() << corpus << " is missing";
  ExpectEquivalentOrUnsupported(corpus);
}

}  // namespace
}  // namespace rdmesh::step
