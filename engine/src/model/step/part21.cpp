#include "model/step/part21.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <limits>
#include <string>
#include <system_error>
#include <utility>

namespace rdmesh::step {
namespace {

// Character classes, one table lookup per byte in the hot loops.
enum : uint8_t {
  kSpaceClass = 1,  // bytes 1..32: blanks and line breaks between tokens
  kDigitClass = 2,
  kNameStart = 4,  // letters, '_', '!' (a user-defined keyword)
  kNameChar = 8,   // letters, digits, '_'
  kHexClass = 16,
};

struct CharTable {
  uint8_t c[256] = {};
  constexpr CharTable() {
    for (int i = 1; i <= 32; ++i) c[i] |= kSpaceClass;
    for (int i = '0'; i <= '9'; ++i) c[i] |= kDigitClass | kNameChar | kHexClass;
    for (int i = 'A'; i <= 'Z'; ++i) c[i] |= kNameStart | kNameChar;
    for (int i = 'a'; i <= 'z'; ++i) c[i] |= kNameStart | kNameChar;
    for (int i = 'A'; i <= 'F'; ++i) c[i] |= kHexClass;
    for (int i = 'a'; i <= 'f'; ++i) c[i] |= kHexClass;
    c[static_cast<unsigned char>('_')] |= kNameStart | kNameChar;
    c[static_cast<unsigned char>('!')] |= kNameStart;
  }
};
constexpr CharTable kChars;

inline bool Is(char c, uint8_t cls) { return (kChars.c[static_cast<unsigned char>(c)] & cls) != 0; }

inline char Upper(char c) { return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 32) : c; }

bool EqualsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (Upper(a[i]) != Upper(b[i])) return false;
  }
  return true;
}

// Byte budget between two polls of the context.
constexpr size_t kPollBytes = size_t{1} << 20;

class Parser {
 public:
  Parser(File& file, const Context* context)
      : f_(file),
        context_(context),
        begin_(file.text.data()),
        p_(begin_),
        end_(begin_ + file.text.size()),
        line_pos_(begin_),
        poll_pos_(begin_) {}

  Status Run();

 private:
  // Skips blanks, line breaks and comments. An unterminated comment moves to the end and is
  // remembered, so that the next token's error names it.
  void Skip() {
    for (;;) {
      if (Is(*p_, kSpaceClass)) {
        ++p_;
      } else if (*p_ == '/' && p_[1] == '*') {
        const char* close = Find2(p_ + 2, '*', '/');
        if (close == nullptr) {
          open_comment_ = p_;
          p_ = end_;
          return;
        }
        p_ = close + 2;
      } else {
        return;
      }
    }
  }

  // The first "ab" at or after `from`, or null.
  const char* Find2(const char* from, char a, char b) const {
    while (from < end_) {
      const void* hit = std::memchr(from, a, static_cast<size_t>(end_ - from));
      if (hit == nullptr) return nullptr;
      const char* q = static_cast<const char*>(hit);
      if (q + 1 < end_ && q[1] == b) return q;
      from = q + 1;
    }
    return nullptr;
  }

  // 1-based line of `pos`; cheap when called with increasing positions.
  uint32_t LineAt(const char* pos) {
    if (pos < line_pos_) {
      line_pos_ = begin_;
      line_ = 1;
    }
    const char* q = line_pos_;
    while (q < pos) {
      const void* hit = std::memchr(q, '\n', static_cast<size_t>(pos - q));
      if (hit == nullptr) break;
      ++line_;
      q = static_cast<const char*>(hit) + 1;
    }
    line_pos_ = pos;
    return line_;
  }

  std::string Found() const {
    if (p_ >= end_) {
      if (open_comment_ != nullptr) return "an unterminated comment";
      return "the end of the file";
    }
    const unsigned char c = static_cast<unsigned char>(*p_);
    if (c > 32 && c < 127) return std::string("'") + static_cast<char>(c) + "'";
    static const char kHex[] = "0123456789ABCDEF";
    return std::string("byte 0x") + kHex[c >> 4] + kHex[c & 15];
  }

