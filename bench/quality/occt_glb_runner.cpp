// occt_glb_runner: OCCT's own way from STEP to glTF, the peer of bench/quality/glb_size.py.
//
//   occt_glb_runner MODEL.step DEFLECTION ANGLE OUT.glb
//
// STEPCAFControl_Reader into an XCAF document (names, colours, assembly), BRepMesh_IncrementalMesh
// on every free shape at an absolute linear deflection DEFLECTION (model units) and an angular
// deflection ANGLE (radians), in parallel, as bench/brepmesh_runner meshes, then
// RWGltf_CafWriter with its default settings (binary; millimetres to metres, +Z up to +Y up, as
// rdmesh writes). Prints one JSON line: {"bytes": B, "seconds": S} (S: the write alone).

#include <BRepMesh_IncrementalMesh.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Message_ProgressRange.hxx>
#include <RWGltf_CafWriter.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_IndexedDataMapOfStringString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDocStd_Document.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s MODEL.step DEFLECTION ANGLE OUT.glb\n", argv[0]);
    return 2;
  }
  // OCCT's reader reports to stdout; keep stdout for the JSON line.
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));
  try {
    Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
    Handle(TDocStd_Document) doc;
    app->NewDocument("BinXCAF", doc);
    STEPCAFControl_Reader reader;
    reader.SetColorMode(true);
    reader.SetNameMode(true);
    if (reader.ReadFile(argv[1]) != IFSelect_RetDone || !reader.Transfer(doc)) {
      std::fprintf(stderr, "cannot read %s\n", argv[1]);
      return 1;
    }
    IMeshTools_Parameters params;
    params.Deflection = std::atof(argv[2]);
    params.Angle = std::atof(argv[3]);
    params.InParallel = true;
    Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    TDF_LabelSequence roots;
    shapes->GetFreeShapes(roots);
    for (const TDF_Label& root : roots) BRepMesh_IncrementalMesh(shapes->GetShape(root), params);
    const auto start = std::chrono::steady_clock::now();
    RWGltf_CafWriter writer(argv[4], /*theIsBinary=*/true);
    writer.ChangeCoordinateSystemConverter().SetInputLengthUnit(0.001);
    writer.ChangeCoordinateSystemConverter().SetInputCoordinateSystem(RWMesh_CoordinateSystem_Zup);
    TColStd_IndexedDataMapOfStringString info;
    if (!writer.Perform(doc, info, Message_ProgressRange())) {
      std::fprintf(stderr, "the glTF writer failed\n");
      return 1;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("{\"bytes\": %llu, \"seconds\": %.4f}\n",
                static_cast<unsigned long long>(std::filesystem::file_size(argv[4])), seconds);
  } catch (const Standard_Failure& failure) {
    std::fprintf(stderr, "OCCT failure: %s\n", failure.GetMessageString());
    return 1;
  }
  return 0;
}
