"""The rdmesh client: upload, describe and mesh models on an rdmeshd server."""

import hashlib
import os
import re
from dataclasses import dataclass
from typing import Callable, Dict, Iterator, List, Optional

import grpc
import numpy as np

from rdmesh import _health
from rdmesh.assemble import assemble
from rdmesh.v1 import rdmesh_pb2 as pb
from rdmesh.v1 import rdmesh_pb2_grpc as pb_grpc

CHUNK_BYTES = 1 << 20
# Request header naming the model a call is about (its sha256, the server's model id), sent on
# every call for a model so that an L7 balancer can route by model (docs/ROUTING.md).
MODEL_HEADER = "x-rdmesh-model"
_MODEL_ID = re.compile(r"^[0-9a-f]{64}$")
_OPTION_NAMES = {"max_deviation", "max_deviation_rel", "rd_tolerance", "max_triangles",
                 "min_edge_length", "max_edge_length", "nurbs", "threads", "face_ids",
                 "timeout_seconds", "sharp_edge_angle", "compress", "off_surface"}
_STAGES = {pb.STAGE_LOADING: "loading", pb.STAGE_EDGES: "edges", pb.STAGE_FACES: "faces",
           pb.STAGE_ASSEMBLY: "assembly", pb.STAGE_DONE: "done"}
_FACE_STATUS = {pb.FACE_STATUS_OK: "ok", pb.FACE_STATUS_FAILED: "failed",
                pb.FACE_STATUS_SKIPPED: "skipped"}


class RdmeshError(Exception):
    """A failed call: `code` is the grpc.StatusCode, `details` the server's message."""

    def __init__(self, code, details):
        super().__init__("%s: %s" % (code.name if code else "UNKNOWN", details))
        self.code = code
        self.details = details

    @classmethod
    def wrap(cls, error):
        return cls(error.code(), error.details())


@dataclass
class Progress:
    """Where a run is: stage ("edges", "faces", ...) and how many of `total` are done."""
    stage: str
    done: int
    total: int


@dataclass
class FaceResult:
    """The mesh of one B-rep face. Lengths in model units."""
    face_id: int
    surface_type: str
    status: str  # "ok", "failed" or "skipped"
    reason: str
    xyz: np.ndarray  # (n, 3) float64
    triangles: np.ndarray  # (m, 3) int32, face-local node ids, counter-clockwise from outside
    global_ids: np.ndarray  # (n,) int64, node ids in the assembled mesh (empty unless ok)
    uv: Optional[np.ndarray] = None  # (n, 2) float64, when asked for
    normals: Optional[np.ndarray] = None  # (n, 3) float64, when asked for
    # (m,) float64, when asked for: each triangle's estimated distance to the exact surface,
    # model units (its maximum is max_deviation)
    triangle_deviation: Optional[np.ndarray] = None
    max_deviation: float = 0.0
    area: float = 0.0
    exact_area: float = 0.0
    seconds: float = 0.0
    messages: int = 1  # FaceMesh events it came in
    # off_surface: how far the interior nodes lie off the surface along its outward normal,
    # model units (0 on it), and why a face stayed on its surface
    offset: float = 0.0
    offset_reason: str = ""


@dataclass
class Edges:
    """The B-rep edges of the assembled mesh as polylines (EdgePolyline events), in edge id
    order, as flat numpy arrays: edge i's node ids are nodes[offsets[i]:offsets[i + 1]] (rows of
    MeshResult.xyz, in curve order) and its faces face_ids[face_offsets[i]:face_offsets[i + 1]]."""
    edge_id: np.ndarray  # (E,) int32, 1..ModelInfo.edges
    offsets: np.ndarray  # (E + 1,) int64 into nodes
    nodes: np.ndarray  # (K,) int64, node ids of the assembled mesh
    face_offsets: np.ndarray  # (E + 1,) int64 into face_ids
    face_ids: np.ndarray  # (M,) int32, the faces each edge bounds, ascending
    seam: np.ndarray  # (E,) bool: a face lies on both sides
    degenerate: np.ndarray  # (E,) bool: no extent in 3D
    sharp: np.ndarray  # (E,) bool: dihedral over sharp_edge_angle, or a free edge
    dihedral: np.ndarray  # (E,) float64 degrees: largest over the nodes; -1 undefined

    def __len__(self):
        return len(self.edge_id)

    def polyline(self, i):
        """Node ids of the i-th edge (not the edge id), in curve order."""
        return self.nodes[self.offsets[i]:self.offsets[i + 1]]

    def faces(self, i):
        """Face ids beside the i-th edge."""
        return self.face_ids[self.face_offsets[i]:self.face_offsets[i + 1]]


