// The translator's driver: the product structure and representation walk of OCCT 7.6's
// STEPControl_ActorRead (which items become shapes, in which unit context, placed where), the
// B-rep items built and healed (topology.h), and the XCAF document of STEPCAFControl_Reader
// (shapes, assembly structure, names, colours).
// OCC_CATCH_SIGNALS below must turn faults inside OCCT's modelling classes into exceptions, in
// TBB's worker threads too, when the caller has OCCT's fault handlers installed (model_readers'
// ScopedOcctFaultHandlers); it has to be defined before any OCCT header.
#define OCC_CONVERT_SIGNALS 1

#include "model/step/translate.h"

#include <BRepLib.hxx>
#include <BRep_Builder.hxx>
#include <Precision.hxx>
#include <Quantity_Color.hxx>
#include <Quantity_ColorRGBA.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <Standard_OutOfMemory.hxx>
#include <TCollection_ExtendedString.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_MapOfShape.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Iterator.hxx>
#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <gp_Ax3.hxx>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "core/parallel.h"
#include "model/length_unit.h"
#include "model/step/document_plan.h"
#include "model/step/entities.h"
#include "model/step/finish.h"
#include "model/step/geometry.h"
#include "model/step/heal_items.h"
#include "model/step/topology.h"
#include "model/xcaf_api.h"

namespace rdmesh::step {

namespace {

// read.precision.val, read.maxprecision.val and read.encoderegularity.angle: OCCT's defaults.
constexpr double kDefaultPrecision = 1e-3;
constexpr double kMaxPrecision = 1.0;
constexpr double kRegularityAngle = 0.01;

// The entity kinds the product walk looks up by type.
enum class Kind : uint8_t {
  kOther,
  kProductDefinition,  // PRODUCT_DEFINITION and PRODUCT_DEFINITION_WITH_ASSOCIATED_DOCUMENTS
  kProductDefinitionShape,
  kShapeDefinitionRepresentation,
  kNauo,
  kCdsr,
  kSrr,      // SHAPE_REPRESENTATION_RELATIONSHIP, exactly
  kSrrWt,    // the complex one with a transformation
  kOtherRr,  // other representation relationships
  kShapeAspect,
  kPropertyDefinition,
  kShapeRepresentation,
  kStyledItem,
  kOverridingStyledItem,
  kStyleContainer,  // MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION, DRAUGHTING_MODEL
  kInvisibility,
  kLayerAssignment,  // PRESENTATION_LAYER_ASSIGNMENT
  kItemDefinedTransformation,
  kExternal,  // document references: OCCT would look for other files
};

const std::unordered_map<std::string_view, Kind>& SimpleKinds() {
  static const std::unordered_map<std::string_view, Kind> kinds = {
      {"PRODUCT_DEFINITION", Kind::kProductDefinition},
      {"PRODUCT_DEFINITION_WITH_ASSOCIATED_DOCUMENTS", Kind::kProductDefinition},
      {"PRODUCT_DEFINITION_SHAPE", Kind::kProductDefinitionShape},
      {"SHAPE_DEFINITION_REPRESENTATION", Kind::kShapeDefinitionRepresentation},
      {"NEXT_ASSEMBLY_USAGE_OCCURRENCE", Kind::kNauo},
      {"CONTEXT_DEPENDENT_SHAPE_REPRESENTATION", Kind::kCdsr},
      {"SHAPE_REPRESENTATION_RELATIONSHIP", Kind::kSrr},
      {"REPRESENTATION_RELATIONSHIP", Kind::kOtherRr},
      {"CONSTRUCTIVE_GEOMETRY_REPRESENTATION_RELATIONSHIP", Kind::kOtherRr},
      {"DEFINITIONAL_REPRESENTATION_RELATIONSHIP", Kind::kOtherRr},
      {"SHAPE_ASPECT", Kind::kShapeAspect},
      {"DATUM_FEATURE", Kind::kShapeAspect},
      {"DATUM", Kind::kShapeAspect},
      {"COMPOSITE_SHAPE_ASPECT", Kind::kShapeAspect},
      {"DERIVED_SHAPE_ASPECT", Kind::kShapeAspect},
      {"PROPERTY_DEFINITION", Kind::kPropertyDefinition},
      {"SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"ADVANCED_BREP_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"MANIFOLD_SURFACE_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"FACETED_BREP_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"GEOMETRICALLY_BOUNDED_WIREFRAME_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"EDGE_BASED_WIREFRAME_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"NON_MANIFOLD_SURFACE_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"CSG_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"TESSELLATED_SHAPE_REPRESENTATION", Kind::kShapeRepresentation},
      {"SHAPE_DIMENSION_REPRESENTATION", Kind::kShapeRepresentation},
      {"STYLED_ITEM", Kind::kStyledItem},
      {"OVER_RIDING_STYLED_ITEM", Kind::kOverridingStyledItem},
      {"MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION", Kind::kStyleContainer},
      {"DRAUGHTING_MODEL", Kind::kStyleContainer},
      {"INVISIBILITY", Kind::kInvisibility},
      {"PRESENTATION_LAYER_ASSIGNMENT", Kind::kLayerAssignment},
      {"ITEM_DEFINED_TRANSFORMATION", Kind::kItemDefinedTransformation},
      {"DOCUMENT_FILE", Kind::kExternal},
      {"APPLIED_DOCUMENT_REFERENCE", Kind::kExternal},
      {"DOCUMENT_PRODUCT_EQUIVALENCE", Kind::kExternal},
      {"EXTERNALLY_DEFINED_ITEM", Kind::kExternal},
  };
  return kinds;
}

// The types whose references the walk follows backwards (Interface_Graph::Sharings).
bool IndexesSharings(Kind kind) {
  switch (kind) {
    case Kind::kProductDefinitionShape:
    case Kind::kShapeDefinitionRepresentation:
    case Kind::kNauo:
    case Kind::kCdsr:
    case Kind::kSrr:
    case Kind::kSrrWt:
    case Kind::kOtherRr:
    case Kind::kShapeAspect:
    case Kind::kPropertyDefinition:
    case Kind::kItemDefinedTransformation:
      return true;
    default:
      return false;
  }
}

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void ApplyTransformation(TopoDS_Shape* shape, const gp_Trsf& trsf) {
  if (trsf.Form() == gp_Identity) return;
  shape->Move(TopLoc_Location(trsf));
}

// The engine cannot go on (its document framework cannot be loaded): the status, as is.
struct Failed {
  Status status;
};

class Translator {
 public:
  Translator(const File& file, const TranslateOptions& options, const Context* context)
      : file_(file), options_(options), context_(context), entities_(file), geometry_(entities_) {}

  Translated Run();

 private:
  // --- Index
  void Index();
  Kind KindOf(uint64_t id) const;
  const std::vector<uint64_t>& Sharings(uint64_t id) const;
  std::vector<uint64_t> Roots() const;

  // --- Units (STEPControl_ActorRead::PrepareUnits)
  const UnitFactors& UnitsOf(uint64_t representation);
  std::string LengthUnitName();

  // --- The walk (STEPControl_ActorRead)
  TopoDS_Shape TransferProduct(uint64_t pd, bool use_trsf);
  TopoDS_Shape TransferNauo(uint64_t nauo);
  TopoDS_Shape TransferShapeRep(uint64_t sr, bool* is_bound, bool use_trsf);
  TopoDS_Shape TransferSrr(uint64_t srr, int nbrep, bool use_trsf);
  TopoDS_Shape TransferItem(uint64_t item, uint64_t representation);
  TopoDS_Shape TransferMappedItem(uint64_t mapped, uint64_t representation);
  bool ComputeSrrTransformation(uint64_t rr, gp_Trsf* trsf);
  void ComputeTransformation(uint64_t origin, uint64_t target, uint64_t origin_rep,
                             uint64_t target_rep, gp_Trsf* trsf);
  bool SrrReversesNauo(uint64_t cdsr);
  uint64_t ProductOfRepresentation(uint64_t rep);
  bool IsBound(uint64_t id) const { return results_.count(id) != 0; }
  TopoDS_Shape Bound(uint64_t id) const {
    auto found = results_.find(id);
    return found == results_.end() ? TopoDS_Shape() : found->second;
  }
  void Bind(uint64_t id, const TopoDS_Shape& shape) {
    if (!shape.IsNull()) results_[id] = shape;
  }

