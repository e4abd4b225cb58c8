// OCCT's document framework for the engine (xcaf_api.h): the STEP translator's document, the
// BinXCAF payload, the parts of an assembly tree, and the writers that take a document.

// BinTools.hxx declares Standard_IStream, which PCDM_ReadWriter.hxx uses without including it.
#include <BinTools.hxx>
#include <BinXCAFDrivers.hxx>
#include <PCDM_ReadWriter.hxx>
#include <PCDM_Reader.hxx>
#include <PCDM_StorageDriver.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <Storage_Data.hxx>
#include <TCollection_AsciiString.hxx>
#include <TCollection_ExtendedString.hxx>
#include <TDF_Label.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS_Iterator.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DataMapOfShapeLabel.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_LayerTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <functional>
#include <mutex>
#include <set>
#include <sstream>

#include "model/read_shape.h"
#include "model/xcaf_api.h"
#include "writers/gltf_writer.h"
#include "writers/obj_writer.h"

namespace rdmesh {
namespace {

// ---------------------------------------------------------------------------------------------
// The STEP translator's document (STEPCAFControl_Reader::Transfer, from the plan)

class DocumentBuilder {
 public:
  explicit DocumentBuilder(const step::DocumentPlan& plan) : plan_(plan) {}

  void Build(ReadShape* read) {
    doc_ = new TDocStd_Document("MDTV-XCAF");
    XCAFApp_Application::GetApplication()->InitDocument(doc_);
    XCAFDoc_DocumentTool::SetLengthUnit(doc_, 1.0, UnitsMethods_LengthUnit_Millimeter);
    tool_ = XCAFDoc_DocumentTool::ShapeTool(doc_->Main());
    for (const TopoDS_Shape& shape : plan_.roots) AddShape(shape);
    ApplyColors();
    ApplyNames();
    ApplyLayers();
    tool_->UpdateAssemblies();
    read->doc = doc_;
    read->shape = FreeShapesCompound(doc_);
  }

 private:
  TDF_Label AddShape(const TopoDS_Shape& shape);
  void ApplyColors();
  void ApplyNames();
  void ApplyLayers();