class _EdgeParts:
    """Collects EdgePolyline events (in edge id order, parts in order) into Edges."""

    def __init__(self):
        self.first, self.nodes, self.left = [], [], 0

    def add(self, part):
        if part.chunk_index == 0:
            if self.left or (self.first and part.edge_id <= self.first[-1].edge_id):
                raise RdmeshError(grpc.StatusCode.INTERNAL,
                                  "edge %d arrived out of order" % part.edge_id)
            self.first.append(part)
            self.nodes.append([])
            self.left = part.chunk_count
        elif not self.left or part.edge_id != self.first[-1].edge_id:
            raise RdmeshError(grpc.StatusCode.INTERNAL,
                              "edge %d: part %d arrived out of order"
                              % (part.edge_id, part.chunk_index))
        self.nodes[-1].append(np.array(part.nodes, dtype=np.int64))
        self.left -= 1

    def result(self):
        if self.left:
            raise RdmeshError(grpc.StatusCode.INTERNAL, "an edge is missing parts")
        nodes = [np.concatenate(n) if n else np.zeros(0, np.int64) for n in self.nodes]
        counts = [len(n) for n in nodes]
        face_counts = [len(p.faces) for p in self.first]
        return Edges(
            edge_id=np.array([p.edge_id for p in self.first], dtype=np.int32),
            offsets=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
            nodes=np.concatenate(nodes) if nodes else np.zeros(0, np.int64),
            face_offsets=np.concatenate([[0], np.cumsum(face_counts)]).astype(np.int64),
            face_ids=np.array([f for p in self.first for f in p.faces], dtype=np.int32),
            seam=np.array([p.seam for p in self.first], dtype=bool),
            degenerate=np.array([p.degenerate for p in self.first], dtype=bool),
            sharp=np.array([p.sharp for p in self.first], dtype=bool),
            dihedral=np.array([p.dihedral for p in self.first], dtype=np.float64))


@dataclass
class MeshResult:
    """A finished run: per-face meshes and the assembled watertight mesh."""
    model: "pb.ModelInfo"
    options: "pb.ResolvedOptions"
    summary: "pb.Summary"
    faces: List[FaceResult]  # face id order
    xyz: np.ndarray  # (N, 3) float64, model units
    triangles: np.ndarray  # (T, 3) int64 rows of xyz
    triangle_face: np.ndarray  # (T,) int32 B-rep face id per triangle
    job_id: str = ""
    largest_message: int = 0  # bytes of the largest event received
    edges: Optional[Edges] = None  # when asked for (mesh(..., edges=True))
    # (T,) float64 per assembled triangle, when asked for (mesh(..., triangle_deviation=True)):
    # the engine's estimated triangle-surface distance, model units
    triangle_deviation: Optional[np.ndarray] = None
    level: int = 0  # the level of detail (mesh_levels(); 0 coarsest), 0 for mesh()
    max_deviation_rel: Optional[float] = None  # the level's relative deviation (mesh_levels())

    @property
    def triangle_count(self):
        return len(self.triangles)


class _FaceParts:
    """Collects the FaceMesh events of one face."""

    def __init__(self, first):
        self.first = first
        self.xyz, self.uv, self.normals, self.triangles = [], [], [], []
        self.deviation = []
        self.count = 0

    def add(self, part):
        if part.chunk_index != self.count:
            raise RdmeshError(grpc.StatusCode.INTERNAL, "face %d: part %d arrived out of order"
                              % (part.face_id, part.chunk_index))
        self.count += 1
        self.xyz.append(np.array(part.xyz, dtype=np.float64))
        self.uv.append(np.array(part.uv, dtype=np.float64))
        self.normals.append(np.array(part.normals, dtype=np.float64))
        self.triangles.append(np.array(part.triangles, dtype=np.int32))
        self.deviation.append(np.array(part.triangle_deviation, dtype=np.float64))
        return self.count == part.chunk_count

    def result(self):
        f = self.first
        uv = np.concatenate(self.uv).reshape(-1, 2)
        normals = np.concatenate(self.normals).reshape(-1, 3)
        triangles = np.concatenate(self.triangles).reshape(-1, 3)
        deviation = np.concatenate(self.deviation)
        return FaceResult(
            face_id=f.face_id, surface_type=f.surface_type,
            status=_FACE_STATUS.get(f.status, "unspecified"), reason=f.reason,
            xyz=np.concatenate(self.xyz).reshape(-1, 3),
            triangles=triangles,
            global_ids=np.zeros(0, dtype=np.int64), uv=uv if len(uv) else None,
            normals=normals if len(normals) else None,
            triangle_deviation=deviation if len(triangles) and len(deviation) == len(triangles)
            else None, max_deviation=f.max_deviation,
            area=f.area, exact_area=f.exact_area, seconds=f.seconds, messages=self.count,
            offset=f.offset, offset_reason=f.offset_reason)


