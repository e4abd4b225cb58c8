#pragma once
// `rdmesh mesh --remote HOST:PORT`: the same run, on an rdmeshd server.

#include <string>
#include <vector>

#include "rdmesh/context.h"
#include "rdmesh/engine.h"
#include "rdmesh/options.h"
#include "rdmesh/status.h"

namespace rdmesh::cli {

/// Meshes the model file at `model_path` on the rdmeshd at `address` ("host:port") with
/// `options`: asks for the model by its sha256 and uploads the file (in 1 MiB chunks; the server
/// parses it once and caches it) only when the server answers NOT_FOUND, streams the Mesh call and
/// rebuilds the MeshResult a local MeshModel returns: every FaceMesh (with uv, normals and global
/// ids), the assembled mesh with its node classification, and the summary, so that WriteMesh writes
/// the same file.
///
/// The context's progress callback receives the server's progress. Cancel() or the context's
/// deadline cancel the call (kCancelled / kDeadlineExceeded). Server errors come back with the
/// engine code they stand for (server/wire/status_map). Credentials come from the environment:
/// RDMESH_TOKEN (or RDMESH_TOKEN_FILE) for a bearer token, RDMESH_TLS_CA (a PEM file) for TLS.
/// Every call carries the header `x-rdmesh-model: <sha256 of the file>`, on which a balancer in
/// front of several rdmeshd replicas routes (docs/ROUTING.md).
Result<MeshResult> MeshRemote(const std::string& address, const std::string& model_path,
                              const MeshOptions& options, Context* context);

/// MeshRemote with levels of detail (MeshRequest.lod_deviation_rel; `levels_rel` as
/// ResolveLevels returns them): one MeshResult per level, coarsest first, each as a local
/// MeshModel at that level returns it. Empty `levels_rel`: one result, as MeshRemote.
Result<std::vector<MeshResult>> MeshRemoteLevels(const std::string& address,
                                                 const std::string& model_path,
                                                 const MeshOptions& options,
                                                 const std::vector<double>& levels_rel,
                                                 Context* context);

}  // namespace rdmesh::cli
