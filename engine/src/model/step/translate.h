#pragma once
// A parsed STEP file (part21.h) translated into what OCCT 7.6's STEPCAFControl_Reader gives the
// engine (model/read_shape.h): the B-rep, scaled to millimetres, healed with the same ShapeFix
// calls and settings as OCCT's reader, and an XCAF document with the same assembly structure,
// names and colours (built from document_plan.h's plan where the run keeps a document). The
// B-rep's faces, edges, surfaces and parameterisations are those OCCT builds (the same Geom
// objects from the same numbers, the same edge and vertex sharing), so a file this translates
// meshes as it does through OCCT. Solids are healed in parallel.
//
// What it covers: the geometry and topology of advanced B-reps (MANIFOLD_SOLID_BREP,
// BREP_WITH_VOIDS, SHELL_BASED_SURFACE_MODEL), SI and conversion-based length units, products,
// assemblies (NEXT_ASSEMBLY_USAGE_OCCURRENCE with CONTEXT_DEPENDENT_SHAPE_REPRESENTATION),
// MAPPED_ITEM, shape representation relationships, names and surface colours. Anything else in a
// shape representation, and anything OCCT would treat in a way this does not reproduce (a curve
// it cannot build, a face it would drop), makes the file unsupported: the caller reads it with
// OCCT instead. Not reproduced, and so not in the document: layers, validation properties, GD&T,
// materials, saved views, SHUO styles, external references (OCCT's reader reads them; the engine
// uses none of them).
#include <string>
#include <utility>
#include <vector>

#include "model/read_shape.h"
#include "model/step/part21.h"
#include "rdmesh/context.h"
#include "rdmesh/status.h"

namespace rdmesh::step {

struct TranslateOptions {
  int threads = 0;  ///< worker threads for healing and face work; 0 = all cores
};

struct Translated {
  /// False when the file holds something this translator does not reproduce; `read` is then
  /// empty and the caller reads the file with OCCT.
  bool supported = false;
  /// When unsupported: the first construct not handled, e.g. "#123 OFFSET_CURVE_3D".
  std::string unsupported;
  ReadShape read;
  /// Wall seconds of each stage, in order ("index", "structure", "build", "heal faces", ...).
  std::vector<std::pair<std::string, double>> stage_seconds;
  /// B-rep items (solids, shells) translated, and how many were healed face by face in
  /// parallel; the others are healed whole, as OCCT heals them (`heal_note` says why, for one).
  int items = 0;
  int items_healed_by_face = 0;
  /// Items healed face by face where a face's fixing cut a shared edge's range (the faces
  /// after it fixed again, `faces_fixed_again` in all, with the edges as OCCT's run leaves them).
  int items_in_order = 0;
  int faces_fixed_again = 0;
  std::string heal_note;
};

/// Translates `file`. kParseError naming the entity (e.g. "#12 EDGE_CURVE refers to #40, which
/// is not in the file") when the file is broken where OCCT's reader would refuse it too (a
/// dangling reference from geometry or topology, a reference cycle, a file with no shapes);
/// supported = false (never an error) for what it does not handle; the context's StopStatus()
/// when stopped. Untrusted input: memory bounded by the file's size; OCCT's healing can fault
/// on broken geometry (as in OCCT's own reader), so callers install OCCT's fault handlers
/// (OSD::SetSignal, as model_readers' ScopedOcctFaultHandlers does): a fault then ends as
/// OCCT's reader would end it, or as supported = false, never a crash. Not
/// thread-safe with OCCT's own STEP reader only where OCCT's healing shares globals, which this
/// initialises before going parallel: callers may run it alongside other engine work.
Result<Translated> TranslateStep(const File& file, const TranslateOptions& options,
                                 const Context* context);

}  // namespace rdmesh::step
