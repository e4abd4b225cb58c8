// OCC_CATCH_SIGNALS below must turn access violations inside OCCT's translators into exceptions
// (Debian's OCCT is built this way too); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include "model/model_readers.h"

#include <unistd.h>

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <Interface_InterfaceModel.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Message_ProgressIndicator.hxx>
#include <OSD.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <Standard_OutOfMemory.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XSControl_WorkSession.hxx>
#include <algorithm>
#include <cctype>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <istream>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <streambuf>
#include <vector>

#include "model/step/part21.h"
#include "model/step/translate.h"
#include "model/step_precheck.h"

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

// While alive, faults (SIGSEGV, SIGBUS, SIGFPE, SIGILL) go to OCCT's handlers, which jump to the
// nearest OCC_CATCH_SIGNALS and throw a Standard_Failure: OCCT 7.6's translators dereference null
// entities in some broken files. Every other signal keeps its handler (Ctrl-C still cancels),
// and the previous handlers come back at the end. Process-wide: callers hold ReaderMutex.
class ScopedOcctFaultHandlers {
 public:
  ScopedOcctFaultHandlers() {
    for (int signal = 1; signal < kSignals; ++signal) sigaction(signal, nullptr, &saved_[signal]);
    OSD::SetSignal(OSD_SignalMode_Set, /*theFloatingSignal=*/false);
    for (int signal = 1; signal < kSignals; ++signal)
      if (!IsFault(signal)) sigaction(signal, &saved_[signal], nullptr);
  }
  ~ScopedOcctFaultHandlers() {
    for (int signal = 1; signal < kSignals; ++signal)
      if (IsFault(signal)) sigaction(signal, &saved_[signal], nullptr);
  }
  ScopedOcctFaultHandlers(const ScopedOcctFaultHandlers&) = delete;
  ScopedOcctFaultHandlers& operator=(const ScopedOcctFaultHandlers&) = delete;

 private:
  static constexpr int kSignals = 32;  // the standard signals
  static bool IsFault(int signal) {
    return signal == SIGSEGV || signal == SIGBUS || signal == SIGFPE || signal == SIGILL;
  }
  struct sigaction saved_[kSignals] = {};
};

