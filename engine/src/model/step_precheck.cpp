#include "model/step_precheck.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

namespace rdmesh {

namespace {

// The position after a run of characters that satisfy `pred`, from `i`.
template <typename Pred>
size_t Skip(std::string_view text, size_t i, Pred pred) {
  while (i < text.size() && pred(static_cast<unsigned char>(text[i]))) ++i;
  return i;
}

bool IsSpace(unsigned char c) { return std::isspace(c) != 0; }
bool IsDigit(unsigned char c) { return std::isdigit(c) != 0; }
bool IsKeyword(unsigned char c) { return std::isalnum(c) != 0 || c == '_'; }

// Decimal digits as a number; -1 when there are none or too many to be an entity id.
long EntityId(std::string_view digits) {
  if (digits.empty() || digits.size() > 18) return -1;
  long id = 0;
  for (char c : digits) id = id * 10 + (c - '0');
  return id;
}

// "#123" (blanks around allowed) as 123, or -1.
long Reference(std::string_view text) {
  size_t begin = Skip(text, 0, IsSpace);
  if (begin >= text.size() || text[begin] != '#') return -1;
  size_t end = Skip(text, begin + 1, IsDigit);
  if (Skip(text, end, IsSpace) != text.size()) return -1;
  return EntityId(text.substr(begin + 1, end - begin - 1));
}

// The first ORIENTED_EDGE that leads back to itself through edge_element links, or -1.
long FirstCycle(const std::unordered_map<long, long>& edge_element) {
  enum Mark { kOnPath = 1, kDone = 2 };
  std::unordered_map<long, int> marks;
  for (const auto& [start, unused] : edge_element) {
    long id = start;
    for (;;) {
      auto link = edge_element.find(id);
      if (link == edge_element.end()) break;  // not an ORIENTED_EDGE: the chain ends
      int& mark = marks[id];
      if (mark == kDone) break;
      if (mark == kOnPath) return id;
      mark = kOnPath;
      id = link->second;
    }
    for (id = start; marks[id] == kOnPath; id = edge_element.at(id)) marks[id] = kDone;
  }
  return -1;
}

// One pass of StepCrashReason; `strings` says whether quoted text is skipped.
std::string Scan(std::string_view text, bool strings) {
  // edge_element of each ORIENTED_EDGE('name', *, *, #edge, .T.), by entity id.
  std::unordered_map<long, long> edge_element;
  std::unordered_set<long> defined;  // every "#id =" instance name
  long oriented_edge = -1;           // the ORIENTED_EDGE whose arguments are being read
  bool in_point = false;             // reading the arguments of a CARTESIAN_POINT
  int argument = 0;
  size_t argument_start = 0;
  int depth = 0;
  size_t comment_end = 0;  // read as code, the text before this position is a comment
  for (size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (!strings && c == '/' && i >= comment_end && i + 1 < text.size() && text[i + 1] == '*') {
      comment_end = text.find("*/", i + 2);  // read on as code, but remember where it ends
      if (comment_end == std::string_view::npos) comment_end = text.size();
    }
    if (strings && c == '\'') {  // a string: '' inside it reads as two strings, which is fine here
      i = text.find('\'', i + 1);
      if (i == std::string_view::npos) break;
    } else if (strings && c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      i = text.find("*/", i + 2);
      if (i == std::string_view::npos) break;
      ++i;
    } else if (in_point && (c == 'E' || c == 'e') && depth > 0 && i > 0 &&
               (IsDigit(text[i - 1]) || text[i - 1] == '.')) {  // the exponent of a real
      size_t start = i;
      while (start > 0 && (IsDigit(text[start - 1]) || text[start - 1] == '.' ||
                           text[start - 1] == '-' || text[start - 1] == '+'))
        --start;
      size_t digits =
          i + 1 < text.size() && (text[i + 1] == '+' || text[i + 1] == '-') ? i + 2 : i + 1;
      size_t end = Skip(text, digits, IsDigit);
      if (end - digits >= 3) {  // only a three-digit exponent can overflow
        std::string number(text.substr(start, end - start));
        if (std::isinf(std::strtod(number.c_str(), nullptr)))
          return "a CARTESIAN_POINT coordinate (" + number + ") is beyond the range of a double";
      }
      i = end - 1;
    } else if (c == '(') {
      if (++depth > kMaxStepNesting && strings)  // names may hold any parentheses
        return "parentheses nested more than " + std::to_string(kMaxStepNesting) + " deep";
      if (depth == 1) {
        argument = 0;
        argument_start = i + 1;
      }
    } else if (c == ',' || c == ')') {
      if (depth == 1 && oriented_edge >= 0 && argument == 3) {
        long target = Reference(text.substr(argument_start, i - argument_start));
        if (target >= 0) edge_element[oriented_edge] = target;
      }
      if (c == ',' && depth == 1) {
        ++argument;
        argument_start = i + 1;
      }
      if (c == ')' && depth > 0 && --depth == 0) {
        oriented_edge = -1;
        in_point = false;
      }
    } else if (c == ';') {
      depth = 0;
      oriented_edge = -1;
      in_point = false;
    } else if (c == '#' && depth == 0) {  // "#id = KEYWORD (" starts an entity instance
      size_t digits_end = Skip(text, i + 1, IsDigit);
      size_t equals = Skip(text, digits_end, IsSpace);
      if (digits_end == i + 1 || equals >= text.size() || text[equals] != '=') continue;
      const long id = EntityId(text.substr(i + 1, digits_end - i - 1));
      size_t keyword = Skip(text, equals + 1, IsSpace);
      size_t keyword_end = Skip(
          text, keyword < text.size() && text[keyword] == '!' ? keyword + 1 : keyword, IsKeyword);
      std::string_view name = text.substr(keyword, keyword_end - keyword);
      // OCCT's parser drops a record that is not "KEYWORD (" or a complex "(": its id stays
      // undefined, and a reference to it lands elsewhere (seen as "#210 = EDG,_CURVE(...)").
      const size_t open = Skip(text, keyword_end, IsSpace);
      const bool record = open < text.size() && text[open] == '(';
      // A broken string can hide a definition from the first pass, so both passes count
      // duplicates; read as code, the text of a comment is no definition.
      if (record && i >= comment_end && !defined.insert(id).second) {
        return "entity #" + std::to_string(id) + " is defined more than once";
      }
      if (name == "ORIENTED_EDGE") oriented_edge = EntityId(text.substr(i + 1, digits_end - i - 1));
      in_point = name == "CARTESIAN_POINT";
      i = keyword_end - 1;
    }
  }
  long cycle = FirstCycle(edge_element);
  if (cycle >= 0) {
    return "ORIENTED_EDGE #" + std::to_string(cycle) +
           " is its own edge_element, directly or through other ORIENTED_EDGEs";
  }
  // The first (lowest) ORIENTED_EDGE whose edge_element is not defined, for a stable message.
  long dangling = -1;
  for (const auto& [id, target] : edge_element) {
    if (defined.count(target) == 0 && (dangling < 0 || id < dangling)) dangling = id;
  }
  if (dangling < 0) return "";
  return "ORIENTED_EDGE #" + std::to_string(dangling) + " names #" +
         std::to_string(edge_element.at(dangling)) +
         " as its edge_element, and the file does not define it";
}

}  // namespace

// Quoted text is skipped in a first pass and read as code in a second: in a file with a broken
// string, OCCT's parser and the first pass may disagree on where strings end.
std::string StepCrashReason(const std::string& bytes) {
  for (bool strings : {true, false}) {
    std::string reason = Scan(bytes, strings);
    if (!reason.empty()) return reason;
  }
  return "";
}

}  // namespace rdmesh