@dataclass
class _Model:
    """A model a call is about: the ModelRef to send, its routing key (the sha256 of its bytes,
    None for a server-side path) and, when this client can upload it, the local file or bytes."""
    ref: "pb.ModelRef"
    key: Optional[str]
    path: Optional[str] = None
    data: Optional[bytes] = None


def model_key(data) -> str:
    """The model id of a model file's bytes: its sha256, 64 lower-case hex digits."""
    return hashlib.sha256(data).hexdigest()


class Client:
    """A connection to rdmeshd, or to a balancer in front of several (docs/ROUTING.md).

    address: "host:port". token: the server's bearer token (--token-file), if it has one.
    root_certificates: PEM bytes of the CA that signed the server's --tls-cert; TLS is used when
    given. request_id: sent as x-request-id so that the server's log lines carry it.

    Every call for a model carries an `x-rdmesh-model: <sha256>` header. mesh() and info() of a
    local file ask for the model by its id first and upload it only when the server answers
    NOT_FOUND (a new model, an evicted one, or one that lived on a replica that is gone); a model
    id this client uploaded from a file is uploaded again from that file in the same case.
    """

    def __init__(self, address, token=None, root_certificates=None, request_id=None):
        options = [("grpc.max_receive_message_length", 64 << 20),
                   ("grpc.max_send_message_length", 64 << 20)]
        if root_certificates:
            credentials = grpc.ssl_channel_credentials(root_certificates=root_certificates)
            self._channel = grpc.secure_channel(address, credentials, options=options)
        else:
            self._channel = grpc.insecure_channel(address, options=options)
        self._stub = pb_grpc.RdmeshStub(self._channel)
        self._metadata = []
        self._uploaded_paths: Dict[str, str] = {}  # model id -> file it was uploaded from
        if token:
            self._metadata.append(("authorization", "Bearer " + token))
        if request_id:
            self._metadata.append(("x-request-id", request_id))
        self._health = self._channel.unary_unary(
            _health.CHECK_METHOD,
            request_serializer=_health.HealthCheckRequest.SerializeToString,
            response_deserializer=_health.HealthCheckResponse.FromString)

    def close(self):
        self._channel.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- calls -----------------------------------------------------------------------------

    def health(self, service="", timeout=5.0):
        """The server's serving status name: "SERVING", "NOT_SERVING", ..."""
        try:
            response = self._health(_health.HealthCheckRequest(service=service), timeout=timeout)
        except grpc.RpcError as error:
            raise RdmeshError.wrap(error) from None
        return _health.status_name(response)

    def server_status(self, timeout=5.0):
        """The server's ServerStatus (jobs running and queued, cache, limits)."""
        return self._call(self._stub.GetServerStatus, pb.GetServerStatusRequest(), timeout)

    def upload(self, path_or_bytes, name=None, timeout=None, chunk_bytes=CHUNK_BYTES):
        """Uploads a model file (a path, or the bytes themselves) in ~1 MiB chunks and returns
        its ModelInfo; ModelInfo.model_id names it in later calls."""
        path = None
        if isinstance(path_or_bytes, (bytes, bytearray, memoryview)):
            data = bytes(path_or_bytes)
            name = name or "upload"
        else:
            path = os.fspath(path_or_bytes)
            with open(path, "rb") as file:
                data = file.read()
            name = name or os.path.basename(path)
        return self._upload(data, name, model_key(data), path, timeout, chunk_bytes)

    def info(self, model, timeout=None):
        """ModelInfo of a model: a ModelInfo, a model id, a local file (uploaded when the server
        does not hold it) or a ModelRef."""
        return self._with_model(
            model, lambda m: self._call(self._stub.GetModelInfo, m.ref, timeout, m.key), timeout)

    def mesh_stream(self, model, uv=False, normals=False, timeout=None, edges=False,
                    triangle_deviation=False, lod=None, **options):
        """The raw Mesh call: an iterator of MeshEvent messages that also has cancel(). A local
        file is uploaded first (a stream cannot be retried after NOT_FOUND). `lod`: relative
        deviations of levels of detail (MeshRequest.lod_deviation_rel)."""
        m = self._model(model)
        if m.data is not None:
            self._upload_model(m, timeout)
        return self._mesh_call(m, uv, normals, timeout, options, edges,
                               triangle_deviation, lod)

    def mesh_levels(self, model, lod, progress: Optional[Callable[[Progress], None]] = None,
                    level_done: Optional[Callable[["MeshResult"], None]] = None, uv=False,
                    normals=False, timeout=None, edges=False, triangle_deviation=False,
                    **options) -> List["MeshResult"]:
        """Levels of detail in one call: `lod` holds relative deviations (fractions of the bbox
        diagonal, as max_deviation_rel, in any order, at most 8). The server reads the model
        once and meshes it once per level, coarsest first; each level is a whole watertight
        mesh equal to mesh(model, max_deviation_rel=level, **options). Returns the levels'
        MeshResults, coarsest first (MeshResult.level, .max_deviation_rel); `level_done` is
        called with each one as soon as its last event arrives, so a viewer can show the coarse
        mesh while the finer ones are meshed. Other arguments as mesh() (no max_deviation,
        max_deviation_rel or max_triangles)."""
        mesh_options(**options)
        lod = [float(v) for v in lod]
        if not lod:
            raise ValueError("lod: give at least one relative deviation")
        results = self._with_model(
            model, lambda m: self._collect_levels(
                self._mesh_call(m, uv, normals, timeout, options, edges, triangle_deviation,
                                lod), progress, edges,
                level_done), timeout)
        if len(results) != len(lod):
            raise RdmeshError(grpc.StatusCode.INTERNAL, "%d levels asked for, %d received"
                              % (len(lod), len(results)))
        return results

    def mesh(self, model, progress: Optional[Callable[[Progress], None]] = None, uv=False,
             normals=False, timeout=None, edges=False, triangle_deviation=False,
             **options) -> MeshResult:
        """Meshes a model (see info() for what `model` may be) and returns per-face numpy arrays
        plus the assembled watertight mesh. Options are those of MeshOptions:
        max_deviation, max_deviation_rel, rd_tolerance, max_triangles, min_edge_length,
        max_edge_length, nurbs, threads, face_ids, timeout_seconds, sharp_edge_angle, compress
        (the mesh is for a compressed .glb: meshed to 98.5% of the deviation, leaving the rest to
        the writer's rounding of positions, as `rdmesh mesh --compress` asks; the summary's
        requested deviation stays the whole one), off_surface (nodes off the surface, triangles
        on both sides of it within the deviation, as `rdmesh mesh --off-surface`: FaceResult
        offset and offset_reason say how far and why not). `progress` is called with a Progress as the run advances. `timeout` is the call's
        deadline in seconds. With `edges`, MeshResult.edges holds every B-rep edge as a
        polyline over the assembled mesh's nodes (Edges). With `triangle_deviation`, every
        FaceResult and the MeshResult carry each triangle's estimated deviation."""
        mesh_options(**options)  # unknown options fail before any call
        return self._with_model(
            model, lambda m: self._collect(
                self._mesh_call(m, uv, normals, timeout, options, edges, triangle_deviation),
                progress, edges), timeout)

    def batch(self, inputs, output_dir, format="msh", jobs=4, timeout=None, progress=None,
              problem=None, **options):
        """Meshes a dataset through the server, as `rdmesh-py batch` (docs/BATCH.md, "Through
        the service"): `inputs` are files, folders (searched for .step .stp .iges .igs .brep)
        and "@list.txt" files; the meshes mirror them under `output_dir` in `format` (msh, stl,
        obj, ply or vtu), and output_dir/manifest.jsonl records every file (the C++ `rdmesh
        batch`'s fields and statuses). `jobs` calls are in flight at a time (one thread each),
        each file is uploaded at most once, `timeout` is per file (seconds, upload and mesh
        together). A second run skips the files already ok with the same bytes, options and
        output. `progress` gets a batch.BatchProgress now and then, `problem` a line per file
        that was not ok; options are mesh()'s. Returns a batch.BatchSummary (exit_code: 0 when
        every file is ok, 1 otherwise); raises batch.BatchError for bad usage."""
        from rdmesh.batch import Batch
        return Batch(self, inputs, output_dir, format=format, jobs=jobs, timeout=timeout,
                     progress=progress, problem=problem, **options).run()

    # -- helpers ---------------------------------------------------------------------------

    def _collect(self, call, progress, edges=False):
        """Reads a Mesh stream into a MeshResult."""
        results = self._collect_levels(call, progress, edges, None, levels=False)
        return results[0]

    def _collect_levels(self, call, progress, edges, level_done, levels=True):
        """Reads a Mesh stream into MeshResults: one, or one per level of detail (LevelStarted
        events), each finished when its Summary arrives."""
        started = None
        results = []
        level = _LevelEvents(progress)
        largest = 0
        try:
            for event in call:
                largest = max(largest, event.ByteSize())
                kind = event.WhichOneof("event")
                if kind == "started":
                    started = event.started
                elif kind == "level_started":
                    if (event.level_started.level != len(results) or level.summary is not None
                            or level.parts or level.faces):
                        raise RdmeshError(grpc.StatusCode.INTERNAL,
                                          "level %d arrived out of order"
                                          % event.level_started.level)
                    level.info = event.level_started
                elif kind == "summary":
                    level.summary = event.summary
                    if levels:
                        result = level.result(started, edges, largest)
                        results.append(result)
                        if level_done:
                            level_done(result)
                        level = _LevelEvents(progress)
                else:
                    level.add(kind, event, started)
        except grpc.RpcError as error:
            raise RdmeshError.wrap(error) from None
        if not levels:
            return [level.result(started, edges, largest)]
        if not results or level.parts or level.faces or level.info is not None:
            raise RdmeshError(grpc.StatusCode.INTERNAL, "the Mesh stream ended early")
        return results

    def _metadata_for(self, key):
        return self._metadata + [(MODEL_HEADER, key)] if key else self._metadata

    def _call(self, method, request, timeout, key=None):
        try:
            return method(request, timeout=timeout, metadata=self._metadata_for(key))
        except grpc.RpcError as error:
            raise RdmeshError.wrap(error) from None

    def _mesh_call(self, m, uv, normals, timeout, options, edges=False, triangle_deviation=False,
                   lod=None):
        fields = pb.ReturnFields(uv=uv, normals=normals, edges=edges,
                                 triangle_deviation=triangle_deviation)
        request = pb.MeshRequest(model=m.ref, options=mesh_options(**options),
                                 return_fields=fields, lod_deviation_rel=lod or [])
        return self._stub.Mesh(request, timeout=timeout, metadata=self._metadata_for(m.key))

    def _upload(self, data, name, key, path, timeout, chunk_bytes=CHUNK_BYTES):
        def chunks():
            yield pb.ModelChunk(data=data[:chunk_bytes], name=name, total_bytes=len(data))
            for start in range(chunk_bytes, len(data), chunk_bytes):
                yield pb.ModelChunk(data=data[start:start + chunk_bytes])

        info = self._call(self._stub.UploadModel, chunks(), timeout, key)
        if path is not None and info.model_id == key:
            self._uploaded_paths[key] = path
        return info

    def _upload_model(self, m, timeout):
        """Uploads a model this client has the bytes of (or the file it was uploaded from)."""
        data = m.data
        if data is None:
            with open(m.path, "rb") as file:
                data = file.read()
            if model_key(data) != m.key:
                raise RdmeshError(grpc.StatusCode.NOT_FOUND,
                                  "model %s is not on the server, and '%s' it was uploaded from "
                                  "has changed since" % (m.key, m.path))
        name = os.path.basename(m.path) if m.path is not None else "upload"
        return self._upload(data, name, m.key, m.path, timeout)

    def _with_model(self, model, call, timeout):
        """call(_Model) for `model`; when the server does not hold a model this client can
        upload (NOT_FOUND), uploads it and calls once more."""
        m = self._model(model)
        try:
            return call(m)
        except RdmeshError as error:
            if error.code != grpc.StatusCode.NOT_FOUND or (m.path is None and m.data is None):
                raise
        self._upload_model(m, timeout)
        return call(m)

    def _model(self, model) -> _Model:
        """What `model` is, without any call: a ModelRef, a ModelInfo, a model id, a local file or
        the bytes of one."""
        if isinstance(model, pb.ModelInfo):
            model = model.model_id
        if isinstance(model, pb.ModelRef):
            kind = model.WhichOneof("source")
            if kind == "model_id":
                return _Model(model, model.model_id, self._uploaded_paths.get(model.model_id))
            if kind == "inline_model":
                return _Model(model, model_key(model.inline_model.data))
            return _Model(model, None)  # a server-side path: its bytes are not known here
        if isinstance(model, str) and _MODEL_ID.match(model) and not os.path.exists(model):
            return _Model(pb.ModelRef(model_id=model), model, self._uploaded_paths.get(model))
        if isinstance(model, (bytes, bytearray)):
            data = bytes(model)
            return _Model(pb.ModelRef(model_id=model_key(data)), model_key(data), data=data)
        if isinstance(model, (str, os.PathLike)):
            path = os.fspath(model)
            with open(path, "rb") as file:
                data = file.read()
            key = model_key(data)
            return _Model(pb.ModelRef(model_id=key), key, path=path, data=data)
        raise TypeError("model must be a path, bytes, a model id, a ModelInfo or a ModelRef")


