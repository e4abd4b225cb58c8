#include "model/step/entities.h"

#include <cmath>
#include <utility>

namespace rdmesh::step {

void ThrowUnsupported(std::string what) { throw Unsupported{std::move(what)}; }

void ThrowBroken(std::string what) { throw Broken{std::move(what)}; }

std::string Describe(const File& file, const Instance& instance) {
  std::string text = "#" + std::to_string(instance.id) + " ";
  if (instance.record_count == 1) {
    text += file.TypeName(file.records[instance.first_record]);
    return text;
  }
  text += "(";
  for (uint32_t r = 0; r < instance.record_count; ++r) {
    if (r > 0) text += " ";
    text += file.TypeName(file.records[instance.first_record + r]);
  }
  return text + ")";
}

std::string Entity::Name() const { return Describe(*file_, *instance_); }

void Entity::Fail(uint32_t i, const char* expected) const {
  ThrowUnsupported(Name() + ": parameter " + std::to_string(i + 1) + " is not " + expected);
}

const Param& Entity::At(uint32_t i) const {
  const Param* param = file_->Arg(*record_, i);
  if (param == nullptr)
    ThrowUnsupported(Name() + ": " + std::to_string(record_->param_count) +
                     " parameters, fewer than expected");
  return *param;
}

bool Entity::IsUnset(uint32_t i) const { return At(i).kind == ParamKind::kUnset; }

namespace {

// Reals beyond the range of a double (1.E+999) are refused: OCCT's healing crashes or searches
// for ever on infinite coordinates (step_precheck.h).
bool AsReal(const Param& param, double* value) {
  if (param.kind == ParamKind::kReal) {
    *value = param.value.real;
    if (!std::isfinite(*value)) ThrowUnsupported("a number beyond the range of a double");
    return true;
  }
  if (param.kind == ParamKind::kInteger) {
    *value = static_cast<double>(param.value.integer);
    return true;
  }
  return false;
}

}  // namespace

double Entity::Real(uint32_t i) const {
  double value = 0.0;
  if (!AsReal(At(i), &value)) Fail(i, "a number");
  return value;
}

double Entity::Measure(uint32_t i) const {
  const Param& param = At(i);
  double value = 0.0;
  if (AsReal(param, &value)) return value;
  if (param.kind == ParamKind::kTyped) {
    const Param* inner = file_->Item(param, 0);
    if (inner != nullptr && AsReal(*inner, &value)) return value;
  }
  Fail(i, "a measure");
}

int64_t Entity::Integer(uint32_t i) const {
  const Param& param = At(i);
  if (param.kind != ParamKind::kInteger) Fail(i, "an integer");
  return param.value.integer;
}

bool Entity::Logical(uint32_t i) const {
  const Param& param = At(i);
  if (param.kind == ParamKind::kEnum) {
    std::string_view text = file_->Text(param);
    if (text == "T") return true;
    if (text == "F") return false;
  }
  Fail(i, "a boolean (.T. or .F.)");
}

std::string_view Entity::Enum(uint32_t i) const {
  const Param& param = At(i);
  if (param.kind != ParamKind::kEnum) Fail(i, "an enumeration");
  return file_->Text(param);
}

uint64_t Entity::Ref(uint32_t i) const {
  const Param& param = At(i);
  if (param.kind != ParamKind::kRef) Fail(i, "a reference");
  return param.value.ref;
}

const Param& Entity::List(uint32_t i) const {
  const Param& param = At(i);
  if (param.kind != ParamKind::kList) Fail(i, "a list");
  return param;
}

std::string Entity::String(uint32_t i) const {
  const Param& param = At(i);
  if (param.kind == ParamKind::kUnset) return "";
  if (param.kind != ParamKind::kString) Fail(i, "a string");
  return DecodeString(file_->Text(param));
}

const Param& Entity::Item(const Param& list, uint32_t i) const {
  const Param* item = file_->Item(list, i);
  if (item == nullptr) ThrowUnsupported(Name() + ": a list is shorter than expected");
  return *item;
}

double Entity::RealItem(const Param& list, uint32_t i) const {
  double value = 0.0;
  if (!AsReal(Item(list, i), &value)) ThrowUnsupported(Name() + ": a list item is not a number");
  return value;
}

int64_t Entity::IntegerItem(const Param& list, uint32_t i) const {
  const Param& item = Item(list, i);
  if (item.kind != ParamKind::kInteger)
    ThrowUnsupported(Name() + ": a list item is not an integer");
  return item.value.integer;
}

uint64_t Entity::RefItem(const Param& list, uint32_t i) const {
  const Param& item = Item(list, i);
  if (item.kind != ParamKind::kRef) ThrowUnsupported(Name() + ": a list item is not a reference");
  return item.value.ref;
}

const Param& Entity::ListItem(const Param& list, uint32_t i) const {
  const Param& item = Item(list, i);
  if (item.kind != ParamKind::kList) ThrowUnsupported(Name() + ": a list item is not a list");
  return item;
}

const Instance& Entities::Get(uint64_t id, uint64_t from) const {
  const Instance* instance = file_.Find(id);
  if (instance == nullptr) {
    if (from == 0) ThrowBroken("#" + std::to_string(id) + " is not in the file");
    const Instance* source = file_.Find(from);
    ThrowBroken((source != nullptr ? step::Describe(file_, *source) : "#" + std::to_string(from)) +
                " refers to #" + std::to_string(id) + ", which is not in the file");
  }
  return *instance;
}

std::string_view Entities::SimpleType(const Instance& instance) const {
  if (instance.record_count != 1) return {};
  return file_.TypeName(file_.records[instance.first_record]);
}

bool Entities::HasPart(const Instance& instance, std::string_view type) const {
  for (uint32_t r = 0; r < instance.record_count; ++r)
    if (file_.TypeName(file_.records[instance.first_record + r]) == type) return true;
  return false;
}

bool Entities::Is(const Instance& instance, std::string_view type) const {
  if (instance.record_count == 1) return SimpleType(instance) == type;
  return HasPart(instance, type);
}

Entity Entities::Simple(const Instance& instance) const {
  return Entity(&file_, &instance, &file_.records[instance.first_record]);
}

Entity Entities::Part(const Instance& instance, std::string_view type) const {
  for (uint32_t r = 0; r < instance.record_count; ++r) {
    const Record& record = file_.records[instance.first_record + r];
    if (file_.TypeName(record) == type) return Entity(&file_, &instance, &record);
  }
  ThrowUnsupported(Describe(instance) + ": no " + std::string(type) + " part");
}

std::string Entities::TypeList(const Instance& instance) const {
  std::string text = "(";
  for (uint32_t r = 0; r < instance.record_count; ++r) {
    if (r > 0) text += " ";
    text += file_.TypeName(file_.records[instance.first_record + r]);
  }
  return text + ")";
}

std::string Entities::Describe(const Instance& instance) const {
  return step::Describe(file_, instance);
}

}  // namespace rdmesh::step
