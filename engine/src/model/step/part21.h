#pragma once
// A STEP Part 21 (ISO 10303-21) exchange file parsed into flat arrays: the header's schema and the
// DATA section's entity instances with their parameters. Text only: it knows no schema and builds
// no geometry (translate.h does). Untrusted input: every malformed file gives kParseError with a
// line number, never a crash.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh::step {

/// The kind of one parameter value.
enum class ParamKind : uint8_t {
  kUnset,    ///< $
  kDerived,  ///< *
  kInteger,  ///< 12, -3
  kReal,     ///< 1.5, -0., 1.E-07, .5 (a 'D' exponent, 1.5D3, is a kParseError)
  kString,   ///< 'text' (the raw bytes between the quotes; DecodeString undoes the escapes)
  kEnum,     ///< .T., .UNSPECIFIED. (the text between the dots, as written)
  kBinary,   ///< "0A1"
  kRef,      ///< #12
  kList,     ///< (a, b, ...)
  kTyped,    ///< LENGTH_MEASURE(1.) : a type name and one inner value
};

/// Lists nested deeper than this (counting a typed value's parentheses) are a kParseError: real
/// files nest a few levels, and the bound keeps the parser's recursion small.
constexpr int kMaxNesting = 64;

/// One parameter. Plain data, 24 bytes, stored in File::params: a list's items (and a typed
/// value's inner value) are contiguous at params[first .. first + count), as are a record's
/// parameters; nested items are stored before the list that holds them.
struct Param {
  ParamKind kind = ParamKind::kUnset;
  /// kList: number of items; kTyped: 1; kString, kEnum, kBinary: length in bytes of the text.
  uint32_t count = 0;
  /// kList, kTyped: index of the first child in File::params. kString, kEnum, kBinary: offset of
  /// the text in File::text. kTyped: also the type name, see File::TypedName.
  uint32_t first = 0;
  /// kTyped: offset of the type name in File::text; its length is in name_length.
  uint32_t name_offset = 0;
  union {
    int64_t integer;  ///< kInteger
    double real;      ///< kReal
    uint64_t ref;     ///< kRef: the entity instance name (#ref)
    uint64_t name_length;
  } value{0};
};

/// One simple record of an instance: TYPE(params...). A complex instance, #5=(A(..)B(..)C(..)),
/// has one record per part, in file order, which is alphabetical by the standard.
struct Record {
  uint32_t type_offset = 0;  ///< the type name in File::text (as written, normally upper case)
  uint32_t type_length = 0;
  uint32_t first_param = 0;  ///< the record's top-level parameters: params[first .. first+count)
  uint32_t param_count = 0;
};

/// One entity instance, #id = ...;
struct Instance {
  uint64_t id = 0;
  uint32_t first_record = 0;  ///< records[first_record .. first_record + record_count)
  uint32_t record_count = 0;  ///< 1 for a simple instance, > 1 for a complex one
  uint32_t line = 0;          ///< 1-based line of '#id' in the file, for messages
};

/// A parsed file. Owns a copy of the bytes it points into (`text`).
class File {
 public:
  std::string text;  ///< the file's bytes
  /// FILE_SCHEMA names, decoded and cut before any object identifier: "AUTOMOTIVE_DESIGN" for
  /// 'AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'.
  std::vector<std::string> schemas;
  std::vector<Instance> instances;  ///< in ascending id order (sorted after the parse)
  std::vector<Record> records;
  std::vector<Param> params;

  /// The instance with `id`, or null. O(1) for dense ids, O(log n) otherwise.
  const Instance* Find(uint64_t id) const;
  std::string_view TypeName(const Record& record) const;
  /// The record of a simple instance (its only record, whatever `type` says); for a complex one,
  /// the part named `type`, compared case-insensitively (null when absent). With empty `type`,
  /// the first record.
  const Record* RecordOf(const Instance& instance, std::string_view type = {}) const;
  /// Parameter `i` of `record`, or null when it has fewer.
  const Param* Arg(const Record& record, uint32_t i) const;
  /// Item `i` of a kList param (or the inner value of a kTyped one), or null.
  const Param* Item(const Param& list, uint32_t i) const;
  /// The text of a kString (raw, escapes kept), kEnum or kBinary param.
  std::string_view Text(const Param& param) const;
  /// The type name of a kTyped param.
  std::string_view TypedName(const Param& param) const;

  /// For the index: id -> position in `instances`; built by Parse.
  std::vector<uint32_t> dense_index;  ///< when ids are dense enough: id -> index + 1 (0 = none)
};

/// A kString's text with Part 21's escapes decoded to UTF-8: '' -> ', \\ -> \, \S\c, \X\hh,
/// \X2\hhhh...\X0\, \X4\hhhhhhhh...\X0\, and \P?\ directives dropped. Line breaks (not part of a
/// string by the standard) are dropped; an invalid escape is kept as written; other bytes,
/// UTF-8 included, pass through. Never fails.
std::string DecodeString(std::string_view raw);

/// Parses the whole file `bytes`. kParseError "line N: reason" for text that is not Part 21 (a
/// missing ISO-10303-21 header, an unterminated string or list, a duplicate instance id, lists
/// nested deeper than kMaxNesting, a missing END-ISO-10303-21). A reference to an id that no
/// instance has is not an error (Find returns null). kResourceExhausted above 4 GiB. Polls
/// `context` about once per MB and returns its StopStatus().
Result<File> Parse(std::string bytes, const Context* context = nullptr);

}  // namespace rdmesh::step