  // --- Items
  void BuildItems(std::vector<std::pair<std::string, double>>* stage_seconds);

  // --- Document (STEPCAFControl_Reader::Transfer, up to the document: document_plan.h)
  void PlanDocument(const std::vector<TopoDS_Shape>& root_shapes, DocumentPlan* plan);
  void PlanColors(DocumentPlan* plan);
  void PlanNames(DocumentPlan* plan);
  void PlanLayers(DocumentPlan* plan);
  bool DecodeColour(uint64_t colour, uint64_t from, Quantity_Color* color);

  void CheckStop() const {
    if (context_ != nullptr && context_->ShouldStop()) throw Stopped{};
  }
  struct Stopped {};

  const File& file_;
  const TranslateOptions& options_;
  const Context* context_;
  Entities entities_;
  Geometry geometry_;

  std::vector<uint32_t> order_;  // instance indices in file order
  std::vector<Kind> kinds_;      // per instance index
  std::unordered_map<uint64_t, std::vector<uint64_t>> sharings_;
  std::unordered_map<uint64_t, UnitFactors> units_;  // per representation

  // The walk runs twice: first to find the B-rep items and their units (planning), then with
  // the built items in place.
  bool planning_ = true;
  std::vector<std::unique_ptr<BrepItem>> items_;
  std::unordered_map<uint64_t, BrepItem*> item_by_id_;
  std::unordered_map<uint64_t, TopoDS_Shape> results_;  // the transfer process's bindings

  HealStats heal_stats_;
};

// ---------------------------------------------------------------------------------------------
// Index

void Translator::Index() {
  const size_t n = file_.instances.size();
  order_.resize(n);
  for (size_t i = 0; i < n; ++i) order_[i] = static_cast<uint32_t>(i);
  std::stable_sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) {
    return file_.instances[a].line < file_.instances[b].line;
  });
  kinds_.assign(n, Kind::kOther);
  const auto& simple = SimpleKinds();
  for (size_t i = 0; i < n; ++i) {
    const Instance& instance = file_.instances[i];
    Kind kind = Kind::kOther;
    if (instance.record_count == 1) {
      auto found = simple.find(entities_.SimpleType(instance));
      if (found != simple.end()) kind = found->second;
    } else if (entities_.HasPart(instance, "REPRESENTATION_RELATIONSHIP")) {
      if (entities_.HasPart(instance, "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION") &&
          entities_.HasPart(instance, "SHAPE_REPRESENTATION_RELATIONSHIP") &&
          instance.record_count == 3)
        kind = Kind::kSrrWt;
      else
        kind = Kind::kOtherRr;
    } else if (entities_.HasPart(instance, "SHAPE_REPRESENTATION")) {
      kind = Kind::kShapeRepresentation;
    }
    kinds_[i] = kind;
  }
  // Sharings, in file order of the referring instances.
  std::vector<uint64_t> stack;
  for (uint32_t index : order_) {
    if (!IndexesSharings(kinds_[index])) continue;
    const Instance& instance = file_.instances[index];
    for (uint32_t r = 0; r < instance.record_count; ++r) {
      const Record& record = file_.records[instance.first_record + r];
      // Walk the record's parameters, lists included (bounded: the parser limits nesting).
      std::vector<const Param*> todo;
      for (uint32_t p = 0; p < record.param_count; ++p) todo.push_back(file_.Arg(record, p));
      while (!todo.empty()) {
        const Param* param = todo.back();
        todo.pop_back();
        if (param == nullptr) continue;
        if (param->kind == ParamKind::kRef) {
          std::vector<uint64_t>& list = sharings_[param->value.ref];
          if (list.empty() || list.back() != instance.id) list.push_back(instance.id);
        } else if (param->kind == ParamKind::kList || param->kind == ParamKind::kTyped) {
          for (uint32_t k = param->count; k-- > 0;) todo.push_back(file_.Item(*param, k));
        }
      }
    }
  }
}

Kind Translator::KindOf(uint64_t id) const {
  const Instance* instance = file_.Find(id);
  if (instance == nullptr) return Kind::kOther;
  return kinds_[static_cast<size_t>(instance - file_.instances.data())];
}

const std::vector<uint64_t>& Translator::Sharings(uint64_t id) const {
  static const std::vector<uint64_t> none;
  auto found = sharings_.find(id);
  return found == sharings_.end() ? none : found->second;
}

// STEPControl_Reader::NbRootsForTransfer with its default settings: the product definitions no
// NEXT_ASSEMBLY_USAGE_OCCURRENCE names as a component.
std::vector<uint64_t> Translator::Roots() const {
  std::vector<uint64_t> roots;
  for (uint32_t index : order_) {
    if (kinds_[index] == Kind::kExternal)
      ThrowUnsupported(entities_.Describe(file_.instances[index]) + " (a document reference)");
  }
  for (uint32_t index : order_) {
    if (kinds_[index] != Kind::kProductDefinition) continue;
    const Instance& pd = file_.instances[index];
    bool is_root = true;
    for (uint64_t user : Sharings(pd.id)) {
      if (KindOf(user) != Kind::kNauo) continue;
      // NAUO(id, name, description, relating, related, reference_designator)
      if (entities_.Simple(entities_.Get(user, 0)).Ref(4) == pd.id) is_root = false;
    }
    if (is_root) roots.push_back(pd.id);
  }
  return roots;
}

// ---------------------------------------------------------------------------------------------
// Units