  // Records the first error at `at`: "line N: what".
  bool FailAt(const char* at, const std::string& what) {
    if (error_.ok()) {
      const char* where = (open_comment_ != nullptr && at >= end_) ? open_comment_ : at;
      error_ = Status(StatusCode::kParseError,
                      "line " + std::to_string(LineAt(std::min(where, end_))) + ": " + what);
    }
    return false;
  }
  bool Expected(const char* what) {
    return FailAt(p_, std::string("expected ") + what + ", found " + Found());
  }

  bool Expect(char c, const char* what) {
    Skip();
    if (*p_ != c || p_ >= end_) return Expected(what);
    ++p_;
    return true;
  }

  // A keyword (case-insensitive) that must not run on into a longer name.
  bool AtKeyword(std::string_view word) const {
    if (static_cast<size_t>(end_ - p_) < word.size()) return false;
    for (size_t i = 0; i < word.size(); ++i) {
      if (Upper(p_[i]) != word[i]) return false;
    }
    return !Is(p_[word.size()], kNameChar) && p_[word.size()] != '-';
  }

  // Digits of an instance name, after '#'.
  bool ParseId(uint64_t* id) {
    if (!Is(*p_, kDigitClass)) return Expected("digits after '#'");
    uint64_t v = 0;
    while (Is(*p_, kDigitClass)) {
      const uint64_t d = static_cast<uint64_t>(*p_ - '0');
      if (v > (std::numeric_limits<uint64_t>::max() - d) / 10) {
        return FailAt(p_, "instance name too large");
      }
      v = v * 10 + d;
      ++p_;
    }
    *id = v;
    return true;
  }

  bool ParseName(uint32_t* offset, uint32_t* length) {
    if (!Is(*p_, kNameStart)) return Expected("a type name");
    const char* s = p_++;
    while (Is(*p_, kNameChar)) ++p_;
    *offset = static_cast<uint32_t>(s - begin_);
    *length = static_cast<uint32_t>(p_ - s);
    return true;
  }

  bool ParseNumber();
  bool ParseValue(int depth);
  bool ParseItems(int depth, uint32_t* first, uint32_t* count);
  bool ParseRecord();
  bool ParseHeader();
  bool ParseData();
  bool Finish();

  File& f_;
  const Context* context_;
  const char* const begin_;
  const char* p_;
  const char* const end_;
  const char* open_comment_ = nullptr;
  const char* line_pos_;
  uint32_t line_ = 1;
  const char* poll_pos_;
  Status error_;
  // Items of the lists being read, innermost last; a list's items move to File::params when it
  // closes, so that they are contiguous there.
  std::vector<Param> scratch_;
};

