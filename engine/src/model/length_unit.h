#pragma once
// A STEP or IGES length unit's name ("MILLIMETRE", "INCH", "MM", ...) as the model reports it.
// Header-only: rdmesh's own STEP translator and OCCT's readers (a module of its own) share it.

#include <cctype>
#include <string>
#include <utility>

namespace rdmesh {

/// The short name ("mm", "inch", ...) and millimetres per unit of a unit name, its letters
/// compared in upper case; an unknown name is given back in lower case, at 1 mm.
inline std::pair<std::string, double> LengthUnitOf(const std::string& raw) {
  std::string key;
  for (char c : raw)
    if (std::isalpha(static_cast<unsigned char>(c)))
      key += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  static const struct {
    const char* key;
    const char* name;
    double mm;
  } kUnits[] = {
      {"MILLIMETRE", "mm", 1.0},  {"MILLIMETER", "mm", 1.0},  {"MM", "mm", 1.0},
      {"CENTIMETRE", "cm", 10.0}, {"CENTIMETER", "cm", 10.0}, {"CM", "cm", 10.0},
      {"METRE", "m", 1000.0},     {"METER", "m", 1000.0},     {"M", "m", 1000.0},
      {"KILOMETRE", "km", 1e6},   {"KILOMETER", "km", 1e6},   {"KM", "km", 1e6},
      {"MICROMETRE", "um", 1e-3}, {"MICROMETER", "um", 1e-3}, {"MICRON", "um", 1e-3},
      {"INCH", "inch", 25.4},     {"IN", "inch", 25.4},       {"FOOT", "foot", 304.8},
      {"FT", "foot", 304.8},      {"MIL", "mil", 0.0254},     {"MILE", "mile", 1609344.0},
  };
  for (const auto& unit : kUnits)
    if (key == unit.key) return {unit.name, unit.mm};
  std::string lower = raw;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return {lower, 1.0};
}

}  // namespace rdmesh