  const step::DocumentPlan& plan_;
  Handle(TDocStd_Document) doc_;
  Handle(XCAFDoc_ShapeTool) tool_;
  XCAFDoc_DataMapOfShapeLabel shape_labels_;  // STEPCAFControl_Reader::myMap
};

TDF_Label DocumentBuilder::AddShape(const TopoDS_Shape& shape) {
  if (const TDF_Label* found = shape_labels_.Seek(shape)) return *found;
  if (!shape.Location().IsIdentity()) {
    TopoDS_Shape unlocated = shape;
    unlocated.Location(TopLoc_Location());
    AddShape(unlocated);
    TDF_Label label = tool_->AddShape(shape, Standard_False);
    shape_labels_.Bind(shape, label);
    return label;
  }
  if (shape.ShapeType() != TopAbs_COMPOUND) {
    TDF_Label label = tool_->AddShape(shape, Standard_False);
    shape_labels_.Bind(shape, label);
    return label;
  }
  bool is_assembly = false;
  for (TopoDS_Iterator it(shape); it.More() && !is_assembly; it.Next()) {
    TopoDS_Shape child = it.Value();
    child.Location(TopLoc_Location());
    if (plan_.new_shapes.Contains(child)) is_assembly = true;
  }
  if (!is_assembly) {
    TDF_Label label = tool_->AddShape(shape, Standard_False);
    shape_labels_.Bind(shape, label);
    return label;
  }
  TDF_Label label = tool_->NewShape();
  for (TopoDS_Iterator it(shape); it.More(); it.Next()) {
    TopoDS_Shape child = it.Value();
    child.Location(TopLoc_Location());
    TDF_Label child_label = AddShape(child);
    if (child_label.IsNull()) continue;
    TDF_Label instance = tool_->AddComponent(label, child_label, it.Value().Location());
    if (!shape_labels_.IsBound(it.Value())) shape_labels_.Bind(it.Value(), instance);
  }
  shape_labels_.Bind(shape, label);
  return label;
}

void DocumentBuilder::ApplyNames() {
  auto label_of = [&](const TopoDS_Shape& shape) {
    TDF_Label label;
    if (shape.IsNull()) return label;
    if (const TDF_Label* found = shape_labels_.Seek(shape)) return *found;
    tool_->Search(shape, label, Standard_True, Standard_True, Standard_False);
    return label;
  };
  for (const step::PlannedName& planned : plan_.names) {
    TDF_Label label = label_of(planned.shape);
    if (label.IsNull()) continue;
    TDataStd_Name::Set(label, TCollection_ExtendedString(planned.name.c_str(), Standard_True));
  }
}

// An item that is a sub-shape of a part gets a sub-shape label.
void DocumentBuilder::ApplyLayers() {
  if (plan_.layers.empty()) return;
  Handle(XCAFDoc_LayerTool) layers = XCAFDoc_DocumentTool::LayerTool(doc_->Main());
  for (const step::PlannedLayer& planned : plan_.layers) {
    const TCollection_ExtendedString name(planned.name.c_str(), Standard_True);
    TDF_Label layer_label;
    for (const TopoDS_Shape& shape : planned.items) {
      TDF_Label label;
      if (!tool_->Search(shape, label, Standard_True, Standard_True, Standard_True)) continue;
      if (layer_label.IsNull()) layer_label = layers->AddLayer(name, planned.visible);
      layers->SetLayer(label, layer_label);
    }
    if (!layer_label.IsNull()) layers->SetVisibility(layer_label, planned.visible);
  }
}

void DocumentBuilder::ApplyColors() {
  if (!plan_.has_styles) return;
  Handle(XCAFDoc_ColorTool) colors = XCAFDoc_DocumentTool::ColorTool(doc_->Main());
  for (const step::PlannedStyle& planned : plan_.styles) {
    TDF_Label label;
    const bool found = tool_->SearchUsingMap(planned.shape, label, Standard_False, Standard_True);
    if (planned.surface || planned.boundary || planned.curve) {
      auto set = [&](const TDF_Label& l) {
        if (planned.surface) colors->SetColor(l, *planned.surface, XCAFDoc_ColorSurf);
        if (planned.boundary) colors->SetColor(l, *planned.boundary, XCAFDoc_ColorCurv);
        if (planned.curve) colors->SetColor(l, *planned.curve, XCAFDoc_ColorCurv);
      };
      if (found) {
        set(label);
      } else {
        for (TopoDS_Iterator it(planned.shape); it.More(); it.Next()) {
          TDF_Label sub;
          if (tool_->SearchUsingMap(it.Value(), sub, Standard_False, Standard_True)) set(sub);
        }
      }
    }
    if (!planned.visible && found) colors->SetVisibility(label, Standard_False);
  }
  colors->ReverseChainsOfTreeNodes();
  // Colours of assemblies go to their components without colours of their own.
  std::function<void(const TDF_Label&)> propagate = [&](const TDF_Label& root) {
    TDF_LabelSequence components;
    if (root.IsEqual(tool_->Label()))
      tool_->GetFreeShapes(components);
    else
      tool_->GetComponents(root, components);
    for (TDF_LabelSequence::Iterator it(components); it.More(); it.Next()) {
      TDF_Label original = it.Value();
      tool_->GetReferredShape(original, original);
      TDF_Label color_label, dummy;
      for (int type = 1; type <= 3; ++type) {
        if (colors->GetColor(root, static_cast<XCAFDoc_ColorType>(type), color_label) &&
            !colors->GetColor(original, static_cast<XCAFDoc_ColorType>(type), dummy))
          colors->SetColor(original, color_label, static_cast<XCAFDoc_ColorType>(type));
      }
      if (!colors->IsVisible(root)) colors->SetVisibility(original, Standard_False);
      if (tool_->IsAssembly(original)) propagate(original);
    }
  };
  propagate(tool_->Label());
}

void BuildStepDocument(const step::DocumentPlan& plan, ReadShape* read) {
  DocumentBuilder(plan).Build(read);
}

// ---------------------------------------------------------------------------------------------
// The BinXCAF payload (model_payload.h)

constexpr const char* kXcafFormat = "BinXCAF";

/// The XCAF application with the binary formats defined (once per process). OCCT's application
/// is a process-wide singleton; its drivers are shared, so their use is serialised.
Handle(TDocStd_Application) BinaryApplication() {
  static std::once_flag once;
  Handle(TDocStd_Application) app = XCAFApp_Application::GetApplication();
  std::call_once(once, [&] { BinXCAFDrivers::DefineFormat(app); });
  return app;
}

std::mutex& DriverMutex() {
  static std::mutex mutex;
  return mutex;
}

Result<std::string> WriteDocument(const Handle(TDocStd_Document) & doc) {
  std::ostringstream out(std::ios::binary);
  Handle(TDocStd_Application) app = BinaryApplication();
  std::lock_guard<std::mutex> lock(DriverMutex());
  Handle(PCDM_StorageDriver) writer = app->WriterFromFormat(kXcafFormat);
  if (writer.IsNull()) return Status(StatusCode::kInternal, "OCCT has no BinXCAF writer");
  // The writer wants a document opened by an application; ours are not registered in OCCT's
  // session (see NewXcafDocument), so open this one, which registers nothing.
  if (!doc->IsOpened()) doc->Open(app);
  // The file names the document's storage format, which picks the reader; readers made by our
  // STEP and IGES loads say "MDTV-XCAF". Name BinXCAF for the write only.
  const TCollection_ExtendedString previous = doc->StorageFormat();
  doc->ChangeStorageFormat(kXcafFormat);
  writer->Write(doc, out);
  doc->ChangeStorageFormat(previous);
  if (writer->GetStoreStatus() != PCDM_SS_OK) {
    return Status(StatusCode::kIoError, "OCCT could not write the XCAF document (status " +
                                            std::to_string(writer->GetStoreStatus()) + ")");
  }
  if (!out) return Status(StatusCode::kIoError, "could not serialise the model");
  return out.str();
}

Result<ReadShape> ReadDocument(const std::string& payload) {
  std::istringstream in(payload, std::ios::binary);
  Handle(TDocStd_Application) app = BinaryApplication();
  std::lock_guard<std::mutex> lock(DriverMutex());
  Handle(Storage_Data) data;
  const TCollection_ExtendedString format = PCDM_ReadWriter::FileFormat(in, data);
  if (!(format == TCollection_ExtendedString(kXcafFormat))) {
    return Status(StatusCode::kParseError,
                  "the payload holds a '" +
                      std::string(TCollection_AsciiString(format).ToCString()) +
                      "' document, not " + kXcafFormat);
  }
  Handle(PCDM_Reader) reader = app->ReaderFromFormat(format);
  if (reader.IsNull()) return Status(StatusCode::kParseError, "no OCCT reader for the payload");
  // Read into a document of our own, not through the application's Open(): that would register
  // the document in OCCT's session for good.
  Handle(TDocStd_Document) doc = new TDocStd_Document(kXcafFormat);
  reader->Read(in, data, doc, app);
  if (reader->GetStatus() != PCDM_RS_OK) {
    return Status(StatusCode::kParseError,
                  "OCCT could not read the XCAF document (status " +
                      std::to_string(static_cast<int>(reader->GetStatus())) + ")");
  }
  ReadShape read;
  read.doc = doc;
  read.shape = FreeShapesCompound(doc);
  return read;
}

// ---------------------------------------------------------------------------------------------
// The parts of an assembly tree (ModelInfo)

std::string LabelName(const TDF_Label& label) {
  Handle(TDataStd_Name) name;
  if (!label.FindAttribute(TDataStd_Name::GetID(), name)) return "";
  return TCollection_AsciiString(name->Get()).ToCString();  // UTF-8
}

// Walks the assembly tree from `label`: counts placed leaf parts and collects part names.
void WalkParts(const TDF_Label& label, int* instances, std::vector<std::string>* names,
               std::set<std::string>* seen) {
  TDF_Label part = label;
  TDF_Label referred;
  if (XCAFDoc_ShapeTool::IsReference(label) && XCAFDoc_ShapeTool::GetReferredShape(label, referred))
    part = referred;
  if (XCAFDoc_ShapeTool::IsAssembly(part)) {
    TDF_LabelSequence components;
    XCAFDoc_ShapeTool::GetComponents(part, components);
    for (const TDF_Label& component : components) WalkParts(component, instances, names, seen);
    return;
  }
  ++*instances;
  std::string name = LabelName(part);
  if (!name.empty() && seen->insert(name).second) names->push_back(name);
}

void DocumentParts(const Handle(TDocStd_Document) & doc, int* instances,
                   std::vector<std::string>* names) {
  Handle(XCAFDoc_ShapeTool) shape_tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  TDF_LabelSequence free_labels;
  shape_tool->GetFreeShapes(free_labels);
  std::set<std::string> seen;
  for (const TDF_Label& label : free_labels) WalkParts(label, instances, names, &seen);
}

constexpr XcafApi kApi = {kXcafApiVersion, &BuildStepDocument, &WriteDocument, &ReadDocument,
                          &DocumentParts,  &WriteGlb,          &WriteObj};

}  // namespace
}  // namespace rdmesh

extern "C" __attribute__((visibility("default"))) const rdmesh::XcafApi* rdmesh_xcaf_api() {
  return &rdmesh::kApi;
}
