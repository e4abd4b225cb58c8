#pragma once
// The compressed .glb (WriteOptions::compress): EXT_meshopt_compression with
// KHR_mesh_quantization, through meshoptimizer. docs/GLB.md describes the layout.

#include <nlohmann/json.hpp>
#include <string>

#include "model/model.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Rewrites a .glb as AddGltfIdsAndEdges makes it (its JSON `json` and binary chunk `bin`) so
/// that every buffer view is meshopt-compressed into `bin`, behind a fallback buffer with no
/// data (both extensions required):
/// - triangle primitives: triangle and vertex order optimised for the GPU's vertex cache and
///   fetch (meshopt_optimizeVertexCache, meshopt_optimizeVertexFetchRemap);
/// - POSITION rounded to a grid, in the mesh's own frame, fine enough that no
///   vertex moves farther than `max_shift` (glTF world units, metres) through its nodes'
///   transforms: 16-bit integers scaled by their node (PlaceGrids) when they fit, else floats of a
///   power-of-two grid (the EXPONENTIAL filter, exact); `max_shift` 0 keeps the floats;
/// - NORMAL octahedral-encoded (the OCTAHEDRAL filter, 10 bits in 16-bit integers);
/// - _FACE_ID and _EDGE_ID 16-bit integers when the ids fit;
/// - each LINES primitive's edge table (extras.edges) as four binary accessors when that is
///   smaller than its JSON;
/// - meshes that OCCT wrote once per instance written once; the solids' edge lines one mesh;
/// - per face its surface type, and per triangle its estimated deviation when `result`'s faces
///   carry it, in binary accessors named by extras.
/// Every rounded position is decoded again and checked against `max_shift` (kInternal when
/// one is off). kIoError naming `path` when the .glb is not laid out as expected.
Status CompressGlb(const Model& model, const MeshResult& result, double max_shift,
                   const std::string& path, nlohmann::ordered_json* json, std::string* bin);

}  // namespace rdmesh
