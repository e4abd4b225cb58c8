#include "model_readers.h"

#include <unistd.h>

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Message_ProgressIndicator.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

namespace rdmesh {

namespace {

// OCCT's translators share global state (static parameter tables, the session): one at a time.
std::mutex& ReaderMutex() {
  static std::mutex mutex;
  return mutex;
}

// OCCT prints translation warnings on the console through the default messenger: drop them.
void SilenceOcctMessages() {
  static std::once_flag once;
  std::call_once(
      once, [] { Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer)); });
}

// Lets a Context stop an OCCT transfer: OCCT polls UserBreak() between entities.
class StopIndicator : public Message_ProgressIndicator {
 public:
  explicit StopIndicator(const Context* context) : context_(context) {}
  Standard_Boolean UserBreak() override { return context_ != nullptr && context_->ShouldStop(); }
  void Show(const Message_ProgressScope&, const Standard_Boolean) override {}

 private:
  const Context* context_;
};

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

Status ParseError(const std::string& name, const std::string& reason) {
  return Status(StatusCode::kParseError, "cannot read '" + name + "': " + reason);
}

// The text after leading whitespace and a UTF-8 byte order mark.
size_t ContentStart(const std::string& bytes) {
  size_t i = bytes.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  while (i < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
  return i;
}

bool LooksLikeIges(const std::string& bytes) {
  size_t end = bytes.find('\n');
  std::string line = bytes.substr(0, end == std::string::npos ? bytes.size() : end);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line.size() >= 73 && line.size() <= 82 && line[72] == 'S';
}

// The last non-blank line of the text.
std::string LastLine(const std::string& bytes) {
  size_t end = bytes.find_last_not_of(" \t\r\n\x1a");
  if (end == std::string::npos) return "";
  size_t begin = bytes.rfind('\n', end);
  begin = begin == std::string::npos ? 0 : begin + 1;
  return bytes.substr(begin, end - begin + 1);
}

// Header and trailer checks that OCCT's parsers do not make reliably.
Status CheckFraming(const std::string& bytes, ModelFormat format, const std::string& name) {
  switch (format) {
    case ModelFormat::kStep: {
      if (bytes.compare(ContentStart(bytes), 12, "ISO-10303-21") != 0)
        return ParseError(name, "not a STEP file (no ISO-10303-21 header)");
      size_t tail = bytes.size() > 4096 ? bytes.size() - 4096 : 0;
      if (bytes.find("END-ISO-10303-21", tail) == std::string::npos)
        return ParseError(name, "truncated STEP file (no END-ISO-10303-21 trailer)");
      return Status::Ok();
    }
    case ModelFormat::kIges: {
      if (!LooksLikeIges(bytes))
        return ParseError(name, "not an IGES file (no 80-column start section)");
      std::string last = LastLine(bytes);
      if (last.size() < 73 || last[72] != 'T')
        return ParseError(name, "truncated IGES file (no terminate section)");
      return Status::Ok();
    }
    case ModelFormat::kBrep:
      if (FormatFromContent(bytes) != ModelFormat::kBrep)
        return ParseError(name, "not a BREP file (no CASCADE Topology header)");
      return Status::Ok();
    case ModelFormat::kAuto:
      break;
  }
  return ParseError(name, "unknown model format");
}

Handle(TDocStd_Document) NewXcafDocument() {
  // Not NewDocument(): that registers the document in the application's session for good.
  Handle(TDocStd_Document) doc = new TDocStd_Document("MDTV-XCAF");
  XCAFApp_Application::GetApplication()->InitDocument(doc);
  return doc;
}

// The document's free shapes (with their locations) as one compound.
TopoDS_Shape FreeShapesCompound(const Handle(TDocStd_Document) & doc) {
  Handle(XCAFDoc_ShapeTool) shape_tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  TDF_LabelSequence labels;
  shape_tool->GetFreeShapes(labels);
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  for (const TDF_Label& label : labels) {
    TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
    if (!shape.IsNull()) builder.Add(compound, shape);
  }
  return compound;
}

struct LengthUnit {
  const char* name;
  double mm;
};

// Maps a STEP or IGES unit name ("MILLIMETRE", "INCH", "MM", "METRE", ...) to a short name.
LengthUnit UnitFromName(std::string name) {
  std::string key;
  for (char c : name)
    if (std::isalpha(static_cast<unsigned char>(c)))
      key += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  static const struct {
    const char* key;
    LengthUnit unit;
  } kUnits[] = {
      {"MILLIMETRE", {"mm", 1.0}},  {"MILLIMETER", {"mm", 1.0}},  {"MM", {"mm", 1.0}},
      {"CENTIMETRE", {"cm", 10.0}}, {"CENTIMETER", {"cm", 10.0}}, {"CM", {"cm", 10.0}},
      {"METRE", {"m", 1000.0}},     {"METER", {"m", 1000.0}},     {"M", {"m", 1000.0}},
      {"KILOMETRE", {"km", 1e6}},   {"KILOMETER", {"km", 1e6}},   {"KM", {"km", 1e6}},
      {"MICROMETRE", {"um", 1e-3}}, {"MICROMETER", {"um", 1e-3}}, {"MICRON", {"um", 1e-3}},
      {"INCH", {"inch", 25.4}},     {"IN", {"inch", 25.4}},       {"FOOT", {"foot", 304.8}},
      {"FT", {"foot", 304.8}},      {"MIL", {"mil", 0.0254}},     {"MILE", {"mile", 1609344.0}},
  };
  for (const auto& entry : kUnits)
    if (key == entry.key) return entry.unit;
  return {"", 1.0};
}

void SetUnit(ReadShape* read, const std::string& raw_name) {
  LengthUnit unit = UnitFromName(raw_name);
  read->length_unit = unit.name[0] != '\0' ? unit.name : Lower(raw_name);
  read->unit_scale_mm = unit.mm;
}

Result<ReadShape> ReadStep(const std::string& bytes, const std::string& name,
                           const Context* context) {
  STEPCAFControl_Reader reader;
  reader.SetColorMode(true);
  reader.SetNameMode(true);
  reader.SetLayerMode(true);
  std::istringstream stream(bytes);
  if (reader.ChangeReader().ReadStream(name.c_str(), stream) != IFSelect_RetDone)
    return ParseError(name, "not a valid STEP file (the parser failed)");
  if (reader.NbRootsForTransfer() == 0) return ParseError(name, "the STEP file holds no shapes");

  ReadShape read;
  TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
  reader.ChangeReader().FileUnits(lengths, angles, solid_angles);
  SetUnit(&read, lengths.IsEmpty() ? "MILLIMETRE" : lengths.First().ToCString());

  read.doc = NewXcafDocument();
  Handle(StopIndicator) indicator = new StopIndicator(context);
  if (!reader.Transfer(read.doc, indicator->Start())) {
    if (context != nullptr && context->ShouldStop()) return context->StopStatus();
    return ParseError(name, "the STEP translator could not transfer the shapes");
  }
  read.shape = FreeShapesCompound(read.doc);
  return read;
}

// Writes the bytes to a new temporary file; returns its path, or "" on failure.
std::string WriteTempFile(const std::string& bytes, const char* suffix) {
  std::string pattern = (std::filesystem::temp_directory_path() / "rdmesh_XXXXXX").string();
  pattern += suffix;
  std::vector<char> path(pattern.begin(), pattern.end());
  path.push_back('\0');
  int fd = mkstemps(path.data(), static_cast<int>(std::char_traits<char>::length(suffix)));
  if (fd < 0) return "";
  bool ok = ::write(fd, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size());
  ::close(fd);
  if (!ok) {
    std::remove(path.data());
    return "";
  }
  return path.data();
}

Result<ReadShape> ReadIges(const std::string& bytes, const std::string& path,
                           const std::string& name, const Context* context) {
  std::string file = path;
  if (file.empty()) {
    file = WriteTempFile(bytes, ".igs");
    if (file.empty())
      return Status(StatusCode::kIoError, "cannot write a temporary file to read '" + name + "'");
  }
  struct TempRemover {
    std::string file;
    ~TempRemover() {
      if (!file.empty()) std::remove(file.c_str());
    }
  } remover{path.empty() ? file : ""};

  IGESCAFControl_Reader reader;
  reader.SetColorMode(true);
  reader.SetNameMode(true);
  reader.SetLayerMode(true);
  if (reader.ReadFile(file.c_str()) != IFSelect_RetDone)
    return ParseError(name, "not a valid IGES file (the parser failed)");

  ReadShape read;
  Handle(IGESData_IGESModel) iges = reader.IGESModel();
  if (!iges.IsNull()) {
    const IGESData_GlobalSection& global = iges->GlobalSection();
    static const char* const kFlagNames[] = {"",  "inch", "mm",  "",   "foot", "mile",
                                             "m", "km",   "mil", "um", "cm",   "microinch"};
    int flag = global.UnitFlag();
    std::string unit_name = flag >= 1 && flag <= 11 ? kFlagNames[flag] : "";
    if (unit_name.empty() && !global.UnitName().IsNull())
      unit_name = global.UnitName()->ToCString();
    if (unit_name == "microinch") {
      read.length_unit = unit_name;
      read.unit_scale_mm = 25.4e-6;
    } else {
      SetUnit(&read, unit_name.empty() ? "MM" : unit_name);
    }
  }

  read.doc = NewXcafDocument();
  Handle(StopIndicator) indicator = new StopIndicator(context);
  if (!reader.Transfer(read.doc, indicator->Start())) {
    if (context != nullptr && context->ShouldStop()) return context->StopStatus();
    return ParseError(name, "the IGES translator could not transfer the shapes");
  }
  read.shape = FreeShapesCompound(read.doc);
  return read;
}

Result<ReadShape> ReadBrep(const std::string& bytes, const std::string& name,
                           const Context* context) {
  ReadShape read;
  std::istringstream stream(bytes);
  BRep_Builder builder;
  Handle(StopIndicator) indicator = new StopIndicator(context);
  BRepTools::Read(read.shape, stream, builder, indicator->Start());
  if (context != nullptr && context->ShouldStop()) return context->StopStatus();
  if (read.shape.IsNull()) return ParseError(name, "not a valid BREP file (no shape)");
  return read;
}

}  // namespace

