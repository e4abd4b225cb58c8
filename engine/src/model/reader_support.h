#pragma once
// What the model readers (model_readers.cpp, and OCCT's in occt_readers.cpp) share. A file that
// includes this defines OCC_CONVERT_SIGNALS before any OCCT header, so that OCC_CATCH_SIGNALS
// turns access violations inside OCCT into exceptions. Internal to the engine.

#include <Message_ProgressIndicator.hxx>
#include <Standard_ErrorHandler.hxx>
#include <streambuf>
#include <string>

#include "rdmesh/context.h"

namespace rdmesh {

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

}  // namespace rdmesh