bool Parser::ParseNumber() {
  const char* s = p_;
  const char* q = p_;
  bool negative = false;
  if (*q == '+' || *q == '-') {
    negative = *q == '-';
    ++q;
  }
  const char* digits = q;
  uint64_t v = 0;
  bool too_large = false;
  while (Is(*q, kDigitClass)) {
    const uint64_t d = static_cast<uint64_t>(*q - '0');
    if (v > (std::numeric_limits<uint64_t>::max() - d) / 10) too_large = true;
    v = v * 10 + d;
    ++q;
  }
  Param param;
  if (*q == '.' || *q == 'E' || *q == 'e') {
    if (q == digits && !Is(q[1], kDigitClass)) return FailAt(s, "expected digits in a number");
    // from_chars takes no '+'; it reads "1.", ".5", "1.E-07" like strtod, without the locale.
    const char* from = negative ? s : digits;
    double real = 0;
    const std::from_chars_result r = std::from_chars(from, end_, real);
    if (r.ec == std::errc::result_out_of_range) {
      // Too small is zero; too large is no number this reader can hold.
      const char* e = r.ptr - 1;
      while (e > from && *e != 'E' && *e != 'e') --e;
      if (e == from || e[1] != '-') return FailAt(s, "real number out of range");
      real = negative ? -0.0 : 0.0;
    } else if (r.ec != std::errc()) {
      return FailAt(s, "expected a number");
    }
    q = r.ptr;
    if (*q == 'D' || *q == 'd') {
      return FailAt(q, "a 'D' exponent is not Part 21 (reals use 'E', as in 1.5E3)");
    }
    param.kind = ParamKind::kReal;
    param.value.real = real;
  } else {
    if (q == digits) return FailAt(s, "expected digits after the sign");
    const uint64_t limit = static_cast<uint64_t>(std::numeric_limits<int64_t>::max()) + negative;
    if (too_large || v > limit) return FailAt(s, "integer out of range");
    param.kind = ParamKind::kInteger;
    param.value.integer = negative ? static_cast<int64_t>(0 - v) : static_cast<int64_t>(v);
  }
  if (Is(*q, kNameChar) || *q == '.' || *q == '+' || *q == '-') {
    return FailAt(q, "malformed number");
  }
  p_ = q;
  scratch_.push_back(param);
  return true;
}

bool Parser::ParseValue(int depth) {
  Param param;
  switch (*p_) {
    case '$':
      ++p_;
      param.kind = ParamKind::kUnset;
      break;
    case '*':
      ++p_;
      param.kind = ParamKind::kDerived;
      break;
    case '\'': {
      const char* open = p_;
      const char* s = ++p_;
      for (;;) {
        const void* hit = std::memchr(p_, '\'', static_cast<size_t>(end_ - p_));
        if (hit == nullptr) return FailAt(open, "unterminated string");
        const char* q = static_cast<const char*>(hit);
        if (q + 1 < end_ && q[1] == '\'') {
          p_ = q + 2;
          continue;
        }
        param.kind = ParamKind::kString;
        param.first = static_cast<uint32_t>(s - begin_);
        param.count = static_cast<uint32_t>(q - s);
        p_ = q + 1;
        break;
      }
      break;
    }
    case '"': {
      const char* s = ++p_;
      while (Is(*p_, kHexClass)) ++p_;
      if (*p_ != '"' || p_ >= end_) return Expected("hexadecimal digits or '\"' in a binary");
      param.kind = ParamKind::kBinary;
      param.first = static_cast<uint32_t>(s - begin_);
      param.count = static_cast<uint32_t>(p_ - s);
      ++p_;
      break;
    }
    case '#': {
      ++p_;
      uint64_t id = 0;
      if (!ParseId(&id)) return false;
      param.kind = ParamKind::kRef;
      param.value.ref = id;
      break;
    }
    case '.': {
      if (Is(p_[1], kDigitClass)) return ParseNumber();
      const char* s = ++p_;
      while (Is(*p_, kNameChar)) ++p_;
      if (p_ == s || *p_ != '.') return Expected("an enumeration .NAME.");
      param.kind = ParamKind::kEnum;
      param.first = static_cast<uint32_t>(s - begin_);
      param.count = static_cast<uint32_t>(p_ - s);
      ++p_;
      break;
    }
    case '(': {
      ++p_;
      if (depth >= kMaxNesting) {
        return FailAt(p_ - 1, "lists nested deeper than " + std::to_string(kMaxNesting));
      }
      param.kind = ParamKind::kList;
      if (!ParseItems(depth + 1, &param.first, &param.count)) return false;
      break;
    }
    case '+':
    case '-':
    case '0':
    case '1':
    case '2':
    case '3':
    case '4':
    case '5':
    case '6':
    case '7':
    case '8':
    case '9':
      return ParseNumber();
    default: {
      if (!Is(*p_, kNameStart) || p_ >= end_) return Expected("a parameter");
      // A typed value, LENGTH_MEASURE(1.): a name and exactly one parameter in parentheses.
      const char* s = p_;
      uint32_t length = 0;
      if (!ParseName(&param.name_offset, &length)) return false;
      if (!Expect('(', "'(' after the type name of a typed parameter")) return false;
      if (depth >= kMaxNesting) {
        return FailAt(p_ - 1, "lists nested deeper than " + std::to_string(kMaxNesting));
      }
      if (!ParseItems(depth + 1, &param.first, &param.count)) return false;
      if (param.count != 1) return FailAt(s, "a typed parameter holds exactly one value");
      param.kind = ParamKind::kTyped;
      param.value.name_length = length;
      break;
    }
  }
  scratch_.push_back(param);
  return true;
}

