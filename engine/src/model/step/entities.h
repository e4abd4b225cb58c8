#pragma once
// Checked, typed access to the entity instances of a parsed STEP file (part21.h), for the
// translator (translate.h). Every accessor validates what it reads: a missing instance throws
// Broken, a parameter of the wrong kind or an entity of another type throws Unsupported (OCCT's
// reader takes such files its own way), so the translator's code reads like the schema.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "model/step/part21.h"

namespace rdmesh::step {

/// The file holds something the translator does not reproduce; OCCT's reader takes it.
struct Unsupported {
  std::string what;
};

/// The file is broken where OCCT's reader refuses it too; becomes a kParseError.
struct Broken {
  std::string what;
};

[[noreturn]] void ThrowUnsupported(std::string what);
[[noreturn]] void ThrowBroken(std::string what);

/// "#12 TYPE", the way messages name an instance.
std::string Describe(const File& file, const Instance& instance);

/// One record of one instance: its parameters, read with checks. Cheap to copy.
class Entity {
 public:
  Entity(const File* file, const Instance* instance, const Record* record)
      : file_(file), instance_(instance), record_(record) {}

  uint64_t id() const { return instance_->id; }
  const Instance& instance() const { return *instance_; }
  std::string_view type() const { return file_->TypeName(*record_); }
  const File& file() const { return *file_; }
  uint32_t size() const { return record_->param_count; }
  std::string Name() const;  ///< "#12 TYPE"

  /// Parameter `i`; Unsupported when the record has fewer.
  const Param& At(uint32_t i) const;
  bool IsUnset(uint32_t i) const;
  double Real(uint32_t i) const;     ///< a real or an integer
  double Measure(uint32_t i) const;  ///< a real, or a typed measure holding one
  int64_t Integer(uint32_t i) const;
  bool Logical(uint32_t i) const;           ///< .T. or .F.
  std::string_view Enum(uint32_t i) const;  ///< the text between the dots
  uint64_t Ref(uint32_t i) const;
  const Param& List(uint32_t i) const;
  std::string String(uint32_t i) const;  ///< decoded (DecodeString); "" when unset

  // Items of a list param (as returned by List or Item).
  uint32_t Count(const Param& list) const { return list.count; }
  const Param& Item(const Param& list, uint32_t i) const;
  double RealItem(const Param& list, uint32_t i) const;
  int64_t IntegerItem(const Param& list, uint32_t i) const;
  uint64_t RefItem(const Param& list, uint32_t i) const;
  const Param& ListItem(const Param& list, uint32_t i) const;

  [[noreturn]] void Fail(uint32_t i, const char* expected) const;

 private:
  const File* file_;
  const Instance* instance_;
  const Record* record_;
};

/// Lookup of instances by id, with messages that name the referring instance.
class Entities {
 public:
  explicit Entities(const File& file) : file_(file) {}
  const File& file() const { return file_; }

  /// The instance `id`, referred to from `from` (0: none); Broken when it is not in the file.
  const Instance& Get(uint64_t id, uint64_t from) const;
  /// The simple type of an instance, or "" for a complex one.
  std::string_view SimpleType(const Instance& instance) const;
  bool IsComplex(const Instance& instance) const { return instance.record_count > 1; }
  /// Whether a complex instance has a record of `type` (exact, upper case).
  bool HasPart(const Instance& instance, std::string_view type) const;
  /// Whether `instance` is of simple type `type` or a complex one with that part.
  bool Is(const Instance& instance, std::string_view type) const;
  /// The whole instance as an Entity of its only record (a simple instance).
  Entity Simple(const Instance& instance) const;
  /// The record `type` of a complex instance; Unsupported when absent.
  Entity Part(const Instance& instance, std::string_view type) const;
  /// The types of a complex instance's records, as "(A B C)", for messages.
  std::string TypeList(const Instance& instance) const;
  std::string Describe(const Instance& instance) const;

 private:
  const File& file_;
};

}  // namespace rdmesh::step
