#!/usr/bin/python3
"""Where a mesh of the unit sphere spends its triangles, from the exact sphere.

  /usr/bin/python3 bench/quality/sphere_stats.py MESH.msh TOL

TOL is the --max-deviation-rel the mesh was made at (of the diagonal 2 sqrt(3)). For each
triangle: its deviation from the sphere (at the circumcentre when that lies inside, else at the
mid-point of its longest edge), and its efficiency, its area over that of the equilateral
triangle at the same deviation. The count over the interpolating minimum is about
1 / (mean deviation ratio x mean efficiency). Also the node valences.
"""
import collections
import sys

import meshio
import numpy as np


def main():
    mesh = meshio.read(sys.argv[1])
    tol = float(sys.argv[2]) * 2 * np.sqrt(3)
    p = mesh.points
    t = np.vstack([c.data for c in mesh.cells if c.type == "triangle"])
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    n = np.cross(b - a, c - a)
    area = np.linalg.norm(n, axis=1) / 2
    n /= np.linalg.norm(n, axis=1)[:, None]
    plane = 1 - np.abs(np.einsum("ij,ij->i", n, a))

    def acute_at(x, y, z):
        return np.einsum("ij,ij->i", y - x, z - x) > 0

    acute = acute_at(a, b, c) & acute_at(b, c, a) & acute_at(c, a, b)
    mids = [(a + b) / 2, (b + c) / 2, (c + a) / 2]
    edge = np.max([1 - np.linalg.norm(m, axis=1) for m in mids], axis=0)
    dev = np.where(acute, plane, edge)
    ratio = dev / tol
    eff = area / (3 * np.sqrt(3) / 4 * (1 - (1 - dev) ** 2))
    print(f"triangles {len(t)}; deviation / requested: max {ratio.max():.3f}, mean {ratio.mean():.3f}")
    print(f"efficiency: mean {eff.mean():.3f}")
    valence = collections.Counter(t.ravel())
    print("valences", sorted(collections.Counter(valence.values()).items()))


if __name__ == "__main__":
    main()