const UnitFactors& Translator::UnitsOf(uint64_t representation) {
  auto found = units_.find(representation);
  if (found != units_.end()) return found->second;
  // (name, items, context_of_items)
  Entity rep = entities_.Simple(entities_.Get(representation, 0));
  if (entities_.IsComplex(rep.instance()))
    ThrowUnsupported(rep.Name() + ": a complex representation");
  const Instance& context = entities_.Get(rep.Ref(2), representation);
  const bool has_units = entities_.HasPart(context, "GLOBAL_UNIT_ASSIGNED_CONTEXT");
  const bool has_uncertainty = entities_.HasPart(context, "GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT");
  const bool geometric = entities_.HasPart(context, "GEOMETRIC_REPRESENTATION_CONTEXT") &&
                         entities_.HasPart(context, "REPRESENTATION_CONTEXT");
  if (!geometric || !has_units || context.record_count != (has_uncertainty ? 4u : 3u))
    ThrowUnsupported(entities_.Describe(context) + ": a representation context without units");
  UnitFactors units;
  double length = 1., plane_angle = M_PI / 180.;
  // STEPConstruct_UnitContext::ComputeFactors, with OCCT's cascade unit of 1 mm.
  Entity assigned = entities_.Part(context, "GLOBAL_UNIT_ASSIGNED_CONTEXT");
  const Param& list = assigned.List(0);
  for (uint32_t i = 0; i < list.count; ++i) {
    const Instance& unit = entities_.Get(assigned.RefItem(list, i), context.id);
    if (!entities_.IsComplex(unit)) continue;  // not a named unit OCCT recognises
    const bool is_length = entities_.HasPart(unit, "LENGTH_UNIT");
    const bool is_angle = entities_.HasPart(unit, "PLANE_ANGLE_UNIT");
    double parameter = 0.;
    if (entities_.HasPart(unit, "SI_UNIT")) {
      // SI_UNIT(prefix, name)
      Entity si = entities_.Part(unit, "SI_UNIT");
      double prefix = 1.;
      if (!si.IsUnset(0)) {
        static const std::map<std::string_view, double> kPrefixes = {
            {"EXA", 1e18},  {"PETA", 1e15},  {"TERA", 1e12},   {"GIGA", 1e9},
            {"MEGA", 1e6},  {"KILO", 1e3},   {"HECTO", 1e2},   {"DECA", 1e1},
            {"DECI", 1e-1}, {"CENTI", 1e-2}, {"MILLI", 1e-3},  {"MICRO", 1e-6},
            {"NANO", 1e-9}, {"PICO", 1e-12}, {"FEMTO", 1e-15}, {"ATTO", 1e-18}};
        auto prefix_found = kPrefixes.find(si.Enum(0));
        if (prefix_found == kPrefixes.end()) ThrowUnsupported(si.Name() + ": an unknown SI prefix");
        prefix = prefix_found->second;
      }
      std::string_view name = si.Enum(1);
      const double name_factor =
          (name == "METRE" || name == "RADIAN" || name == "STERADIAN") ? 1. : 0.;
      parameter = prefix * name_factor;
    } else if (entities_.HasPart(unit, "CONVERSION_BASED_UNIT")) {
      // CONVERSION_BASED_UNIT(name, conversion_factor)
      Entity cbu = entities_.Part(unit, "CONVERSION_BASED_UNIT");
      const Instance& measure = entities_.Get(cbu.Ref(1), unit.id);
      // (value_component, unit_component)
      Entity mwu = entities_.Simple(measure);
      if (entities_.IsComplex(measure)) ThrowUnsupported(mwu.Name() + " as a conversion factor");
      const Instance& target = entities_.Get(mwu.Ref(1), measure.id);
      if (!entities_.IsComplex(target) || !entities_.HasPart(target, "SI_UNIT"))
        ThrowUnsupported(entities_.Describe(target) + " as a conversion target");
      Entity si = entities_.Part(target, "SI_UNIT");
      double prefix = 1.;
      if (!si.IsUnset(0)) {
        std::string_view p = si.Enum(0);
        if (p == "MILLI")
          prefix = 1e-3;
        else if (p == "CENTI")
          prefix = 1e-2;
        else if (p == "KILO")
          prefix = 1e3;
        else if (p == "MICRO")
          prefix = 1e-6;
        else if (p == "DECI")
          prefix = 1e-1;
        else
          ThrowUnsupported(si.Name() + ": an unusual SI prefix in a conversion");
      }
      parameter = prefix * mwu.Measure(0);
    } else {
      continue;
    }
    if (is_length) length = parameter * 1000. / 1.;
    if (is_angle) plane_angle = parameter;
  }
  units.length = length;
  units.plane_angle = plane_angle;
  units.precision = kDefaultPrecision;
  if (has_uncertainty) {
    Entity uncertain = entities_.Part(context, "GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT");
    const Param& values = uncertain.List(0);
    double uncertainty = RealLast();
    bool found_length = false;
    for (uint32_t i = 0; i < values.count; ++i) {
      const Instance& u = entities_.Get(uncertain.RefItem(values, i), context.id);
      if (entities_.SimpleType(u) != "UNCERTAINTY_MEASURE_WITH_UNIT") continue;
      // (value_component, unit_component, name, description)
      Entity umwu = entities_.Simple(u);
      const Instance& unit = entities_.Get(umwu.Ref(1), u.id);
      if (!entities_.IsComplex(unit) || !entities_.HasPart(unit, "LENGTH_UNIT")) continue;
      if (!entities_.HasPart(unit, "SI_UNIT") && !entities_.HasPart(unit, "CONVERSION_BASED_UNIT"))
        continue;
      const double value = umwu.Measure(0);
      if (uncertainty > value) uncertainty = value;
      found_length = true;
    }
    if (found_length) units.precision = uncertainty * units.length;
  }
  units.max_tolerance = std::max(units.precision, kMaxPrecision);
  return units_.emplace(representation, units).first->second;
}

