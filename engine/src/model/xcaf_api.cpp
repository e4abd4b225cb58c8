#include "model/xcaf_api.h"

#include "model/engine_module.h"

// Defined when the document framework is linked in (rdmesh_engine, xcaf_document.cpp); null in a
// program linked to rdmesh_engine_lean, which loads it from the module instead.
extern "C" const rdmesh::XcafApi* rdmesh_xcaf_api() __attribute__((weak));

namespace rdmesh {
namespace {

Result<const XcafApi*> LoadXcaf() {
  if (rdmesh_xcaf_api != nullptr) return rdmesh_xcaf_api();
  Result<const void*> module = LoadEngineModule("rdmesh_occt_xcaf.so", "rdmesh_xcaf_api",
                                                "OCCT's document framework", kXcafApiVersion);
  if (!module.ok()) return module.status();
  return static_cast<const XcafApi*>(*module);
}

}  // namespace

Result<const XcafApi*> Xcaf() {
  static const Result<const XcafApi*> loaded = LoadXcaf();
  return loaded;
}

}  // namespace rdmesh
