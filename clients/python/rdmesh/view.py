"""A picture of a mesh coloured by each triangle's estimated deviation (rdmesh-py view).

Reads the VTU and PLY files that `rdmesh` and `rdmesh-py mesh` write (through meshio): their
triangles with the cell data "deviation" (the engine's estimate of the distance between each
triangle and the exact surface) and "face_id" (the B-rep face of each triangle). Renders them with
matplotlib's Agg backend, so no display is needed: triangles coloured by deviation from 0 to the
largest, a colour bar, and the B-rep faces with the largest deviation labelled at their worst
triangle.
"""

import os

import numpy as np

READ_FORMATS = (".vtu", ".ply")


def read_deviation_mesh(path):
    """(points (N, 3), triangles (T, 3), deviation (T,), face_id (T,) or None) of a VTU or PLY
    file with the cell data "deviation". ValueError when it cannot serve."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in READ_FORMATS:
        raise ValueError("view reads %s files (rdmesh or rdmesh-py mesh output), not %r"
                         % (" and ".join(READ_FORMATS), ext or path))
    import meshio
    mesh = meshio.read(path)
    blocks = [k for k, block in enumerate(mesh.cells) if block.type == "triangle"]
    if not blocks:
        raise ValueError("%s holds no triangles" % path)
    if "deviation" not in mesh.cell_data:
        raise ValueError("%s has no cell data 'deviation' (write it with rdmesh, or with "
                         "rdmesh-py mesh, as .vtu or .ply)" % path)

    def cells(name):
        return np.concatenate([np.asarray(mesh.cell_data[name][k]).reshape(-1) for k in blocks])

    triangles = np.concatenate([np.asarray(mesh.cells[k].data, dtype=np.int64) for k in blocks])
    face_id = cells("face_id").astype(np.int64) if "face_id" in mesh.cell_data else None
    return np.asarray(mesh.points, dtype=np.float64), triangles, cells("deviation"), face_id


def worst_faces(deviation, face_id, count):
    """The `count` B-rep faces (triangles, without face ids) of largest deviation, worst first:
    a list of (face id or None, index of its worst triangle, its deviation). Ties go to the
    smaller face id."""
    if count <= 0 or not len(deviation):
        return []
    if face_id is None:
        order = np.lexsort((np.arange(len(deviation)), -deviation))[:count]
        return [(None, int(t), float(deviation[t])) for t in order]
    worst = {}
    for t in np.lexsort((np.arange(len(deviation)), -deviation)):
        f = int(face_id[t])
        if f not in worst:
            worst[f] = int(t)
            if len(worst) == count:
                break
    return [(f, t, float(deviation[t])) for f, t in worst.items()]


def render(mesh_path, out_path, width=1000, height=750, labels=5, elev=25.0, azim=-60.0,
           title=None, cmap="viridis"):
    """Renders `mesh_path` (VTU or PLY with cell data "deviation") into the PNG `out_path` of
    width x height pixels. Returns what the picture shows: {"clim": (low, high) of the colour
    bar, "labels": [{"face_id", "deviation", "xyz", "text"}] as drawn, worst first,
    "triangles": count}."""
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib import cm, colors
    from matplotlib.figure import Figure
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    points, triangles, deviation, face_id = read_deviation_mesh(mesh_path)
    high = float(deviation.max()) if len(deviation) else 0.0
    norm = colors.Normalize(vmin=0.0, vmax=high if high > 0 else 1.0)
    colormap = matplotlib.colormaps[cmap]

    dpi = 100
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_axes([0.0, 0.0, 0.82, 0.94], projection="3d")
    ax.view_init(elev=elev, azim=azim)
    corners = points[triangles]
    # Colour by deviation, shaded by a light from the viewer's upper left so that the shape
    # reads (brightness 55-100% of the colour bar's colour).
    face_colours = colormap(norm(deviation))
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    normals /= np.where(lengths > 0, lengths, 1.0)[:, None]
    a, e = np.radians(azim), np.radians(elev)
    view = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    up = np.array([-np.sin(e) * np.cos(a), -np.sin(e) * np.sin(a), np.cos(e)])
    left = np.cross(up, view)
    light = view + 0.5 * up + 0.5 * left
    light /= np.linalg.norm(light)
    shade = 0.55 + 0.45 * np.abs(normals @ light)
    face_colours[:, :3] *= shade[:, None]
    ax.add_collection3d(Poly3DCollection(corners, facecolors=face_colours,
                                         edgecolors=face_colours, linewidths=0.2))
    low_corner, high_corner = points.min(axis=0), points.max(axis=0)
    centre = (low_corner + high_corner) / 2
    extent = np.maximum(high_corner - low_corner, 1e-3 * (high_corner - low_corner).max())
    for setter, c, size in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre, extent):
        setter(c - size / 2, c + size / 2)
    ax.set_box_aspect(extent, zoom=1.2)
    ax.set_axis_off()

    # Labels: a numbered marker on each of the worst faces' worst triangle, drawn over the mesh
    # (in screen space, so no face hides it), and the list in the lower left corner.
    from mpl_toolkits.mplot3d import proj3d
    fig.canvas.draw()
    drawn = []
    for rank, (face, t, value) in enumerate(worst_faces(deviation, face_id, labels)):
        xyz = corners[t].mean(axis=0)
        name = "face %d" % face if face is not None else "triangle %d" % t
        text = "%d. %s: %.3g" % (rank + 1, name, value)
        x, y, _ = proj3d.proj_transform(xyz[0], xyz[1], xyz[2], ax.get_proj())
        ax.annotate("%d" % (rank + 1), xy=(x, y), xycoords="data",
                    xytext=(14 + 10 * (rank % 2), 14 + 12 * (rank // 2)),
                    textcoords="offset points", color="black", fontsize=9, fontweight="bold",
                    bbox=dict(boxstyle="circle,pad=0.2", fc="white", ec="red", lw=1.2),
                    arrowprops=dict(arrowstyle="-", color="red", lw=1.2), zorder=10)
        drawn.append({"face_id": face, "deviation": value, "xyz": xyz.tolist(), "text": text})
    if drawn:
        fig.text(0.01, 0.01, "largest deviation:\n" + "\n".join(d["text"] for d in drawn),
                 fontsize=8, va="bottom", family="monospace")

    mappable = cm.ScalarMappable(norm=norm, cmap=colormap)
    bar_axes = fig.add_axes([0.85, 0.12, 0.03, 0.72])
    bar = fig.colorbar(mappable, cax=bar_axes)
    bar.set_label("estimated deviation (model units)")
    fig.suptitle(title if title is not None else
                 "%s: %d triangles, deviation up to %.3g"
                 % (os.path.basename(mesh_path), len(triangles), high), fontsize=10)
    os.makedirs(os.path.dirname(os.path.abspath(out_path)), exist_ok=True)
    fig.savefig(out_path, dpi=dpi, format="png")
    return {"clim": tuple(float(v) for v in mappable.get_clim()), "labels": drawn,
            "triangles": int(len(triangles))}
