// step_read_runner: the plain OpenCASCADE STEP read that rdmesh's model load is compared with
// (bench/performance/load_cost.py, issue 14 part 3).
//
//   step_read_runner MODEL.step
//
// Reads MODEL.step with STEPControl_Reader (ReadFile, TransferRoots, OneShape), with OCCT's
// default settings, and prints one JSON line on stdout:
//   {"read_seconds": R, "transfer_seconds": T, "seconds": R + T, "faces": F}
// Nothing else: no names or colours (XCAF), no healing beyond the transfer's own, no areas.

#include <IFSelect_ReturnStatus.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Shape.hxx>
#include <chrono>
#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s MODEL.step\n", argv[0]);
    return 2;
  }
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  STEPControl_Reader reader;
  if (reader.ReadFile(argv[1]) != IFSelect_RetDone) {
    std::fprintf(stderr, "%s: cannot read %s\n", argv[0], argv[1]);
    return 3;
  }
  const auto read = Clock::now();
  reader.TransferRoots();
  const TopoDS_Shape shape = reader.OneShape();
  const auto done = Clock::now();
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  const double read_s = std::chrono::duration<double>(read - start).count();
  const double transfer_s = std::chrono::duration<double>(done - read).count();
  std::printf(
      "{\"read_seconds\": %.6f, \"transfer_seconds\": %.6f, \"seconds\": %.6f, "
      "\"faces\": %d}\n",
      read_s, transfer_s, read_s + transfer_s, faces.Extent());
  return 0;
}