// Runs one call into OCCT's readers under its own OCC_CATCH_SIGNALS. A fault inside lands here and
// leaves as a Standard_Failure thrown from this frame, so the caller's objects unwind normally; the
// handler in ReadModelBytes alone would longjmp over the caller's frame and leak what it holds.
template <typename Call>
auto GuardFaults(Call&& call) -> decltype(call()) {
  OCC_CATCH_SIGNALS
  return call();
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

// The model is not to blame: the reader ran out of memory.
Status OutOfMemory(const std::string& name) {
  return Status(StatusCode::kResourceExhausted, "cannot read '" + name + "': out of memory");
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

// A BREP file lists "TShapes N", then N shapes whose sub-shape lists each end with '*', then the
// root as "+id location". OCCT's reader loops forever on some truncated files: check first.
bool BrepIsComplete(const std::string& bytes) {
  size_t header = bytes.find("\nTShapes ");
  if (header == std::string::npos) return false;
  long count = std::strtol(bytes.c_str() + header + 9, nullptr, 10);
  if (count <= 0) return false;
  long starred = 0;
  std::string root;
  std::istringstream lines(bytes.substr(header + 1));
  for (std::string line; std::getline(lines, line);) {
    size_t end = line.find_last_not_of(" \t\r");
    if (end == std::string::npos) continue;
    line.resize(end + 1);
    if (line.back() == '*') {
      ++starred;
    } else if (starred >= count && root.empty()) {
      root = line;
    }
  }
  static const std::regex kRoot("[+\\-ie][0-9]+ [0-9]+");
  return starred >= count && std::regex_match(root, kRoot);
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
      if (!BrepIsComplete(bytes))
        return ParseError(name, "truncated BREP file (incomplete TShapes section)");
      return Status::Ok();
    case ModelFormat::kAuto:
      break;
  }
  return ParseError(name, "unknown model format");
}

// An input stream over bytes held elsewhere, so big files are not copied once more.
class MemoryStreamBuffer : public std::streambuf {
 public:
  explicit MemoryStreamBuffer(const std::string& bytes) {
    char* begin = const_cast<char*>(bytes.data());  // never written: get area only
    setg(begin, begin, begin + bytes.size());
  }

 protected:
  pos_type seekoff(off_type offset, std::ios_base::seekdir dir, std::ios_base::openmode) override {
    char* base = dir == std::ios_base::beg ? eback() : dir == std::ios_base::cur ? gptr() : egptr();
    return seekpos(pos_type(base - eback() + offset), std::ios_base::in);
  }
  pos_type seekpos(pos_type position, std::ios_base::openmode) override {
    if (position < 0 || position > egptr() - eback()) return pos_type(off_type(-1));
    setg(eback(), eback() + position, egptr());
    return position;
  }
};

// Swallows everything written to it.
class NullStreamBuffer : public std::streambuf {
 protected:
  int_type overflow(int_type c) override { return traits_type::not_eof(c); }
  std::streamsize xsputn(const char*, std::streamsize count) override { return count; }
};

Handle(TDocStd_Document) NewXcafDocument() {
  // Not NewDocument(): that registers the document in the application's session for good.
  Handle(TDocStd_Document) doc = new TDocStd_Document("MDTV-XCAF");
  XCAFApp_Application::GetApplication()->InitDocument(doc);
  return doc;
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

// Which STEP reader runs: rdmesh's own first (model/step), with OCCT's for what it does not
// cover; RDMESH_STEP_READER=occt forces OCCT's alone (to compare the two).
bool OwnStepReader() {
  const char* choice = std::getenv("RDMESH_STEP_READER");
  return choice == nullptr || std::string(choice) != "occt";
}

// rdmesh's own STEP reader (model/step): the Part 21 parser, then the translator. Null when the
// file holds something the translator does not reproduce, or text our parser refuses: OCCT's
// reader then reads it (and gives its own error). `why` says which.
Result<std::optional<ReadShape>> ReadStepOwn(const std::string& bytes, const Context* context,
                                             std::string* why) {
  auto start = std::chrono::steady_clock::now();
  Result<step::File> file = step::Parse(bytes, context);
  if (context != nullptr && context->ShouldStop()) return context->StopStatus();
  if (!file.ok()) {
    *why = "parser: " + file.status().message();
    return std::optional<ReadShape>();
  }
  const double parse_seconds = SecondsSince(start);
  Result<step::Translated> translated =
      step::TranslateStep(*file, step::TranslateOptions{}, context);
  if (context != nullptr && context->ShouldStop()) return context->StopStatus();
  // Out of memory is no reason to try OCCT's reader, which would fail the same way, worse said.
  if (!translated.ok() && translated.status().code() == StatusCode::kResourceExhausted)
    return translated.status();
  if (!translated.ok()) {
    *why = "translator: " + translated.status().message();
    return std::optional<ReadShape>();
  }
  if (!translated->supported) {
    *why = "unsupported: " + translated->unsupported;
    return std::optional<ReadShape>();
  }
  ReadShape read = std::move(translated->read);
  read.reader = "rdmesh";
  read.stages.emplace_back("parse", parse_seconds);
  for (auto& stage : translated->stage_seconds) read.stages.push_back(std::move(stage));
  return std::optional<ReadShape>(std::move(read));
}

Result<ReadShape> ReadStep(const std::string& bytes, const std::string& name,
                           const Context* context) {
  auto start = std::chrono::steady_clock::now();
  std::string fallback;
  if (OwnStepReader()) {
    // A failure inside OCCT's modelling classes (or a signal they raise, which the caller's
    // OCC_CATCH_SIGNALS turns into one) costs the own reader its turn, not the file: OCCT's
    // reader gets it.
    try {
      Result<std::optional<ReadShape>> own = ReadStepOwn(bytes, context, &fallback);
      if (!own.ok() && own.status().code() == StatusCode::kResourceExhausted)
        return Status(StatusCode::kResourceExhausted,
                      "cannot read '" + name + "': " + own.status().message());
      if (!own.ok()) return own.status();
      if (own->has_value()) return std::move(**own);
    } catch (const Standard_OutOfMemory&) {
      return OutOfMemory(name);
    } catch (const Standard_Failure& failure) {
      fallback = std::string("own reader failed: ") + failure.DynamicType()->Name();
    }
  }
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

Result<ReadShape> ReadBrep(const std::string& bytes, const std::string& name,
                           const Context* context) {
  ReadShape read;
  MemoryStreamBuffer buffer(bytes);
  std::istream stream(&buffer);
  BRep_Builder builder;
  Handle(StopIndicator) indicator = new StopIndicator(context);
  GuardFaults([&] { BRepTools::Read(read.shape, stream, builder, indicator->Start()); });
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

ModelFormat ResolveFormat(ModelFormat format, const std::string& name, const std::string& bytes) {
  if (format == ModelFormat::kAuto) format = FormatFromExtension(name);
  if (format == ModelFormat::kAuto) format = FormatFromContent(bytes);
  return format;
}

Status CheckStepBytes(const std::string& bytes, const std::string& name) {
  std::lock_guard<std::mutex> lock(ReaderMutex());
  SilenceOcctMessages();
  STEPControl_Reader reader;
  return ParseStep(bytes, name, reader);
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
  // Some OCCT readers also print straight to std::cout ("Not a TShape table"), which would mix
  // into a client's stdout (rdmesh --json): mute it while reading.
  NullStreamBuffer null_buffer;
  struct CoutRestorer {
    std::streambuf* saved;
    ~CoutRestorer() { std::cout.rdbuf(saved); }
  } restore_cout{std::cout.rdbuf(&null_buffer)};
  ScopedOcctFaultHandlers fault_handlers;
  try {
    OCC_CATCH_SIGNALS
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
  } catch (const Standard_OutOfMemory&) {
    return OutOfMemory(name);
  } catch (const std::bad_alloc&) {
    return OutOfMemory(name);
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
