"""Welding per-face meshes into one watertight mesh through their global node ids."""

import numpy as np


def assemble(faces, node_count=None, triangle_deviation=False):
    """Assembles faces into one mesh.

    faces: FaceResult objects (or anything with face_id, status, xyz (n, 3), triangles (m, 3)
        face-local node ids and global_ids (n,)), in any order; faces whose status is not "ok" or
        that have no triangles are left out.
    node_count: the run's node count (Summary.nodes); global ids are 0..node_count-1.

    Returns (xyz, triangles, triangle_face):
        xyz            (N, 3) float64, model units: one row per node used by the faces
        triangles      (T, 3) int64, 0-based rows of xyz, face order, each face's own order
        triangle_face  (T,)   int32, the B-rep face id of each triangle

    With triangle_deviation, a fourth array follows: (T,) float64, each assembled triangle's
    estimated deviation (FaceResult.triangle_deviation), or None unless every face has one per
    triangle.

    A node shared by several faces (a boundary node) has one global id and appears once. When
    every global id 0..node_count-1 is used, row i of xyz is global node i, and the arrays equal
    the engine's own assembled mesh: triangles that collapse (two equal global ids, at a pole)
    are left out as the engine does. Faces without global ids get nodes of their own, so the
    result is then not welded.
    """
    faces = sorted((f for f in faces if f.status == "ok" and len(f.triangles)),
                   key=lambda f: f.face_id)
    ids = [np.asarray(f.global_ids, dtype=np.int64) for f in faces]
    known = [i for i in ids if len(i)]
    top = max([node_count or 0] + [int(i.max()) + 1 for i in known if len(i)])
    # Faces without ids get fresh ids above every known one.
    next_id = top
    for k, f in enumerate(faces):
        if len(ids[k]) != len(f.xyz):
            ids[k] = np.arange(next_id, next_id + len(f.xyz), dtype=np.int64)
            next_id += len(f.xyz)
    total = next_id
    xyz = np.zeros((total, 3), dtype=np.float64)
    used = np.zeros(total, dtype=bool)
    for k, f in enumerate(faces):
        xyz[ids[k]] = f.xyz
        used[ids[k]] = True
    # Compact: drop ids that no assembled face uses (a face subset, failed faces).
    remap = np.cumsum(used, dtype=np.int64) - 1
    deviations = [getattr(f, "triangle_deviation", None) for f in faces]
    with_deviation = triangle_deviation and all(
        d is not None and len(d) == len(f.triangles) for d, f in zip(deviations, faces))
    if not faces:
        empty = (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int32))
        return empty + (np.zeros(0),) if triangle_deviation else empty
    triangles, triangle_face, deviation = [], [], []
    for k, f in enumerate(faces):
        tri = ids[k][np.asarray(f.triangles, dtype=np.int64).reshape(-1, 3)]
        keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])
        triangles.append(remap[tri[keep]])
        triangle_face.append(np.full(int(keep.sum()), f.face_id, dtype=np.int32))
        if with_deviation:
            deviation.append(np.asarray(deviations[k], dtype=np.float64)[keep])
    result = (xyz[used], np.concatenate(triangles), np.concatenate(triangle_face))
    if triangle_deviation:
        return result + (np.concatenate(deviation) if with_deviation else None,)
    return result