// STEPControl_Reader::findUnits: the names of a context's length, plane angle and solid angle
// units ("" where absent); nullopt when it names none.
std::optional<std::array<std::string, 3>> UnitNames(const Entities& entities,
                                                    const Instance& context) {
  if (!entities.IsComplex(context) || !entities.HasPart(context, "GLOBAL_UNIT_ASSIGNED_CONTEXT") ||
      !entities.HasPart(context, "GEOMETRIC_REPRESENTATION_CONTEXT"))
    return std::nullopt;
  Entity assigned = entities.Part(context, "GLOBAL_UNIT_ASSIGNED_CONTEXT");
  const Param& list = assigned.List(0);
  std::array<std::string, 3> names;
  int found = 0;
  for (uint32_t i = 0; i < list.count; ++i) {
    const Instance& unit = entities.Get(assigned.RefItem(list, i), context.id);
    if (!entities.IsComplex(unit)) continue;
    int index = -1;
    std::string name;
    if (entities.HasPart(unit, "CONVERSION_BASED_UNIT")) {
      Entity cbu = entities.Part(unit, "CONVERSION_BASED_UNIT");
      std::string_view measure = entities.SimpleType(entities.Get(cbu.Ref(1), unit.id));
      if (measure == "LENGTH_MEASURE_WITH_UNIT")
        index = 0;
      else if (measure == "PLANE_ANGLE_MEASURE_WITH_UNIT")
        index = 1;
      else if (measure == "SOLID_ANGLE_MEASURE_WITH_UNIT")
        index = 2;
      if (index < 0) continue;
      name = cbu.String(0);
    } else if (entities.HasPart(unit, "SI_UNIT")) {
      if (entities.HasPart(unit, "LENGTH_UNIT"))
        index = 0;
      else if (entities.HasPart(unit, "PLANE_ANGLE_UNIT"))
        index = 1;
      else if (entities.HasPart(unit, "SOLID_ANGLE_UNIT"))
        index = 2;
      if (index < 0) continue;
      // getSiName: the prefix and the name in lower case.
      Entity si = entities.Part(unit, "SI_UNIT");
      if (!si.IsUnset(0))
        for (char c : si.Enum(0))
          name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      std::string_view si_name = si.Enum(1);
      if (si_name == "METRE" || si_name == "RADIAN" || si_name == "STERADIAN")
        for (char c : si_name)
          name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else {
      continue;
    }
    names[index] = name;
    ++found;
  }
  if (found == 0) return std::nullopt;
  return names;
}

// STEPControl_Reader::FileUnits: the first root's length unit name, else the first context's in
// the file, else "MILLIMETRE" (ReadStep's default).
std::string Translator::LengthUnitName() {
  for (uint64_t root : Roots()) {
    uint64_t rep_id = 0;
    for (uint64_t user : Sharings(root)) {
      if (KindOf(user) != Kind::kProductDefinitionShape) continue;
      for (uint64_t sdr : Sharings(user)) {
        if (KindOf(sdr) != Kind::kShapeDefinitionRepresentation) continue;
        Entity e = entities_.Simple(entities_.Get(sdr, 0));
        if (e.IsUnset(1)) continue;
        const uint64_t used = e.Ref(1);
        if (KindOf(used) == Kind::kShapeRepresentation) {
          rep_id = used;
          break;
        }
      }
      if (rep_id != 0) break;
    }
    if (rep_id == 0) continue;
    Entity rep = entities_.Simple(entities_.Get(rep_id, 0));
    if (auto names = UnitNames(entities_, entities_.Get(rep.Ref(2), rep_id))) return (*names)[0];
  }
  for (uint32_t index : order_) {
    const Instance& instance = file_.instances[index];
    if (!entities_.IsComplex(instance) || !entities_.HasPart(instance, "REPRESENTATION_CONTEXT"))
      continue;
    if (auto names = UnitNames(entities_, instance)) return (*names)[0];
  }
  return "MILLIMETRE";
}

// ---------------------------------------------------------------------------------------------
// The walk

// The product definition whose SHAPE_DEFINITION_REPRESENTATION uses `rep`, or 0.
uint64_t Translator::ProductOfRepresentation(uint64_t rep) {
  for (uint64_t user : Sharings(rep)) {
    if (KindOf(user) != Kind::kShapeDefinitionRepresentation) continue;
    Entity sdr = entities_.Simple(entities_.Get(user, 0));
    if (sdr.Ref(1) != rep) continue;
    const uint64_t pds = sdr.Ref(0);
    if (KindOf(pds) != Kind::kProductDefinitionShape) continue;
    const uint64_t definition = entities_.Simple(entities_.Get(pds, user)).Ref(2);
    if (KindOf(definition) == Kind::kProductDefinition) return definition;
  }
  return 0;
}

// STEPConstruct_Assembly::CheckSRRReversesNAUO.
bool Translator::SrrReversesNauo(uint64_t cdsr_id) {
  Entity cdsr = entities_.Simple(entities_.Get(cdsr_id, 0));
  const uint64_t pds = cdsr.Ref(1);
  const uint64_t nauo = entities_.Simple(entities_.Get(pds, cdsr_id)).Ref(2);
  if (KindOf(nauo) != Kind::kNauo) return false;
  Entity n = entities_.Simple(entities_.Get(nauo, pds));
  const uint64_t relating = n.Ref(3), related = n.Ref(4);
  Entity rr = entities_.Part(entities_.Get(cdsr.Ref(0), cdsr_id), "REPRESENTATION_RELATIONSHIP");
  const uint64_t pd1 = ProductOfRepresentation(rr.Ref(2));
  const uint64_t pd2 = ProductOfRepresentation(rr.Ref(3));
  if (pd1 == related && pd2 == relating) return false;
  if (pd2 == related && pd1 == relating) return true;
  return pd2 == related || pd1 == relating;
}

// STEPControl_ActorRead::ComputeTransformation.
void Translator::ComputeTransformation(uint64_t origin, uint64_t target, uint64_t origin_rep,
                                       uint64_t target_rep, gp_Trsf* trsf) {
  auto holds = [&](uint64_t rep, uint64_t item) {
    Entity r = entities_.Simple(entities_.Get(rep, 0));
    const Param& items = r.List(1);
    for (uint32_t i = 0; i < items.count; ++i)
      if (r.Item(items, i).kind == ParamKind::kRef && r.RefItem(items, i) == item) return true;
    return false;
  };
  const bool ok_origin = holds(origin_rep, origin);
  const bool swap_target = !ok_origin ? holds(origin_rep, target) : false;
  const bool ok_target = holds(target_rep, target);
  const bool swap_origin = !ok_target ? holds(target_rep, origin) : false;
  uint64_t org = origin, trg = target;
  if ((!ok_origin || !ok_target) && swap_origin && swap_target) std::swap(org, trg);
  const gp_Ax2 from = geometry_.Axis2Placement(org, 0, UnitsOf(origin_rep));
  const gp_Ax2 to = geometry_.Axis2Placement(trg, 0, UnitsOf(target_rep));
  trsf->SetTransformation(gp_Ax3(to), gp_Ax3(from));
}

// STEPControl_ActorRead::ComputeSRRWT.
bool Translator::ComputeSrrTransformation(uint64_t rr_id, gp_Trsf* trsf) {
  *trsf = gp_Trsf();
  if (KindOf(rr_id) != Kind::kSrrWt) return false;
  const Instance& rr_instance = entities_.Get(rr_id, 0);
  Entity rr = entities_.Part(rr_instance, "REPRESENTATION_RELATIONSHIP");
  Entity wt = entities_.Part(rr_instance, "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION");
  const uint64_t op = wt.Ref(0);
  const Instance& op_instance = entities_.Get(op, rr_id);
  if (entities_.SimpleType(op_instance) == "CARTESIAN_TRANSFORMATION_OPERATOR_3D") {
    *trsf = geometry_.Transformation(op, rr_id, UnitsOf(rr.Ref(3)));
    return trsf->Form() != gp_Identity;
  }
  if (KindOf(op) != Kind::kItemDefinedTransformation)
    ThrowUnsupported(entities_.Describe(op_instance) + " as a transformation");
  // ITEM_DEFINED_TRANSFORMATION(name, description, transform_item_1, transform_item_2)
  Entity idt = entities_.Simple(op_instance);
  const uint64_t ax1 = idt.Ref(2), ax2 = idt.Ref(3);
  if (entities_.SimpleType(entities_.Get(ax1, op)) != "AXIS2_PLACEMENT_3D" ||
      entities_.SimpleType(entities_.Get(ax2, op)) != "AXIS2_PLACEMENT_3D")
    return false;
  ComputeTransformation(ax1, ax2, rr.Ref(2), rr.Ref(3), trsf);
  return trsf->Form() != gp_Identity;
}

TopoDS_Shape Translator::TransferProduct(uint64_t pd, bool use_trsf) {
  if (IsBound(pd)) return Bound(pd);
  CheckStop();
  std::vector<uint64_t> sdrs, nauos, aspect_sdrs;
  for (uint64_t user : Sharings(pd)) {
    const Kind kind = KindOf(user);
    if (kind == Kind::kProductDefinitionShape) {
      for (uint64_t s : Sharings(user)) {
        const Kind k = KindOf(s);
        if (k == Kind::kShapeDefinitionRepresentation) {
          if (!entities_.Simple(entities_.Get(s, 0)).IsUnset(1)) sdrs.push_back(s);
        } else if (k == Kind::kShapeAspect) {
          // SDRs of a shape aspect (AP203 hybrid models), unless used by GD&T.
          const Instance& aspect = entities_.Get(s, 0);
          if (entities_.SimpleType(aspect) == "DATUM_FEATURE") continue;
          for (uint64_t p : Sharings(s)) {
            if (KindOf(p) != Kind::kPropertyDefinition) continue;
            for (uint64_t q : Sharings(p))
              if (KindOf(q) == Kind::kShapeDefinitionRepresentation) aspect_sdrs.push_back(q);
          }
        } else if (k == Kind::kNauo) {
          Entity nauo = entities_.Simple(entities_.Get(s, 0));
          if (nauo.Ref(3) == pd) nauos.push_back(s);
        }
      }
    } else if (kind == Kind::kNauo) {
      Entity nauo = entities_.Simple(entities_.Get(user, 0));
      if (nauo.Ref(3) == pd) nauos.push_back(user);
    }
  }
  if (!aspect_sdrs.empty())
    ThrowUnsupported(entities_.Describe(entities_.Get(aspect_sdrs.front(), 0)) +
                     " of a shape aspect");
  if (sdrs.empty() && nauos.empty()) return TopoDS_Shape();
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  TopoDS_Shape one;
  int components = 0, shapes = 0;
  for (uint64_t nauo : nauos) {
    TopoDS_Shape result = IsBound(nauo) ? Bound(nauo) : TransferNauo(nauo);
    if (result.IsNull()) continue;
    one = result;
    builder.Add(compound, result);
    ++components;
  }
  for (uint64_t sdr_id : sdrs) {
    const uint64_t rep = entities_.Simple(entities_.Get(sdr_id, 0)).Ref(1);
    if (KindOf(rep) != Kind::kShapeRepresentation) continue;
    bool is_bound = true;
    TopoDS_Shape result = IsBound(rep) ? Bound(rep) : TransferShapeRep(rep, &is_bound, use_trsf);
    if (!result.IsNull()) {
      one = result;
      builder.Add(compound, result);
      ++shapes;
    }
    // Representations related to this one (AP203 since 1998, AP209, and most CAD files: a
    // SHAPE_REPRESENTATION of placements related to an ADVANCED_BREP_SHAPE_REPRESENTATION).
    for (uint64_t user : Sharings(rep)) {
      const Kind k = KindOf(user);
      if (k != Kind::kSrr) continue;
      Entity srr = entities_.Simple(entities_.Get(user, 0));
      const int nbrep = srr.Ref(2) == rep ? 2 : 1;
      TopoDS_Shape related = TransferSrr(user, nbrep, use_trsf);
      if (related.IsNull()) continue;
      one = related;
      builder.Add(compound, related);
      ++shapes;
    }
  }
  TopoDS_Shape result = (shapes == 1 && components == 0) ? one : TopoDS_Shape(compound);
  Bind(pd, result);
  return result;
}

TopoDS_Shape Translator::TransferNauo(uint64_t nauo) {
  uint64_t pd = 0, srr = 0;
  gp_Trsf trsf;
  bool has_trsf = false, reversed = false, depends = false;
  for (uint64_t pds : Sharings(nauo)) {
    if (KindOf(pds) != Kind::kProductDefinitionShape) continue;
    for (uint64_t cdsr : Sharings(pds)) {
      if (KindOf(cdsr) != Kind::kCdsr) continue;
      depends = true;
      Entity c = entities_.Simple(entities_.Get(cdsr, 0));
      const uint64_t rr_id = c.Ref(0);
      const Instance& rr_instance = entities_.Get(rr_id, cdsr);
      if (!entities_.HasPart(rr_instance, "REPRESENTATION_RELATIONSHIP") &&
          entities_.SimpleType(rr_instance) != "SHAPE_REPRESENTATION_RELATIONSHIP")
        ThrowUnsupported(entities_.Describe(rr_instance) + " in an assembly");
      Entity rr = entities_.IsComplex(rr_instance)
                      ? entities_.Part(rr_instance, "REPRESENTATION_RELATIONSHIP")
                      : entities_.Simple(rr_instance);
      reversed = SrrReversesNauo(cdsr);
      const uint64_t rep = reversed ? rr.Ref(3) : rr.Ref(2);
      has_trsf = ComputeSrrTransformation(rr_id, &trsf);
      for (uint64_t user : Sharings(rep)) {
        const Kind k = KindOf(user);
        if (k == Kind::kShapeDefinitionRepresentation) {
          const uint64_t pds1 = entities_.Simple(entities_.Get(user, 0)).Ref(0);
          if (KindOf(pds1) != Kind::kProductDefinitionShape) continue;
          const uint64_t definition = entities_.Simple(entities_.Get(pds1, user)).Ref(2);
          if (pd == 0 && KindOf(definition) == Kind::kProductDefinition) pd = definition;
        } else if (k == Kind::kSrr || k == Kind::kSrrWt) {
          srr = user;
        }
      }
    }
  }
  TopoDS_Shape result;
  if (depends) {
    if (pd != 0) {
      result = IsBound(pd) ? Bound(pd) : TransferProduct(pd, false);
      if (!result.IsNull() && has_trsf)
        ApplyTransformation(&result, reversed ? trsf.Inverted() : trsf);
    }
    if (result.IsNull() && srr != 0 && !IsBound(srr)) result = TransferSrr(srr, 0, false);
  }
  Bind(nauo, result);
  return result;
}

TopoDS_Shape Translator::TransferSrr(uint64_t srr_id, int nbrep, bool use_trsf) {
  const Instance& instance = entities_.Get(srr_id, 0);
  Entity rr = entities_.IsComplex(instance)
                  ? entities_.Part(instance, "REPRESENTATION_RELATIONSHIP")
                  : entities_.Simple(instance);
  gp_Trsf trsf;
  const bool has_trsf = ComputeSrrTransformation(srr_id, &trsf);
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  TopoDS_Shape one;
  int count = 0;
  for (int i = 1; i <= 2; ++i) {
    if (nbrep != 0 && nbrep != i) continue;
    const uint64_t rep = rr.Ref(i == 1 ? 2 : 3);
    if (KindOf(rep) != Kind::kShapeRepresentation) continue;
    bool is_bound = false;
    TopoDS_Shape result = IsBound(rep) ? Bound(rep) : TransferShapeRep(rep, &is_bound, use_trsf);
    if (result.IsNull()) continue;
    one = result;
    builder.Add(compound, result);
    ++count;
  }
  if (has_trsf) {
    if (count == 1)
      ApplyTransformation(&one, trsf);
    else if (count > 1)
      ApplyTransformation(&compound, trsf);
  }
  TopoDS_Shape result;
  if (count == 1)
    result = one;
  else if (count > 1)
    result = compound;
  Bind(srr_id, result);
  return result;
}

TopoDS_Shape Translator::TransferShapeRep(uint64_t sr, bool* is_bound, bool use_trsf) {
  Entity rep = entities_.Simple(entities_.Get(sr, 0));
  const Param& items = rep.List(1);
  // Recognize: a representation transfers when one of its items is a shape.
  static const std::set<std::string_view> kShapeItems = {
      "MANIFOLD_SOLID_BREP", "BREP_WITH_VOIDS",     "SHELL_BASED_SURFACE_MODEL",
      "MAPPED_ITEM",         "GEOMETRIC_CURVE_SET", "GEOMETRIC_SET"};
  static const std::set<std::string_view> kUnsupportedItems = {"FACETED_BREP",
                                                               "FACE_SURFACE",
                                                               "ADVANCED_FACE",
                                                               "EDGE_BASED_WIREFRAME_MODEL",
                                                               "FACE_BASED_SURFACE_MODEL",
                                                               "FACETED_BREP_AND_BREP_WITH_VOIDS"};
  bool recognized = false;
  for (uint32_t i = 0; i < items.count; ++i) {
    if (rep.Item(items, i).kind != ParamKind::kRef) continue;
    const Instance& item = entities_.Get(rep.RefItem(items, i), sr);
    std::string_view type = entities_.SimpleType(item);
    if (kUnsupportedItems.count(type) != 0) ThrowUnsupported(entities_.Describe(item));
    if (kShapeItems.count(type) != 0) recognized = true;
  }
  if (!recognized) return TopoDS_Shape();
  *is_bound = false;
  UnitsOf(sr);
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  TopoDS_Shape one;
  int count = 0;
  gp_Trsf trsf;
  for (uint32_t i = 0; i < items.count; ++i) {
    if (rep.Item(items, i).kind != ParamKind::kRef) continue;
    const uint64_t item_id = rep.RefItem(items, i);
    const Instance& item = entities_.Get(item_id, sr);
    std::string_view type = entities_.SimpleType(item);
    if (use_trsf && type == "AXIS2_PLACEMENT_3D") {
      bool used_by_transformation = false;
      for (uint64_t user : Sharings(item_id))
        if (KindOf(user) == Kind::kItemDefinedTransformation) used_by_transformation = true;
      if (!used_by_transformation) {
        const gp_Ax3 target(geometry_.Axis2Placement(item_id, sr, UnitsOf(sr)));
        const gp_Ax3 origin(gp_Pnt(0., 0., 0), gp_Vec(0., 0., 1.), gp_Vec(1., 0., 0.));
        if (!(target.Location().SquareDistance(origin.Location()) < Precision::SquareConfusion() &&
              target.Direction().IsEqual(origin.Direction(), Precision::Angular()) &&
              target.XDirection().IsEqual(origin.XDirection(), Precision::Angular())))
          trsf.SetTransformation(target, origin);
        continue;
      }
    }
    TopoDS_Shape result;
    if (IsBound(item_id)) {
      *is_bound = true;
      result = Bound(item_id);
    } else if (type == "MAPPED_ITEM") {
      result = TransferMappedItem(item_id, sr);
    } else if (IsBrepItem(entities_, item)) {
      result = TransferItem(item_id, sr);
    }
    if (result.IsNull()) continue;
    one = result;
    builder.Add(compound, result);
    ++count;
  }
  TopoDS_Shape result;
  if (count == 1) {
    if (trsf.Form() != gp_Identity) one.Move(TopLoc_Location(trsf));
    result = one;
  } else if (count > 1) {
    if (trsf.Form() != gp_Identity) compound.Move(TopLoc_Location(trsf));
    result = compound;
  }
  Bind(sr, result);
  return result;
}

TopoDS_Shape Translator::TransferMappedItem(uint64_t mapped_id, uint64_t representation) {
  // MAPPED_ITEM(name, mapping_source, mapping_target); REPRESENTATION_MAP(mapping_origin,
  // mapped_representation)
  Entity mapped = entities_.Simple(entities_.Get(mapped_id, representation));
  const uint64_t source = mapped.Ref(1);
  const Instance& map_instance = entities_.Get(source, mapped_id);
  if (entities_.SimpleType(map_instance) != "REPRESENTATION_MAP")
    ThrowUnsupported(entities_.Describe(map_instance) + " as a mapping source");
  Entity map = entities_.Simple(map_instance);
  const uint64_t maprep = map.Ref(1);
  if (KindOf(maprep) != Kind::kShapeRepresentation)
    ThrowUnsupported(entities_.Describe(entities_.Get(maprep, source)) + " as a mapped shape");
  bool is_bound = false;
  TopoDS_Shape shape = IsBound(maprep) ? Bound(maprep) : TransferShapeRep(maprep, &is_bound, false);
  if (shape.IsNull()) return shape;
  gp_Trsf trsf;
  bool ok = false;
  const uint64_t target = mapped.Ref(2);
  const Instance& target_instance = entities_.Get(target, mapped_id);
  std::string_view target_type = entities_.SimpleType(target_instance);
  if (target_type == "CARTESIAN_TRANSFORMATION_OPERATOR_3D") {
    trsf = geometry_.Transformation(target, mapped_id, UnitsOf(representation));
    ok = true;
  } else if (target_type == "AXIS2_PLACEMENT_3D" &&
             entities_.SimpleType(entities_.Get(map.Ref(0), source)) == "AXIS2_PLACEMENT_3D") {
    ComputeTransformation(map.Ref(0), target, maprep, representation, &trsf);
    ok = true;
  }
  if (!ok) ThrowUnsupported(mapped.Name() + ": a placement OCCT ignores");
  ApplyTransformation(&shape, trsf);
  Bind(mapped_id, shape);
  return shape;
}

// In the planning walk: records the item and stands in an empty compound for it, so the walk
// builds the same structure. After BuildItems: the healed item.
TopoDS_Shape Translator::TransferItem(uint64_t item_id, uint64_t representation) {
  if (planning_) {
    auto found = item_by_id_.find(item_id);
    if (found == item_by_id_.end()) {
      auto item = std::make_unique<BrepItem>();
      item->id = item_id;
      item->units = UnitsOf(representation);
      item_by_id_[item_id] = item.get();
      items_.push_back(std::move(item));
    }
    TopoDS_Compound placeholder;
    BRep_Builder().MakeCompound(placeholder);
    Bind(item_id, placeholder);
    return placeholder;
  }
  BrepItem* item = item_by_id_.at(item_id);
  // The faces and shells the item bound, as the healing left them (MergeTransferInfo).
  for (const auto& [id, raw] : item->bound) Bind(id, HealedShape(*item, raw));
  Bind(item_id, item->healed);
  return item->healed;
}

// ---------------------------------------------------------------------------------------------
// Items

void Translator::BuildItems(std::vector<std::pair<std::string, double>>* stage_seconds) {
  auto stage = Clock::now();
  // Items whose edges share a curve entity share Geom objects, which OCCT's reader healed one
  // after the other: build and heal those in order; heal the others in parallel.
  std::unordered_map<uint64_t, int> curve_users;
  for (auto& item : items_) {
    CheckStop();
    BuildItem(geometry_, item.get());
    for (uint64_t curve : item->curves) ++curve_users[curve];
  }
  bool shared = false;
  for (const auto& [curve, users] : curve_users) shared = shared || users > 1;
  // A curve set's elements are bound to shapes in OCCT's transfer process, where edges bind
  // their curves and other sets look their elements up: an element used so twice is not
  // reproduced.
  std::unordered_set<uint64_t> elements;
  for (auto& item : items_) {
    for (uint64_t element : item->elements) {
      if (curve_users.count(element) != 0 || !elements.insert(element).second)
        ThrowUnsupported(entities_.Describe(entities_.Get(element, item->id)) +
                         ": an element of a geometric set used elsewhere too");
    }
  }
  stage_seconds->emplace_back("build", Since(stage));
  stage = Clock::now();
  if (shared) {
    // Rebuild in OCCT's order, each item healed before the next is built.
    Geometry fresh(entities_);
    for (auto& item : items_) {
      CheckStop();
      BuildItem(fresh, item.get());
      HealItem(item.get());
    }
    stage_seconds->emplace_back("rebuild and heal in order", Since(stage));
    heal_stats_.refused = "items share a curve";
    return;
  }
  std::vector<BrepItem*> items;
  for (auto& item : items_) items.push_back(item.get());
  const Context* context = context_;
  const HealStats stats = HealItems(
      items, options_.threads, [context] { return context != nullptr && context->ShouldStop(); });
  CheckStop();
  stage_seconds->emplace_back("heal faces", stats.face_seconds);
  stage_seconds->emplace_back("heal shells", stats.finish_seconds);
  heal_stats_ = stats;
}

// ---------------------------------------------------------------------------------------------
// Document

void Translator::PlanNames(DocumentPlan* plan) {
  auto useful = [](const std::string& s) {
    return s.find_first_not_of(' ') != std::string::npos;  // UsefullLength() > 0
  };
  for (uint32_t index : order_) {
    const Instance& instance = file_.instances[index];
    const Kind kind = kinds_[index];
    if (kind == Kind::kNauo) {
      // The name of the PRODUCT_DEFINITION_SHAPE's relationship: the NAUO itself.
      std::string name;
      bool named = false;
      for (uint64_t pds : Sharings(instance.id)) {
        if (KindOf(pds) != Kind::kProductDefinitionShape) continue;
        const uint64_t definition = entities_.Simple(entities_.Get(pds, 0)).Ref(2);
        if (KindOf(definition) != Kind::kNauo) continue;
        // (id, name, description, relating, related, reference_designator)
        Entity pdr = entities_.Simple(entities_.Get(definition, pds));
        const std::string description = pdr.String(2);
        if (useful(description))
          name = description;
        else if (!pdr.IsUnset(1) && useful(pdr.String(1)))
          name = pdr.String(1);
        else
          name = pdr.String(0);
        named = true;
      }
      (void)named;
      const TopoDS_Shape shape = Bound(instance.id);
      if (!shape.IsNull()) plan->names.push_back({shape, name});
    } else if (kind == Kind::kProductDefinition) {
      // PRODUCT_DEFINITION(id, description, formation, frame_of_reference) ->
      // PRODUCT_DEFINITION_FORMATION(id, description, of_product) -> PRODUCT(id, name, ...)
      Entity pd = entities_.Simple(instance);
      std::string name;
      if (!pd.IsUnset(2)) {
        const Instance& formation = entities_.Get(pd.Ref(2), instance.id);
        Entity f = entities_.Simple(formation);
        const Instance& product = entities_.Get(f.Ref(2), formation.id);
        Entity p = entities_.Simple(product);
        if (entities_.SimpleType(product) != "PRODUCT")
          ThrowUnsupported(p.Name() + " as a product");
        const std::string product_name = p.String(1);
        name = useful(product_name) ? product_name : p.String(0);
      }
      const TopoDS_Shape shape = Bound(instance.id);
      if (!shape.IsNull()) plan->names.push_back({shape, name});
    }
  }
}

// STEPCAFControl_Reader::ReadLayers: each PRESENTATION_LAYER_ASSIGNMENT whose items were
// transferred becomes a layer (invisible when an INVISIBILITY names it) holding their labels;
// an item that is a sub-shape of a part gets a sub-shape label.
void Translator::PlanLayers(DocumentPlan* plan) {
  std::unordered_set<uint64_t> invisible;
  bool any = false;
  for (uint32_t index : order_) {
    if (kinds_[index] == Kind::kLayerAssignment) any = true;
    if (kinds_[index] != Kind::kInvisibility) continue;
    Entity inv = entities_.Simple(file_.instances[index]);
    const Param& items = inv.List(0);
    for (uint32_t i = 0; i < items.count; ++i)
      if (inv.Item(items, i).kind == ParamKind::kRef) invisible.insert(inv.RefItem(items, i));
  }
  if (!any) return;
  for (uint32_t index : order_) {
    if (kinds_[index] != Kind::kLayerAssignment) continue;
    // (name, description, assigned_items)
    const Instance& instance = file_.instances[index];
    Entity layer = entities_.Simple(instance);
    if (layer.IsUnset(2)) continue;
    PlannedLayer planned{layer.String(0), invisible.count(instance.id) == 0, {}};
    const Param& items = layer.List(2);
    for (uint32_t i = 0; i < items.count; ++i) {
      if (layer.Item(items, i).kind != ParamKind::kRef) continue;
      const TopoDS_Shape shape = Bound(layer.RefItem(items, i));
      if (!shape.IsNull()) planned.items.push_back(shape);
    }
    if (!planned.items.empty()) plan->layers.push_back(std::move(planned));
  }
}

bool Translator::DecodeColour(uint64_t colour_id, uint64_t from, Quantity_Color* color) {
  const Instance& colour = entities_.Get(colour_id, from);
  std::string_view type = entities_.SimpleType(colour);
  if (type == "COLOUR_RGB") {
    // (name, red, green, blue)
    Entity rgb = entities_.Simple(colour);
    const double r = rgb.Real(1), g = rgb.Real(2), b = rgb.Real(3);
    if (r > 1. || g > 1. || b > 1.) {
      double norm = r;
      if (norm < g) norm = g;
      if (norm < b) norm = b;
      color->SetValues(r / norm, g / norm, b / norm, Quantity_TOC_sRGB);
    } else {
      color->SetValues(r, g, b, Quantity_TOC_sRGB);
    }
    return true;
  }
  if (type == "DRAUGHTING_PRE_DEFINED_COLOUR") {
    const std::string name = entities_.Simple(colour).String(0);
    static const std::map<std::string, Quantity_NameOfColor> kNames = {
        {"red", Quantity_NOC_RED},          {"green", Quantity_NOC_GREEN},
        {"blue", Quantity_NOC_BLUE1},       {"yellow", Quantity_NOC_YELLOW},
        {"magenta", Quantity_NOC_MAGENTA1}, {"cyan", Quantity_NOC_CYAN1},
        {"black", Quantity_NOC_BLACK},      {"white", Quantity_NOC_WHITE}};
    auto found = kNames.find(name);
    if (found == kNames.end()) ThrowUnsupported(entities_.Describe(colour) + ": an unknown colour");
    color->SetValues(found->second);
    return true;
  }
  ThrowUnsupported(entities_.Describe(colour) + " as a colour");
}

// STEPCAFControl_Reader::ReadColors, for styles without a context (component styles and SHUOs
// are not reproduced).
void Translator::PlanColors(DocumentPlan* plan) {
  std::vector<uint64_t> styles;
  std::unordered_set<uint64_t> seen;
  std::unordered_set<uint64_t> invisible;
  for (uint32_t index : order_) {
    const Instance& instance = file_.instances[index];
    const Kind kind = kinds_[index];
    if (kind == Kind::kStyleContainer) {
      Entity container = entities_.Simple(instance);
      const Param& items = container.List(1);
      for (uint32_t i = 0; i < items.count; ++i) {
        if (container.Item(items, i).kind != ParamKind::kRef) continue;
        const uint64_t item = container.RefItem(items, i);
        const Kind k = KindOf(item);
        if (k != Kind::kStyledItem && k != Kind::kOverridingStyledItem) continue;
        if (seen.insert(item).second) styles.push_back(item);
      }
    } else if (kind == Kind::kStyledItem) {
      if (seen.insert(instance.id).second) styles.push_back(instance.id);
    } else if (kind == Kind::kInvisibility) {
      Entity inv = entities_.Simple(instance);
      const Param& items = inv.List(0);
      for (uint32_t i = 0; i < items.count; ++i)
        if (inv.Item(items, i).kind == ParamKind::kRef) invisible.insert(inv.RefItem(items, i));
    }
  }
  if (styles.empty()) return;
  plan->has_styles = true;
  for (uint64_t style_id : styles) {
    // STYLED_ITEM(name, styles, item)
    Entity style = entities_.Simple(entities_.Get(style_id, 0));
    const bool visible = invisible.count(style_id) == 0;
    std::optional<uint64_t> surf, bound, curve, render;
    double transparency = 0.;
    const Param& assignments = style.List(1);
    for (uint32_t j = 0; j < assignments.count; ++j) {
      const Instance& psa_instance = entities_.Get(style.RefItem(assignments, j), style_id);
      std::string_view psa_type = entities_.SimpleType(psa_instance);
      if (psa_type == "PRESENTATION_STYLE_BY_CONTEXT")
        ThrowUnsupported(entities_.Describe(psa_instance) + " (a component style)");
      if (psa_type != "PRESENTATION_STYLE_ASSIGNMENT")
        ThrowUnsupported(entities_.Describe(psa_instance) + " as a style");
      Entity psa = entities_.Simple(psa_instance);
      const Param& selects = psa.List(0);
      for (uint32_t k = 0; k < selects.count; ++k) {
        const Param& select = psa.Item(selects, k);
        if (select.kind != ParamKind::kRef) continue;  // NULL_STYLE and other typed values
        const Instance& s = entities_.Get(select.value.ref, psa_instance.id);
        std::string_view s_type = entities_.SimpleType(s);
        if (s_type == "SURFACE_STYLE_USAGE") {
          // (side, style)
          Entity usage = entities_.Simple(s);
          // An unset or unknown side reads as NEGATIVE in OCCT.
          const bool negative = usage.IsUnset(0) || usage.At(0).kind != ParamKind::kEnum ||
                                (usage.Enum(0) != "POSITIVE" && usage.Enum(0) != "BOTH");
          const Instance& side_instance = entities_.Get(usage.Ref(1), s.id);
          if (entities_.SimpleType(side_instance) != "SURFACE_SIDE_STYLE")
            ThrowUnsupported(entities_.Describe(side_instance) + " as a surface side style");
          Entity side = entities_.Simple(side_instance);
          const Param& elements = side.List(1);
          for (uint32_t l = 0; l < elements.count; ++l) {
            const Instance& element = entities_.Get(side.RefItem(elements, l), side_instance.id);
            std::string_view e_type = entities_.SimpleType(element);
            Entity el = entities_.Simple(element);
            if (e_type == "SURFACE_STYLE_FILL_AREA") {
              const Instance& fill = entities_.Get(el.Ref(0), element.id);
              if (entities_.SimpleType(fill) != "FILL_AREA_STYLE")
                ThrowUnsupported(entities_.Describe(fill) + " as a fill area style");
              Entity fas = entities_.Simple(fill);
              const Param& fill_styles = fas.List(1);
              for (uint32_t m = 0; m < fill_styles.count; ++m) {
                const Instance& fasc = entities_.Get(fas.RefItem(fill_styles, m), fill.id);
                if (entities_.SimpleType(fasc) != "FILL_AREA_STYLE_COLOUR")
                  ThrowUnsupported(entities_.Describe(fasc) + " as a fill style");
                if (!surf || !negative) surf = entities_.Simple(fasc).Ref(1);
              }
            } else if (e_type == "SURFACE_STYLE_BOUNDARY") {
              const Instance& cs = entities_.Get(el.Ref(0), element.id);
              if (entities_.SimpleType(cs) == "CURVE_STYLE") {
                Entity c = entities_.Simple(cs);
                if (!c.IsUnset(3)) bound = c.Ref(3);
              }
            } else if (e_type == "SURFACE_STYLE_RENDERING" ||
                       e_type == "SURFACE_STYLE_RENDERING_WITH_PROPERTIES") {
              // (rendering_method, surface_colour[, properties])
              render = el.Ref(1);
              transparency = 0.;
              if (e_type == "SURFACE_STYLE_RENDERING_WITH_PROPERTIES") {
                const Param& properties = el.List(2);
                for (uint32_t p = 0; p < properties.count; ++p) {
                  if (el.Item(properties, p).kind != ParamKind::kRef) continue;
                  const Instance& prop = entities_.Get(el.RefItem(properties, p), element.id);
                  if (entities_.SimpleType(prop) == "SURFACE_STYLE_TRANSPARENT")
                    transparency = entities_.Simple(prop).Real(0);
                }
              }
            }
          }
        } else if (s_type == "CURVE_STYLE") {
          Entity c = entities_.Simple(s);
          if (!c.IsUnset(3)) curve = c.Ref(3);
        }
      }
    }
    if (!surf && !bound && !curve && !render && visible) continue;
    const uint64_t item_id = style.Ref(2);
    TopoDS_Shape shape = Bound(item_id);
    if (shape.IsNull()) continue;
    if (!surf && !bound && !curve && !render && visible) continue;
    PlannedStyle planned;
    planned.shape = shape;
    planned.visible = visible;
    if (surf || bound || curve || render) {
      Quantity_Color scol, bcol, ccol, rcol;
      Quantity_ColorRGBA full;
      if (surf) {
        DecodeColour(*surf, style_id, &scol);
        full = Quantity_ColorRGBA(scol);
      }
      if (bound) DecodeColour(*bound, style_id, &bcol);
      if (curve) DecodeColour(*curve, style_id, &ccol);
      if (render) {
        DecodeColour(*render, style_id, &rcol);
        full = Quantity_ColorRGBA(rcol, static_cast<float>(1.0f - transparency));
      }
      if (surf || render) planned.surface = full;
      if (bound) planned.boundary = bcol;
      if (curve) planned.curve = ccol;
    }
    plan->styles.push_back(std::move(planned));
  }
}

void Translator::PlanDocument(const std::vector<TopoDS_Shape>& root_shapes, DocumentPlan* plan) {
  plan->roots = root_shapes;
  // FillShapesMap: the roots' shapes and the components of their compounds, unlocated.
  TopTools_MapOfShape shapes;
  std::function<void(const TopoDS_Shape&)> fill = [&](const TopoDS_Shape& s) {
    TopoDS_Shape unlocated = s;
    unlocated.Location(TopLoc_Location());
    shapes.Add(unlocated);
    if (s.ShapeType() != TopAbs_COMPOUND) return;
    for (TopoDS_Iterator it(s); it.More(); it.Next()) fill(it.Value());
  };
  for (const TopoDS_Shape& shape : root_shapes) fill(shape);
  for (uint32_t index : order_) {
    const Kind kind = kinds_[index];
    if (kind != Kind::kProductDefinition && kind != Kind::kShapeRepresentation) continue;
    TopoDS_Shape shape = Bound(file_.instances[index].id);
    if (!shape.IsNull() && shapes.Contains(shape)) plan->new_shapes.Add(shape);
  }
  // The document's order: colours, names, layers.
  PlanColors(plan);
  PlanNames(plan);
  PlanLayers(plan);
}

Translated Translator::Run() {
  PrepareOcct();
  Translated out;
  auto stage = Clock::now();
  Index();
  out.stage_seconds.emplace_back("index", Since(stage));

  stage = Clock::now();
  const std::vector<uint64_t> roots = Roots();
  if (roots.empty()) ThrowBroken("the STEP file holds no shapes (no product definition)");
  // Planning walk: which B-rep items, in which unit contexts.
  planning_ = true;
  for (uint64_t root : roots) TransferProduct(root, /*use_trsf=*/true);
  out.stage_seconds.emplace_back("structure", Since(stage));

  BuildItems(&out.stage_seconds);

  stage = Clock::now();
  planning_ = false;
  results_.clear();
  std::vector<TopoDS_Shape> root_shapes;
  const ParallelRunner runner(options_.threads);
  for (uint64_t root : roots) {
    TopoDS_Shape shape = TransferProduct(root, /*use_trsf=*/true);
    if (shape.IsNull()) continue;
    EncodeRegularityInParallel(shape, kRegularityAngle, runner);
    root_shapes.push_back(shape);
  }
  if (root_shapes.empty()) ThrowBroken("the STEP translator could not transfer the shapes");
  // The plane pcurves the healing kept for the stages above go, as OCCT's reader stores none:
  // the document and its binary round trip then hold OCCT's B-rep to the last bit.
  for (const TopoDS_Shape& shape : root_shapes) RemovePcurves(shape, heal_stats_.kept_pcurves);
  out.stage_seconds.emplace_back("regularity", Since(stage));

  stage = Clock::now();
  std::tie(out.read.length_unit, out.read.unit_scale_mm) = LengthUnitOf(LengthUnitName());
  DocumentPlan plan;
  PlanDocument(root_shapes, &plan);
  // The document only where the run keeps it, or where it decides the shape and parts.
  const bool keep = context_ == nullptr || context_->keep_document();
  if (keep || !LeanShape(plan, &out.read)) {
    Result<const XcafApi*> xcaf = Xcaf();
    if (!xcaf.ok()) throw Failed{xcaf.status()};
    (*xcaf)->build_step_document(plan, &out.read);
  }
  out.stage_seconds.emplace_back("document", Since(stage));
  out.items = static_cast<int>(items_.size());
  out.items_healed_by_face = heal_stats_.items_face_parallel;
  out.items_in_order = heal_stats_.items_in_order;
  out.faces_fixed_again = heal_stats_.faces_fixed_again;
  out.heal_note = heal_stats_.refused;
  out.supported = true;
  return out;
}

}  // namespace

Result<Translated> TranslateStep(const File& file, const TranslateOptions& options,
                                 const Context* context) {
  Translator translator(file, options, context);
  try {
    OCC_CATCH_SIGNALS
    return translator.Run();
  } catch (const Unsupported& unsupported) {
    Translated out;
    out.supported = false;
    out.unsupported = unsupported.what;
    return out;
  } catch (const Broken& broken) {
    return Status(StatusCode::kParseError, broken.what);
  } catch (const Failed& failed) {
    return failed.status;
  } catch (const std::bad_alloc&) {
    return Status(StatusCode::kResourceExhausted, "out of memory");
  } catch (const Standard_OutOfMemory&) {
    return Status(StatusCode::kResourceExhausted, "out of memory");
  } catch (const Standard_Failure& failure) {
    Translated out;
    out.supported = false;
    out.unsupported = std::string("OCCT failed: ") + failure.DynamicType()->Name();
    return out;
  } catch (...) {
    if (context != nullptr && context->ShouldStop()) return context->StopStatus();
    Translated out;
    out.unsupported = "an unexpected failure";
    return out;
  }
}

}  // namespace rdmesh::step