// The items of a list after its '(' up to and including its ')'.
bool Parser::ParseItems(int depth, uint32_t* first, uint32_t* count) {
  const size_t base = scratch_.size();
  Skip();
  if (*p_ == ')') {
    ++p_;
    *first = static_cast<uint32_t>(f_.params.size());
    *count = 0;
    return true;
  }
  for (;;) {
    if (!ParseValue(depth)) return false;
    Skip();
    if (*p_ == ',') {
      ++p_;
      Skip();
      continue;
    }
    if (*p_ == ')') {
      ++p_;
      break;
    }
    return Expected("',' or ')' after a parameter");
  }
  *first = static_cast<uint32_t>(f_.params.size());
  *count = static_cast<uint32_t>(scratch_.size() - base);
  f_.params.insert(f_.params.end(), scratch_.begin() + static_cast<std::ptrdiff_t>(base),
                   scratch_.end());
  scratch_.resize(base);
  return true;
}

// NAME(params...)
bool Parser::ParseRecord() {
  Record record;
  if (!ParseName(&record.type_offset, &record.type_length)) return false;
  if (!Expect('(', "'(' after the type name")) return false;
  if (!ParseItems(0, &record.first_param, &record.param_count)) return false;
  f_.records.push_back(record);
  return true;
}

bool Parser::ParseHeader() {
  Skip();
  if (static_cast<size_t>(end_ - p_) >= 3 && std::memcmp(p_, "\xEF\xBB\xBF", 3) == 0) {
    p_ += 3;  // a UTF-8 byte order mark
    Skip();
  }
  if (!AtKeyword("ISO-10303-21")) return Expected("ISO-10303-21; at the start of a STEP file");
  p_ += 12;
  if (!Expect(';', "';' after ISO-10303-21")) return false;
  Skip();
  if (!AtKeyword("HEADER")) return Expected("HEADER;");
  p_ += 6;
  if (!Expect(';', "';' after HEADER")) return false;
  // The header's entities go through the same record reader and are dropped afterwards.
  for (;;) {
    Skip();
    if (AtKeyword("ENDSEC")) {
      p_ += 6;
      break;
    }
    if (AtKeyword("DATA")) return Expected("ENDSEC; to end the header");
    if (!Is(*p_, kNameStart) || p_ >= end_) return Expected("a header entity or ENDSEC");
    const size_t first_record = f_.records.size();
    if (!ParseRecord()) return false;
    if (!Expect(';', "';' after a header entity")) return false;
    const Record& record = f_.records[first_record];
    const Param* names = f_.Arg(record, 0);
    if (EqualsNoCase(f_.TypeName(record), "FILE_SCHEMA") && names != nullptr &&
        names->kind == ParamKind::kList) {
      for (uint32_t i = 0; i < names->count; ++i) {
        const Param* name = f_.Item(*names, i);
        if (name->kind != ParamKind::kString) continue;
        std::string schema = DecodeString(f_.Text(*name));
        const size_t start = schema.find_first_not_of(" \t");
        const size_t stop = schema.find_first_of(" \t{", start == std::string::npos ? 0 : start);
        f_.schemas.push_back(start == std::string::npos ? std::string()
                                                        : schema.substr(start, stop - start));
      }
    }
  }
  if (!Expect(';', "';' after ENDSEC")) return false;
  f_.records.clear();
  f_.params.clear();
  return true;
}

