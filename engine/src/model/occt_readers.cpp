// OCC_CATCH_SIGNALS below must turn access violations inside OCCT's translators into exceptions
// (Debian's OCCT is built this way too); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include "model/occt_readers.h"

#include <unistd.h>

#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <Interface_InterfaceModel.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TCollection_HAsciiString.hxx>
#include <XCAFApp_Application.hxx>
#include <XSControl_WorkSession.hxx>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <istream>
#include <tuple>
#include <vector>

#include "model/length_unit.h"
#include "model/reader_support.h"
#include "model/step_precheck.h"

namespace rdmesh {

namespace {

Handle(TDocStd_Document) NewXcafDocument() {
  // Not NewDocument(): that registers the document in the application's session for good.
  Handle(TDocStd_Document) doc = new TDocStd_Document("MDTV-XCAF");
  XCAFApp_Application::GetApplication()->InitDocument(doc);
  return doc;
}

void SetUnit(ReadShape* read, const std::string& raw_name) {
  std::tie(read->length_unit, read->unit_scale_mm) = LengthUnitOf(raw_name);
}

// Which parser complaints refuse a file before the transfer. IGES: any complaint on a geometric
// or solid entity (OCCT 7.6's IGES translator dereferences the null fields the parser leaves).
// STEP: only a reference from a geometric or topological entity to an entity that is not in the
// file: OCCT does not crash on it but drops that face without a word (cq_red_cube_blue_cylinder
// with one face's surface reference dangling loads 8 of 9 faces). Other STEP complaints are common
// in real files that OCCT transfers fine: entity types it does not know (newer AP242 items: "Entity
// has illegal type"), names that are not quoted strings, styles, PMI.
struct FatalChecks {
  const char* format;              // "STEP" or "IGES", for messages
  std::vector<std::string> types;  // entity class prefixes whose complaints count
  std::vector<std::string> fatal;  // the message fragments that count (empty: all)
};

const FatalChecks kStepChecks{"STEP", {"StepGeom_", "StepShape_"}, {"is unresolved"}};
const FatalChecks kIgesChecks{"IGES", {"IGESGeom_", "IGESSolid_"}, {}};

bool StartsWithAny(const std::string& text, const std::vector<std::string>& prefixes) {
  for (const std::string& prefix : prefixes)
    if (text.rfind(prefix, 0) == 0) return true;
  return false;
}

bool ContainsAny(const std::string& text, const std::vector<std::string>& parts) {
  for (const std::string& part : parts)
    if (text.find(part) != std::string::npos) return true;
  return false;
}

// Refuses a parsed file whose geometry the translator would crash on or silently lose.
Status CheckReferences(XSControl_Reader& reader, const FatalChecks& fatal,
                       const std::string& name) {
  Handle(Interface_InterfaceModel) model = reader.WS()->Model();
  if (model.IsNull()) return Status::Ok();
  Interface_CheckIterator checks =
      GuardFaults([&] { return reader.WS()->ModelCheckList(/*complete=*/false); });
  int broken = 0;
  std::string first;
  for (checks.Start(); checks.More(); checks.Next()) {
    const Handle(Interface_Check)& check = checks.Value();
    int number = checks.Number();
    if (!check->HasFailed() || number < 1 || number > model->NbEntities()) continue;
    Handle(Standard_Transient) entity = model->Value(number);
    std::string type = entity->DynamicType()->Name();
    if (!StartsWithAny(type, fatal.types)) continue;
    for (int i = 1; i <= check->NbFails(); ++i) {
      std::string message = check->CFail(i);
      if (!fatal.fatal.empty() && !ContainsAny(message, fatal.fatal)) continue;
      if (broken++ == 0)
        first = std::string(model->StringLabel(entity)->ToCString()) + " (" +
                type.substr(type.find('_') + 1) + "): " + message;
    }
  }
  if (broken == 0) return Status::Ok();
  return ParseError(
      name, std::string("broken ") + fatal.format + " data at " + first +
                (broken > 1 ? " (and " + std::to_string(broken - 1) + " more)" : std::string()));
}

// Parses the bytes into `reader`, with the checks that refuse a file before the transfer.
Status ParseStep(const std::string& bytes, const std::string& name, XSControl_Reader& reader) {
  std::string crash = StepCrashReason(bytes);
  if (!crash.empty()) return ParseError(name, crash + " (OCCT's reader would crash or hang on it)");
  MemoryStreamBuffer buffer(bytes);
  std::istream stream(&buffer);
  if (GuardFaults([&] { return reader.ReadStream(name.c_str(), stream); }) != IFSelect_RetDone)
    return ParseError(name, "not a valid STEP file (the parser failed)");
  return CheckReferences(reader, kStepChecks, name);
}

// OCCT's STEP reader, after rdmesh's own passed the file on (or was not asked).
Result<ReadShape> ReadStep(const std::string& bytes, const std::string& name,
                           const Context* context, std::chrono::steady_clock::time_point start,
                           const std::string& fallback) {
  STEPCAFControl_Reader reader;
  reader.SetColorMode(true);
  reader.SetNameMode(true);
  reader.SetLayerMode(true);
  Status parsed = ParseStep(bytes, name, reader.ChangeReader());
  if (!parsed.ok()) return parsed;
  if (reader.NbRootsForTransfer() == 0) return ParseError(name, "the STEP file holds no shapes");

  ReadShape read;
  read.stages.emplace_back("occt_parse", SecondsSince(start));
  start = std::chrono::steady_clock::now();
  TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
  GuardFaults([&] { reader.ChangeReader().FileUnits(lengths, angles, solid_angles); });
  SetUnit(&read, lengths.IsEmpty() ? "MILLIMETRE" : lengths.First().ToCString());

  read.doc = NewXcafDocument();
  Handle(StopIndicator) indicator = new StopIndicator(context);
  if (!GuardFaults([&] { return reader.Transfer(read.doc, indicator->Start()); })) {
    if (context != nullptr && context->ShouldStop()) return context->StopStatus();
    return ParseError(name, "the STEP translator could not transfer the shapes");
  }
  read.shape = GuardFaults([&] { return FreeShapesCompound(read.doc); });
  read.stages.emplace_back("occt_transfer", SecondsSince(start));
  read.reader = "occt";
  read.reader_note = fallback;
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
  if (GuardFaults([&] { return reader.ReadFile(file.c_str()); }) != IFSelect_RetDone)
    return ParseError(name, "not a valid IGES file (the parser failed)");
  Status references = CheckReferences(reader, kIgesChecks, name);
  if (!references.ok()) return references;

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
  if (!GuardFaults([&] { return reader.Transfer(read.doc, indicator->Start()); })) {
    if (context != nullptr && context->ShouldStop()) return context->StopStatus();
    return ParseError(name, "the IGES translator could not transfer the shapes");
  }
  read.shape = GuardFaults([&] { return FreeShapesCompound(read.doc); });
  return read;
}

Status CheckStep(const std::string& bytes, const std::string& name) {
  STEPControl_Reader reader;
  return ParseStep(bytes, name, reader);
}

constexpr OcctReaderApi kApi{kOcctReaderApiVersion, &ReadStep, &ReadIges, &CheckStep};

}  // namespace

}  // namespace rdmesh

extern "C" __attribute__((visibility("default"))) const rdmesh::OcctReaderApi*
rdmesh_occt_reader_api() {
  return &rdmesh::kApi;
}