class _LevelEvents:
    """The events of one mesh (one level of detail, or the only mesh) until its Summary."""

    def __init__(self, progress):
        self.progress = progress
        self.edge_parts = _EdgeParts()
        self.parts: Dict[int, _FaceParts] = {}
        self.faces: Dict[int, FaceResult] = {}
        self.ids: Dict[int, list] = {}
        self.faces_done = 0
        self.info = None  # LevelStarted
        self.summary = None

    def add(self, kind, event, started):
        progress = self.progress
        if kind == "progress" and progress:
            p = event.progress
            stage = _STAGES.get(p.stage, "unspecified")
            if stage == "faces":
                self.faces_done = max(self.faces_done, p.done)
                progress(Progress(stage, self.faces_done, p.total))
            else:
                progress(Progress(stage, p.done, p.total))
        elif kind == "face":
            part = event.face
            collector = self.parts.setdefault(part.face_id, _FaceParts(part))
            if collector.add(part):
                self.faces[part.face_id] = self.parts.pop(part.face_id).result()
                if progress and started is not None:
                    self.faces_done = max(self.faces_done, len(self.faces))
                    progress(Progress("faces", self.faces_done, started.faces_requested))
        elif kind == "node_ids":
            chunk = event.node_ids
            self.ids.setdefault(chunk.face_id, []).append(
                np.array(chunk.global_ids, dtype=np.int64))
        elif kind == "edge":
            self.edge_parts.add(event.edge)

    def result(self, started, edges, largest):
        summary = self.summary
        if started is None or summary is None or self.parts:
            raise RdmeshError(grpc.StatusCode.INTERNAL, "the Mesh stream ended early")
        ordered = [self.faces[k] for k in sorted(self.faces)]
        for face in ordered:
            if face.face_id in self.ids:
                face.global_ids = np.concatenate(self.ids[face.face_id])
            if face.status == "ok" and len(face.global_ids) != len(face.xyz):
                raise RdmeshError(grpc.StatusCode.INTERNAL,
                                  "face %d: %d global ids for %d nodes"
                                  % (face.face_id, len(face.global_ids), len(face.xyz)))
        xyz, triangles, triangle_face, deviation = assemble(ordered, summary.nodes, True)
        info = self.info
        return MeshResult(model=started.model, options=started.options, summary=summary,
                          faces=ordered, xyz=xyz, triangles=triangles,
                          triangle_face=triangle_face, job_id=started.job_id,
                          largest_message=largest,
                          edges=self.edge_parts.result() if edges else None,
                          triangle_deviation=deviation,
                          level=info.level if info is not None else 0,
                          max_deviation_rel=info.max_deviation_rel if info is not None else None)


def mesh_options(**options) -> "pb.MeshOptions":
    """A MeshOptions message from keyword arguments (None values are left unset)."""
    unknown = set(options) - _OPTION_NAMES
    if unknown:
        raise TypeError("unknown mesh option(s): %s (known: %s)"
                        % (", ".join(sorted(unknown)), ", ".join(sorted(_OPTION_NAMES))))
    message = pb.MeshOptions()
    for key, value in options.items():
        if value is None:
            continue
        if key == "face_ids":
            message.face_ids.extend(int(v) for v in value)
        else:
            setattr(message, key, value)
    return message


def iter_faces(events: Iterator) -> Iterator[FaceResult]:
    """Yields each face of a raw Mesh event stream as soon as its last part arrives (without
    global ids: those come in node_ids events once the faces are welded)."""
    parts: Dict[int, _FaceParts] = {}
    for event in events:
        if event.WhichOneof("event") == "face":
            collector = parts.setdefault(event.face.face_id, _FaceParts(event.face))
            if collector.add(event.face):
                yield parts.pop(event.face.face_id).result()
