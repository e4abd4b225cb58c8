"""MSH 4.1 ASCII output with one surface entity per B-rep face.

meshio 5's gmsh 4.1 writer puts every node in one entity and lists only one surface when a mesh
has several cell blocks (its own reader then fails on the file), so .msh files are written here;
every other format goes through meshio.
"""

import numpy as np


def write_msh41(path, xyz, triangles, triangle_face):
    """Writes an MSH 4.1 ASCII file.

    xyz (N, 3) float64 node coordinates; triangles (T, 3) 0-based node rows; triangle_face (T,)
    the B-rep face id of each triangle, which becomes the tag of its surface entity (dim 2). A
    node belongs to the entity of the first face (lowest id) that uses it; node tags are row + 1.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    triangle_face = np.asarray(triangle_face, dtype=np.int64)
    order = np.argsort(triangle_face, kind="stable")
    triangles, triangle_face = triangles[order], triangle_face[order]
    face_ids, starts = np.unique(triangle_face, return_index=True)
    ends = list(starts[1:]) + [len(triangles)]

    node_face = np.zeros(len(xyz), dtype=np.int64)  # 0 = unused
    # Reversed assignment leaves each node with the first (lowest) face that uses it.
    node_face[triangles[::-1].ravel()] = np.repeat(triangle_face[::-1], 3)

    with open(path, "w") as out:
        out.write("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
        out.write("$Entities\n0 0 %d 0\n" % len(face_ids))
        for face, start, end in zip(face_ids, starts, ends):
            points = xyz[triangles[start:end].ravel()]
            lo, hi = points.min(axis=0), points.max(axis=0)
            out.write("%d %.17g %.17g %.17g %.17g %.17g %.17g 0 0\n" % (face, *lo, *hi))
        out.write("$EndEntities\n")

        used = np.flatnonzero(node_face)
        blocks = [(face, used[node_face[used] == face]) for face in face_ids]
        blocks = [(face, nodes) for face, nodes in blocks if len(nodes)]
        out.write("$Nodes\n%d %d %d %d\n" % (len(blocks), len(used),
                                           used.min() + 1 if len(used) else 0,
                                           used.max() + 1 if len(used) else 0))
        # Every line formatted once, in bulk: a numpy savetxt call per face costs more than
        # the face's lines on models of hundreds of small faces.
        coordinates = ["%.17g %.17g %.17g\n" % tuple(row) for row in xyz.tolist()]
        for face, nodes in blocks:
            out.write("2 %d 0 %d\n" % (face, len(nodes)))
            out.write("".join("%d\n" % (node + 1) for node in nodes.tolist()))
            out.write("".join([coordinates[node] for node in nodes.tolist()]))
        out.write("$EndNodes\n")

        out.write("$Elements\n%d %d 1 %d\n" % (len(face_ids), len(triangles), len(triangles)))
        rows = (triangles + 1).tolist()
        for face, start, end in zip(face_ids, starts, ends):
            out.write("2 %d 2 %d\n" % (face, end - start))
            out.write("".join("%d %d %d %d\n" % (i + 1, *rows[i]) for i in range(start, end)))
        out.write("$EndElements\n")
