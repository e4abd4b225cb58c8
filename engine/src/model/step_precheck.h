#pragma once
// A scan of STEP text for what is known to crash or hang OCCT 7.6's STEP reader: faults that
// OCC_CATCH_SIGNALS does not turn into exceptions (stack overflows, a null dereference inside
// ShapeFix) and searches that never end. Internal to the engine (model_readers.cpp); a file that
// passes may still fail to read, cleanly.

#include <string>

namespace rdmesh {

/// Parentheses nested deeper than this are refused. StepData's parser recurses once per level
/// (StepData_UndefinedEntity::ReadRecord): 70000 levels overflow an 8 MiB stack, and smaller
/// thread stacks or sanitizer builds overflow sooner. Real files nest a few levels.
constexpr int kMaxStepNesting = 1000;

/// Why OCCT's STEP reader would crash on `bytes`, or "" when no known cause is present:
/// - parentheses nested deeper than kMaxStepNesting (outside strings and comments);
/// - an ORIENTED_EDGE whose edge_element is itself, or leads back to it through other
///   ORIENTED_EDGEs (StepShape_OrientedEdge::EdgeStart recurses along that chain for ever);
/// - an ORIENTED_EDGE whose edge_element is not defined in the file (a truncated file): OCCT 7.6
///   leaves such an unresolved reference as a record number (StepData_StepReaderData::
///   SetEntityNumbers), which can land on an ORIENTED_EDGE and make the same endless recursion.
///   Such a file could not transfer cleanly anyway: its edge is missing;
/// - an entity id defined twice (outside strings and comments): OCCT then resolves references
///   by the nearest record of that id, which our cycle check cannot follow, and its
///   SetEntityNumbers reads uninitialised memory on such files (valgrind). Part 21 forbids it;
/// - a CARTESIAN_POINT coordinate beyond the range of a double (1.E+999): OCCT takes it as
///   infinity, and ShapeFix_Edge::FixAddPCurve then dereferences a null curve in
///   GeomProjLib::ProjectOnPlane or searches for ever in Extrema_GenExtPS (tests/data/fuzz).
///   Infinite numbers elsewhere (directions, weights) are left to OCCT.
/// Reads the text once; no OCCT call.
std::string StepCrashReason(const std::string& bytes);

}  // namespace rdmesh
