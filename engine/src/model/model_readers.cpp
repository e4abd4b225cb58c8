// OCC_CATCH_SIGNALS below must turn access violations inside OCCT's translators into exceptions
// (Debian's OCCT is built this way too); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include "model/model_readers.h"

#include <unistd.h>

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <OSD.hxx>
#include <Standard_Failure.hxx>
#include <Standard_OutOfMemory.hxx>
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

#include "model/engine_module.h"
#include "model/occt_readers.h"
#include "model/reader_support.h"
#include "model/step/part21.h"
#include "model/step/translate.h"

// Defined when OCCT's readers are linked in (rdmesh_engine); null in a program linked to
// rdmesh_engine_lean, which loads them from the module instead (occt_readers.h).
extern "C" const rdmesh::OcctReaderApi* rdmesh_occt_reader_api() __attribute__((weak));

namespace rdmesh {

namespace {

// The module of OCCT's readers: rdmesh_occt_readers.so in the executable's folder.
Result<const OcctReaderApi*> LoadOcctReaders() {
  Result<const void*> module =
      LoadEngineModule("rdmesh_occt_readers.so", "rdmesh_occt_reader_api",
                       "OCCT's STEP and IGES readers", kOcctReaderApiVersion);
  if (!module.ok()) return module.status();
  return static_cast<const OcctReaderApi*>(*module);
}

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

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
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

// Swallows everything written to it.
class NullStreamBuffer : public std::streambuf {
 protected:
  int_type overflow(int_type c) override { return traits_type::not_eof(c); }
  std::streamsize xsputn(const char*, std::streamsize count) override { return count; }
};

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
  // Out of memory is no reason to try OCCT's reader, which would fail the same way, worse said;
  // nor is a module that cannot be loaded (kInternal: the document framework's, xcaf_api.h).
  if (!translated.ok() && (translated.status().code() == StatusCode::kResourceExhausted ||
                           translated.status().code() == StatusCode::kInternal))
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
  Result<const OcctReaderApi*> occt = OcctReaders();
  if (!occt.ok()) return occt.status();
  return (*occt)->read_step(bytes, name, context, start, fallback);
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
  Result<const OcctReaderApi*> occt = OcctReaders();
  if (!occt.ok()) return occt.status();
  return (*occt)->check_step(bytes, name);
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
      case ModelFormat::kIges: {
        Result<const OcctReaderApi*> occt = OcctReaders();
        if (!occt.ok()) return occt.status();
        return (*occt)->read_iges(bytes, path, name, context);
      }
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

Result<const OcctReaderApi*> OcctReaders() {
  if (rdmesh_occt_reader_api != nullptr) return rdmesh_occt_reader_api();
  static const Result<const OcctReaderApi*> loaded = LoadOcctReaders();
  return loaded;
}

}  // namespace rdmesh