ModelFormat FormatFromExtension(const std::string& path) {
  std::string ext = Lower(std::filesystem::path(path).extension().string());
  if (ext == ".step" || ext == ".stp") return ModelFormat::kStep;
  if (ext == ".iges" || ext == ".igs") return ModelFormat::kIges;
  if (ext == ".brep" || ext == ".brp") return ModelFormat::kBrep;
  return ModelFormat::kAuto;
}

ModelFormat FormatFromContent(const std::string& bytes) {
  if (bytes.compare(ContentStart(bytes), 12, "ISO-10303-21") == 0) return ModelFormat::kStep;
  std::string head = bytes.substr(0, 512);
  if (head.find("CASCADE Topology") != std::string::npos ||
      head.find("DBRep_DrawableShape") != std::string::npos)
    return ModelFormat::kBrep;
  if (LooksLikeIges(bytes)) return ModelFormat::kIges;
  return ModelFormat::kAuto;
}

Result<ReadShape> ReadModelBytes(const std::string& bytes, ModelFormat format,
                                 const std::string& path, const std::string& name,
                                 const Context* context) {
  if (bytes.find_first_not_of(" \t\r\n") == std::string::npos)
    return ParseError(name, "empty file");
  Status framing = CheckFraming(bytes, format, name);
  if (!framing.ok()) return framing;

  std::lock_guard<std::mutex> lock(ReaderMutex());
  SilenceOcctMessages();
  try {
    switch (format) {
      case ModelFormat::kStep:
        return ReadStep(bytes, name, context);
      case ModelFormat::kIges:
        return ReadIges(bytes, path, name, context);
      case ModelFormat::kBrep:
        return ReadBrep(bytes, name, context);
      case ModelFormat::kAuto:
        break;
    }
    return ParseError(name, "unknown model format");
  } catch (const Standard_Failure& failure) {
    const char* what = failure.GetMessageString();
    return ParseError(
        name, std::string("the reader failed: ") + failure.DynamicType()->Name() +
                  (what != nullptr && what[0] != '\0' ? std::string(": ") + what : std::string()));
  } catch (const std::exception& e) {
    return ParseError(name, std::string("the reader failed: ") + e.what());
  } catch (...) {
    return ParseError(name, "the reader failed with an unknown exception");
  }
}

}  // namespace rdmesh
