// libFuzzer target: the Part 21 text parser (engine/src/model/step/part21) on arbitrary bytes.
// Built with -DRDMESH_FUZZ=ON and clang, like step_fuzzer; no OCCT runs, so every fault is ours.
// Beyond ASan/UBSan it traps on a broken invariant of a parsed file: offsets inside the text and
// the parameter array, instances in strictly ascending id order, Find returning each of them, a
// list's items stored before the list (so that no walk can loop), and refusals that name a line.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "model/step/part21.h"

namespace {

using rdmesh::step::File;
using rdmesh::step::Param;
using rdmesh::step::ParamKind;

void Check(bool ok) {
  if (!ok) __builtin_trap();
}

void CheckFile(const File& f) {
  const size_t text = f.text.size();
  for (size_t i = 0; i < f.params.size(); ++i) {
    const Param& p = f.params[i];
    switch (p.kind) {
      case ParamKind::kString:
      case ParamKind::kEnum:
      case ParamKind::kBinary:
        Check(uint64_t{p.first} + p.count <= text);
        Check(f.Text(p).size() == p.count);
        if (p.kind == ParamKind::kString) (void)rdmesh::step::DecodeString(f.Text(p));
        break;
      case ParamKind::kTyped:
        Check(p.count == 1);
        Check(p.name_offset + p.value.name_length <= text);
        Check(!f.TypedName(p).empty());
        [[fallthrough]];
      case ParamKind::kList:
        Check(uint64_t{p.first} + p.count <= i);
        if (p.count > 0) Check(f.Item(p, p.count - 1) == &f.params[p.first + p.count - 1]);
        Check(f.Item(p, p.count) == nullptr);
        break;
      default:
        Check(f.Item(p, 0) == nullptr && f.Text(p).empty());
    }
  }
  for (const rdmesh::step::Record& r : f.records) {
    Check(uint64_t{r.type_offset} + r.type_length <= text && r.type_length > 0);
    Check(uint64_t{r.first_param} + r.param_count <= f.params.size());
    Check(f.Arg(r, r.param_count) == nullptr);
  }
  for (size_t i = 0; i < f.instances.size(); ++i) {
    const rdmesh::step::Instance& inst = f.instances[i];
    if (i > 0) Check(f.instances[i - 1].id < inst.id);
    Check(inst.record_count > 0 && inst.line > 0);
    Check(uint64_t{inst.first_record} + inst.record_count <= f.records.size());
    Check(f.Find(inst.id) == &inst);
    const rdmesh::step::Record* first = f.RecordOf(inst);
    Check(first == &f.records[inst.first_record]);
    Check(f.RecordOf(inst, f.TypeName(*first)) != nullptr);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  (void)rdmesh::step::DecodeString(bytes);
  rdmesh::Result<File> file = rdmesh::step::Parse(std::string(bytes));
  if (file.ok()) {
    CheckFile(*file);
  } else {
    Check(file.status().code() == rdmesh::StatusCode::kParseError);
    Check(file.status().message().rfind("line ", 0) == 0);
  }
  return 0;
}