// After DATA: an optional (name, schemas) of edition 3, then instances up to ENDSEC;.
bool Parser::ParseData() {
  Skip();
  if (*p_ == '(') {
    ++p_;
    const size_t kept = f_.params.size();
    uint32_t first = 0;
    uint32_t count = 0;
    if (!ParseItems(0, &first, &count)) return false;
    f_.params.resize(kept);  // the section's name and schemas: not instances
  }
  if (!Expect(';', "';' after DATA")) return false;
  for (;;) {
    Skip();
    if (static_cast<size_t>(p_ - poll_pos_) >= kPollBytes) {
      poll_pos_ = p_;
      if (context_ != nullptr && context_->ShouldStop()) {
        error_ = context_->StopStatus();
        return false;
      }
    }
    if (*p_ != '#') {
      if (AtKeyword("ENDSEC")) {
        p_ += 6;
        return Expect(';', "';' after ENDSEC");
      }
      return Expected("an instance '#N=' or ENDSEC");
    }
    Instance instance;
    instance.line = LineAt(p_);
    ++p_;
    if (!ParseId(&instance.id)) return false;
    if (!Expect('=', "'=' after the instance name")) return false;
    instance.first_record = static_cast<uint32_t>(f_.records.size());
    Skip();
    if (*p_ == '(') {
      // A complex instance: (A(...)B(...)...).
      ++p_;
      for (;;) {
        Skip();
        if (*p_ == ')') {
          ++p_;
          break;
        }
        if (!Is(*p_, kNameStart) || p_ >= end_) return Expected("a type name or ')'");
        if (!ParseRecord()) return false;
      }
      if (f_.records.size() == instance.first_record) {
        return FailAt(p_ - 1, "a complex instance needs at least one record");
      }
    } else {
      if (!Is(*p_, kNameStart) || p_ >= end_) return Expected("a type name or '(' after '='");
      if (!ParseRecord()) return false;
    }
    instance.record_count = static_cast<uint32_t>(f_.records.size()) - instance.first_record;
    if (!Expect(';', "';' after an instance")) return false;
    f_.instances.push_back(instance);
  }
}

// Sorts the instances by id when the file did not, refuses duplicates, builds the index.
bool Parser::Finish() {
  std::vector<Instance>& all = f_.instances;
  bool ascending = true;
  for (size_t i = 1; i < all.size(); ++i) {
    if (all[i - 1].id >= all[i].id) {
      ascending = false;
      break;
    }
  }
  if (!ascending) {
    std::sort(all.begin(), all.end(), [](const Instance& a, const Instance& b) {
      return a.id != b.id ? a.id < b.id : a.line < b.line;
    });
    for (size_t i = 1; i < all.size(); ++i) {
      if (all[i - 1].id == all[i].id) {
        error_ = Status(StatusCode::kParseError, "line " + std::to_string(all[i].line) +
                                                     ": instance #" + std::to_string(all[i].id) +
                                                     " is defined twice (first on line " +
                                                     std::to_string(all[i - 1].line) + ")");
        return false;
      }
    }
  }
  if (!all.empty()) {
    const uint64_t max_id = all.back().id;
    if (max_id <= 4 * static_cast<uint64_t>(all.size()) + 1024) {
      f_.dense_index.assign(static_cast<size_t>(max_id) + 1, 0);
      for (size_t i = 0; i < all.size(); ++i) {
        f_.dense_index[static_cast<size_t>(all[i].id)] = static_cast<uint32_t>(i + 1);
      }
    }
  }
  return true;
}

