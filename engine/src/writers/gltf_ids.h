#pragma once
// Picking ids and edge lines for a .glb that OCCT's RWGltf_CafWriter wrote.

#include <string>
#include <vector>

#include "model/model.h"
#include "rdmesh/mesh.h"
#include "rdmesh/status.h"

namespace rdmesh {

/// Rewrites the .glb at `path`, written from triangulations lent with uv_face_ids (each vertex's
/// TEXCOORD_0 is (face id, 0)):
/// - every triangle primitive's TEXCOORD_0 becomes `_FACE_ID`, one float per vertex: the B-rep
///   face id (1..F) of the face the vertex belongs to (glTF vertices are per face, so each
///   triangle's three vertices carry its face id). An instanced part's mesh carries the face
///   ids of the instance it was lent from; every node that draws it at another instance gets
///   extras.rdmesh.face_ids, an object mapping those ids (as strings) to its own face ids;
/// - when `edges` is not empty, a root node "edges" (model units to metres, +Z up to +Y up, as
///   the faces) with one child node per solid (and one for edges of faces in no solid), each
///   with a mesh of one LINES primitive: every edge line that is not degenerate, in edge id
///   order, as segments over vertices of its own, each with `_EDGE_ID` (a float: the edge id
///   1..E). The primitive's extras list its edges with their faces and seam / sharp flags.
/// The root's `extras.rdmesh` explains both attributes. With `compress`, CompressGlb
/// (gltf_compress.h) then compresses the file, rounding positions by at most
/// kCompressRoundingShare of the result's requested deviation. kIoError naming the path on
/// failure.
Status AddGltfIdsAndEdges(const Model& model, const MeshResult& result,
                          const std::vector<EdgeLine>& edges, bool compress,
                          const std::string& path);

}  // namespace rdmesh