Status Parser::Run() {
  // Estimates from the corpus's byte counts: an instance per ~60 bytes, a parameter per ~9.
  const size_t bytes = f_.text.size();
  f_.instances.reserve(bytes / 48 + 16);
  f_.records.reserve(bytes / 48 + 16);
  f_.params.reserve(bytes / 8 + 64);
  scratch_.reserve(256);
  if (!ParseHeader()) return error_;
  bool any_data = false;
  for (;;) {
    Skip();
    if (AtKeyword("DATA")) {
      p_ += 4;
      if (!ParseData()) return error_;
      any_data = true;
      continue;
    }
    if (AtKeyword("END-ISO-10303-21")) {
      p_ += 16;
      if (!Expect(';', "';' after END-ISO-10303-21")) return error_;
      break;
    }
    Expected(any_data ? "DATA; or END-ISO-10303-21;" : "DATA;");
    return error_;
  }
  if (!Finish()) return error_;
  return Status::Ok();
}

// Appends code point `cp` as UTF-8 (U+FFFD for surrogates and values beyond U+10FFFF).
void AppendUtf8(uint32_t cp, std::string* out) {
  if ((cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) cp = 0xFFFD;
  if (cp < 0x80) {
    out->push_back(static_cast<char>(cp));
  } else if (cp < 0x800) {
    out->push_back(static_cast<char>(0xC0 | (cp >> 6)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else if (cp < 0x10000) {
    out->push_back(static_cast<char>(0xE0 | (cp >> 12)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else {
    out->push_back(static_cast<char>(0xF0 | (cp >> 18)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  }
}

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// `n` hex digits at raw[i..], or -1.
int64_t HexRun(std::string_view raw, size_t i, int n) {
  if (i + static_cast<size_t>(n) > raw.size()) return -1;
  int64_t v = 0;
  for (int k = 0; k < n; ++k) {
    const int h = HexValue(raw[i + static_cast<size_t>(k)]);
    if (h < 0) return -1;
    v = v * 16 + h;
  }
  return v;
}

bool StartsWith(std::string_view raw, size_t i, std::string_view what) {
  return raw.size() >= i && raw.substr(i, what.size()) == what;
}

// \X2\ (4 hex digits a unit, UTF-16) or \X4\ (8, UTF-32) from raw[i] (after the directive) up
// to \X0\. Returns the index after \X0\, or 0 when the run is malformed.
size_t DecodeHexRun(std::string_view raw, size_t i, int width, std::string* out) {
  std::string decoded;
  uint32_t high = 0;  // a pending UTF-16 high surrogate
  for (;;) {
    if (StartsWith(raw, i, "\\X0\\")) {
      if (high != 0) AppendUtf8(0xFFFD, &decoded);
      out->append(decoded);
      return i + 4;
    }
    const int64_t unit = HexRun(raw, i, width);
    if (unit < 0) return 0;
    i += static_cast<size_t>(width);
    const uint32_t u = static_cast<uint32_t>(unit);
    if (width == 4 && u >= 0xD800 && u <= 0xDBFF) {
      if (high != 0) AppendUtf8(0xFFFD, &decoded);
      high = u;
      continue;
    }
    if (width == 4 && u >= 0xDC00 && u <= 0xDFFF && high != 0) {
      AppendUtf8(0x10000 + ((high - 0xD800) << 10) + (u - 0xDC00), &decoded);
      high = 0;
      continue;
    }
    if (high != 0) AppendUtf8(0xFFFD, &decoded);
    high = 0;
    AppendUtf8(u, &decoded);
  }
}

}  // namespace

const Instance* File::Find(uint64_t id) const {
  if (!dense_index.empty()) {
    if (id >= dense_index.size()) return nullptr;
    const uint32_t slot = dense_index[static_cast<size_t>(id)];
    return slot == 0 ? nullptr : &instances[slot - 1];
  }
  auto it = std::lower_bound(instances.begin(), instances.end(), id,
                             [](const Instance& a, uint64_t key) { return a.id < key; });
  return (it != instances.end() && it->id == id) ? &*it : nullptr;
}

std::string_view File::TypeName(const Record& record) const {
  return std::string_view(text).substr(record.type_offset, record.type_length);
}

const Record* File::RecordOf(const Instance& instance, std::string_view type) const {
  if (instance.record_count == 0) return nullptr;
  const Record* first = &records[instance.first_record];
  if (instance.record_count == 1 || type.empty()) return first;
  for (uint32_t i = 0; i < instance.record_count; ++i) {
    if (EqualsNoCase(TypeName(first[i]), type)) return &first[i];
  }
  return nullptr;
}

const Param* File::Arg(const Record& record, uint32_t i) const {
  return i < record.param_count ? &params[record.first_param + i] : nullptr;
}

const Param* File::Item(const Param& list, uint32_t i) const {
  if (list.kind != ParamKind::kList && list.kind != ParamKind::kTyped) return nullptr;
  return i < list.count ? &params[list.first + i] : nullptr;
}

std::string_view File::Text(const Param& param) const {
  if (param.kind != ParamKind::kString && param.kind != ParamKind::kEnum &&
      param.kind != ParamKind::kBinary) {
    return {};
  }
  return std::string_view(text).substr(param.first, param.count);
}

std::string_view File::TypedName(const Param& param) const {
  if (param.kind != ParamKind::kTyped) return {};
  return std::string_view(text).substr(param.name_offset,
                                       static_cast<size_t>(param.value.name_length));
}

std::string DecodeString(std::string_view raw) {
  std::string out;
  out.reserve(raw.size());
  size_t i = 0;
  while (i < raw.size()) {
    const char c = raw[i];
    if (c == '\'') {
      out.push_back('\'');
      i += (i + 1 < raw.size() && raw[i + 1] == '\'') ? 2 : 1;
      continue;
    }
    if (c == '\r' || c == '\n') {
      ++i;
      continue;
    }
    if (c != '\\') {
      out.push_back(c);
      ++i;
      continue;
    }
    if (StartsWith(raw, i, "\\\\")) {
      out.push_back('\\');
      i += 2;
      continue;
    }
    if (StartsWith(raw, i, "\\S\\") && i + 3 < raw.size() && raw[i + 3] >= ' ' &&
        raw[i + 3] <= '~') {
      AppendUtf8(static_cast<unsigned char>(raw[i + 3]) + 128u, &out);
      // A quote after \S\ is written doubled.
      i += (raw[i + 3] == '\'' && i + 4 < raw.size() && raw[i + 4] == '\'') ? 5 : 4;
      continue;
    }
    if (StartsWith(raw, i, "\\P") && i + 3 < raw.size() && raw[i + 2] >= 'A' && raw[i + 2] <= 'I' &&
        raw[i + 3] == '\\') {
      i += 4;
      continue;
    }
    if (StartsWith(raw, i, "\\X\\")) {
      const int64_t v = HexRun(raw, i + 3, 2);
      if (v >= 0) {
        AppendUtf8(static_cast<uint32_t>(v), &out);
        i += 5;
        continue;
      }
    }
    if (StartsWith(raw, i, "\\X2\\") || StartsWith(raw, i, "\\X4\\")) {
      const size_t next = DecodeHexRun(raw, i + 4, raw[i + 2] == '2' ? 4 : 8, &out);
      if (next != 0) {
        i = next;
        continue;
      }
    }
    out.push_back('\\');  // an escape this decoder does not know stays as written
    ++i;
  }
  return out;
}

Result<File> Parse(std::string bytes, const Context* context) {
  if (bytes.size() >= std::numeric_limits<uint32_t>::max()) {
    return Status(StatusCode::kResourceExhausted, "a STEP file of 4 GiB or more");
  }
  File file;
  file.text = std::move(bytes);
  Parser parser(file, context);
  Status status = parser.Run();
  if (!status.ok()) return status;
  return file;
}

}  // namespace rdmesh::step
