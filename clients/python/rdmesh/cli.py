"""rdmesh-py: health, info, status, mesh and batch (a dataset) through an rdmeshd server; view
draws a mesh coloured by its estimated deviation."""

import argparse
import json
import os
import sys
import time

import numpy as np

from rdmesh.client import Client, RdmeshError

OUTPUT_FORMATS = (".msh", ".stl", ".obj", ".vtu", ".ply")


def write_ply(path, xyz, triangles, cell_data):
    """ASCII PLY of a welded mesh: double x y z per vertex; per face the vertex list and the
    `cell_data` arrays (int32 as int, float64 as double; 17 digits, so they read back exactly).
    meshio's PLY writer leaves cell data out."""
    kinds = {np.dtype(np.int32): ("int", "%d"), np.dtype(np.float64): ("double", "%.17g")}
    columns = [(name, np.asarray(values)) for name, values in cell_data.items()]
    with open(path, "w") as file:
        file.write("ply\nformat ascii 1.0\ncomment written by rdmesh-py\n")
        file.write("element vertex %d\nproperty double x\nproperty double y\n"
                   "property double z\n" % len(xyz))
        file.write("element face %d\nproperty list uchar int vertex_indices\n" % len(triangles))
        for name, values in columns:
            file.write("property %s %s\n" % (kinds[values.dtype][0], name))
        file.write("end_header\n")
        np.savetxt(file, np.asarray(xyz, dtype=np.float64), fmt="%.17g")
        rows = [np.full((len(triangles), 1), 3), np.asarray(triangles, dtype=np.int64)]
        formats = ["%d"] * 4
        for _, values in columns:
            rows.append(values.reshape(-1, 1))
            formats.append(kinds[values.dtype][1])
        table = np.hstack([r.astype(object) for r in rows]) if len(triangles) else []
        np.savetxt(file, table, fmt=" ".join(formats))


def write_mesh(path, result):
    """Writes the assembled mesh: .msh as MSH 4.1 with one surface per B-rep face, .ply as
    ASCII PLY (write_ply), the other formats with meshio (STL binary). VTU and PLY carry the face
    id per triangle and, when the result has them, each triangle's estimated deviation as cell
    data "face_id" and "deviation"."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in OUTPUT_FORMATS:
        raise ValueError("unsupported output format %r (use %s)" % (ext, " ".join(OUTPUT_FORMATS)))
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    if ext == ".msh":
        from rdmesh.msh import write_msh41
        write_msh41(path, result.xyz, result.triangles, result.triangle_face)
        return
    cell_data = {}
    if ext in (".vtu", ".ply"):
        cell_data = {"face_id": result.triangle_face.astype(np.int32)}
        if getattr(result, "triangle_deviation", None) is not None:
            cell_data["deviation"] = np.asarray(result.triangle_deviation, dtype=np.float64)
    if ext == ".ply":
        write_ply(path, result.xyz, result.triangles, cell_data)
        return
    import meshio
    cell_data = {name: [values] for name, values in cell_data.items()}
    mesh = meshio.Mesh(result.xyz, [("triangle", result.triangles.astype(np.int32))],
                       cell_data=cell_data)
    kwargs = {"binary": True} if ext == ".stl" else {}
    meshio.write(path, mesh, **kwargs)


def open_edges(triangles):
    """Edges used by one triangle only: 0 for a watertight mesh of closed solids."""
    t = np.asarray(triangles, dtype=np.int64)
    if not len(t):
        return 0
    a = np.concatenate([t[:, 0], t[:, 1], t[:, 2]])
    b = np.concatenate([t[:, 1], t[:, 2], t[:, 0]])
    keys = np.minimum(a, b) * (int(t.max()) + 1) + np.maximum(a, b)
    return int((np.unique(keys, return_counts=True)[1] == 1).sum())


def _token(args):
    if args.token_file:
        with open(args.token_file) as file:
            return file.read().strip()
    return os.environ.get("RDMESH_TOKEN") or None


def _client(args):
    root = None
    if args.tls_ca:
        with open(args.tls_ca, "rb") as file:
            root = file.read()
    return Client(args.address, token=_token(args), root_certificates=root)


def _model_ref(client, args):
    if args.server_path:
        from rdmesh.v1 import rdmesh_pb2 as pb
        return pb.ModelRef(server_path=args.model)
    return args.model


def cmd_health(args):
    with _client(args) as client:
        try:
            status = client.health(timeout=args.timeout or 5.0)
        except RdmeshError as error:
            print("UNREACHABLE %s" % error, file=sys.stderr)
            return 2
    print(status)
    return 0 if status == "SERVING" else 1


def cmd_status(args):
    from google.protobuf import json_format
    with _client(args) as client:
        status = client.server_status(timeout=args.timeout or 5.0)
    print(json_format.MessageToJson(status, preserving_proto_field_name=True))
    return 0


def cmd_info(args):
    from google.protobuf import json_format
    with _client(args) as client:
        info = client.info(_model_ref(client, args), timeout=args.timeout)
    print(json_format.MessageToJson(info, preserving_proto_field_name=True))
    return 0


def _add_mesh_options(parser):
    parser.add_argument("--max-deviation", type=float,
                        help="absolute max deviation, model units")
    parser.add_argument("--max-deviation-rel", type=float,
                        help="max deviation as a fraction of the bbox diagonal (default 1e-3)")
    parser.add_argument("--rd-tolerance", type=float, help="representation-deficit tolerance")
    parser.add_argument("--max-triangles", type=int, help="triangle budget for the whole model")
    parser.add_argument("--min-edge-length", type=float, help="model units")
    parser.add_argument("--max-edge-length", type=float, help="model units")
    parser.add_argument("--nurbs", action="store_true", help="convert faces to B-splines first")
    parser.add_argument("--off-surface", action="store_true",
                        help="let the nodes leave the surface: triangles on both sides of it "
                             "within the deviation, about half as many on faces bending one way")
    parser.add_argument("--threads", type=int, help="worker threads (capped by the server)")
    parser.add_argument("--faces", help="comma-separated face ids to mesh (default all)")


def _mesh_options(args):
    """The mesh options of _add_mesh_options' flags, as Client.mesh() keyword arguments."""
    try:
        faces = [int(f) for f in args.faces.split(",")] if args.faces else None
    except ValueError:
        raise ValueError("--faces: give face ids like 1,2,5") from None
    return dict(max_deviation=args.max_deviation, max_deviation_rel=args.max_deviation_rel,
                rd_tolerance=args.rd_tolerance, max_triangles=args.max_triangles,
                min_edge_length=args.min_edge_length, max_edge_length=args.max_edge_length,
                nurbs=args.nurbs or None, off_surface=args.off_surface or None,
                threads=args.threads, face_ids=faces)


def cmd_mesh(args):
    options = _mesh_options(args)
    start = time.monotonic()
    bar = None
    progress = None
    if not args.no_progress:
        from tqdm import tqdm
        bar = tqdm(total=0, unit="face", desc="meshing", leave=False, file=sys.stderr,
                   disable=None)  # None: only on a terminal

        def progress(p):
            if p.stage != "faces" or p.total <= 0:
                return
            bar.total = p.total
            bar.n = p.done
            bar.refresh()
    lod = None
    if args.lod:
        try:
            lod = [float(v) for v in args.lod.split(",")]
        except ValueError:
            raise ValueError("--lod: give relative deviations like 1e-2,1e-3,1e-4") from None
    try:
        with _client(args) as client:
            deviation = args.output.lower().endswith((".vtu", ".ply"))
            if lod:
                results = client.mesh_levels(_model_ref(client, args), lod, progress=progress,
                                             timeout=args.timeout, triangle_deviation=deviation,
                                             **options)
            else:
                results = [client.mesh(_model_ref(client, args), progress=progress,
                                       timeout=args.timeout, triangle_deviation=deviation,
                                       **options)]
    finally:
        if bar is not None:
            bar.close()
    summaries = []
    for result in results:
        output = level_path(args.output, result.level) if lod else args.output
        write_mesh(output, result)
        summaries.append(_report(args, result, output, start))
    if args.json:
        if lod:
            print(json.dumps({"levels": summaries}))
        else:
            print(json.dumps(summaries[0]))
    for result in results:
        for face in result.faces:
            if face.status == "failed":
                print("%sface %d failed: %s" % ("level %d: " % result.level if lod else "",
                                                face.face_id, face.reason), file=sys.stderr)
    return 0


def level_path(output, level):
    """Where level `level` of a --lod run goes: OUT.EXT -> OUT.lodN.EXT (N = 0 the coarsest)."""
    root, ext = os.path.splitext(output)
    return "%s.lod%d%s" % (root, level, ext)


def _report(args, result, output, start):
    """One mesh's summary (printed unless --json, returned as a dict)."""
    seconds = time.monotonic() - start
    s = result.summary
    summary = {
        "model": result.model.name, "model_id": result.model.model_id,
        "faces": result.model.faces, "faces_ok": s.faces_ok, "faces_failed": s.faces_failed,
        "triangles": int(len(result.triangles)), "nodes": int(len(result.xyz)),
        "open_edges": open_edges(result.triangles),
        "requested_deviation": s.requested_deviation,
        "estimated_deviation": s.estimated_deviation,
        "mesh_area": s.mesh_area, "exact_area": s.exact_area,
        "server_seconds": s.total_seconds, "seconds": seconds,
        "output": os.path.abspath(output),
    }
    if result.max_deviation_rel is not None:
        summary.update(level=result.level, max_deviation_rel=result.max_deviation_rel)
    if not args.json:
        print("%s: %d faces (%d ok, %d failed), %d triangles, %d nodes, %d open edges"
              % (summary["model"], summary["faces"], s.faces_ok, s.faces_failed,
                 summary["triangles"], summary["nodes"], summary["open_edges"]))
        print("deviation %.4g (asked %.4g), area %.6g of %.6g; %.2f s (server %.2f s) -> %s"
              % (s.estimated_deviation, s.requested_deviation, s.mesh_area, s.exact_area,
                 seconds, s.total_seconds, summary["output"]))
    return summary


def cmd_batch(args):
    """Exit codes: 0 every file ok, 1 any not ok, 2 bad usage or no server, 4 interrupted, 5
    the manifest cannot be written (as the C++ batch)."""
    import signal
    from rdmesh import batch
    display = batch.Display(args.quiet)
    try:
        client = _client(args)
    except (OSError, ValueError) as error:
        print("rdmesh-py: %s" % error, file=sys.stderr)
        return batch.EXIT_USAGE
    with client:
        timeout = args.file_timeout if args.file_timeout is not None else args.timeout
        try:  # the inputs and options are checked before the server is asked anything
            run = batch.Batch(client, args.inputs, args.output, format=args.format,
                              jobs=args.jobs or 1, timeout=timeout, progress=display.progress,
                              problem=display.problem, **_mesh_options(args))
        except (batch.BatchError, ValueError, TypeError) as error:
            print("rdmesh-py: error: %s" % error, file=sys.stderr)
            return batch.EXIT_USAGE
        try:
            client.health(timeout=10.0)
            if not args.jobs:  # two calls per job slot: one uploads or waits while one meshes
                run.jobs = max(2, 2 * client.server_status(timeout=10.0).max_jobs)
        except RdmeshError as error:
            print("rdmesh-py: cannot reach rdmeshd at %s: %s" % (args.address, error),
                  file=sys.stderr)
            return batch.EXIT_USAGE

        def interrupt(signum, frame):
            if signum == signal.SIGINT and not run.stopping:
                run.stop()
                display.problem("interrupted: finishing the running file(s); Ctrl-C again "
                                "stops them now")
            else:
                run.kill()
        previous = {sig: signal.signal(sig, interrupt)
                    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
        try:
            summary = run.run()
        except batch.BatchError as error:
            print("rdmesh-py: error: %s" % error, file=sys.stderr)
            return batch.EXIT_USAGE
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)
            display.erase()
    if not args.quiet:
        print(batch.summary_text(summary), file=sys.stderr if args.json else sys.stdout)
    if args.json:
        print(json.dumps(summary.as_json()))
    return summary.exit_code


def cmd_view(args):
    from rdmesh.view import render
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        raise ValueError("--size must be WIDTHxHEIGHT in pixels, e.g. 1000x750") from None
    if not (16 <= width <= 8000 and 16 <= height <= 8000):
        raise ValueError("--size must lie between 16x16 and 8000x8000 pixels")
    shown = render(args.mesh, args.output, width=width, height=height, labels=args.labels,
                   elev=args.elev, azim=args.azim, title=args.title)
    if args.json:
        print(json.dumps(dict(shown, output=os.path.abspath(args.output))))
    else:
        print("%s: %d triangles, colour range %.4g..%.4g -> %s"
              % (args.mesh, shown["triangles"], shown["clim"][0], shown["clim"][1],
                 os.path.abspath(args.output)))
        for label in shown["labels"]:
            print("  " + label["text"])
    return 0


def parser():
    p = argparse.ArgumentParser(prog="rdmesh-py", description=__doc__)
    p.add_argument("--address", default=os.environ.get("RDMESH_ADDRESS", "127.0.0.1:50051"),
                   help="rdmeshd host:port (env RDMESH_ADDRESS; default %(default)s)")
    p.add_argument("--token-file", default=os.environ.get("RDMESH_TOKEN_FILE"),
                   help="file holding the server's bearer token (env RDMESH_TOKEN_FILE, or "
                        "the token itself in RDMESH_TOKEN)")
    p.add_argument("--tls-ca", default=os.environ.get("RDMESH_TLS_CA"),
                   help="PEM of the CA that signed the server's certificate: use TLS")
    p.add_argument("--timeout", type=float, default=None, help="call deadline, seconds")
    sub = p.add_subparsers(dest="command", required=True)

    sub.add_parser("health", help="print the server's health status (exit 0 when SERVING)")
    sub.add_parser("status", help="print the server's status (jobs, cache, limits) as JSON")
    info = sub.add_parser("info", help="describe a model (JSON)")
    info.add_argument("model", help="a model file (uploaded), or a model id")
    info.add_argument("--server-path", action="store_true",
                      help="MODEL is a path under the server's --data-root")

    mesh = sub.add_parser("mesh", help="mesh a model and write the mesh")
    mesh.add_argument("model", help="a model file (uploaded), or a model id")
    mesh.add_argument("-o", "--output", required=True,
                      help="output file: " + ", ".join(OUTPUT_FORMATS))
    mesh.add_argument("--server-path", action="store_true",
                      help="MODEL is a path under the server's --data-root")
    _add_mesh_options(mesh)
    mesh.add_argument("--lod",
                      help="levels of detail: relative deviations, e.g. 1e-2,1e-3,1e-4; one "
                           "call, the model read once, each level written to OUT.lodN.EXT "
                           "(N = 0 the coarsest)")
    mesh.add_argument("--no-progress", action="store_true", help="no progress bar")
    mesh.add_argument("--json", action="store_true", help="print the summary as one JSON line")

    from rdmesh.batch import FORMATS
    batch = sub.add_parser(
        "batch", help="mesh many models through the server into a mirrored tree with "
                      "OUTDIR/manifest.jsonl; a second run skips what is done (docs/BATCH.md)")
    batch.add_argument("inputs", nargs="+",
                       help="model files, folders (searched for .step .stp .iges .igs .brep) "
                            "and @LIST files (one path per line)")
    batch.add_argument("-o", "--output", required=True, help="output folder")
    batch.add_argument("--format", default="msh",
                       help="output format: %s (default %%(default)s; glb is not written by "
                            "this client)" % ", ".join(FORMATS))
    batch.add_argument("-j", "--jobs", type=int, default=0, metavar="N",
                       help="calls in flight at a time, one thread each (default: 2x the "
                            "server's job slots, as GetServerStatus reports them; behind nginx "
                            "give 2x the replicas' slots)")
    batch.add_argument("--timeout", dest="file_timeout", type=float, default=None,
                       metavar="S",
                       help="seconds per file, upload and mesh together (DEADLINE_EXCEEDED: "
                            "timed_out); 0 = none")
    _add_mesh_options(batch)
    batch.add_argument("--json", action="store_true",
                       help="print the summary as one JSON object, the last stdout line")
    batch.add_argument("-q", "--quiet", action="store_true",
                       help="print nothing but errors (and --json)")

    view = sub.add_parser("view", help="draw a mesh coloured by estimated deviation (PNG)")
    view.add_argument("mesh", help=".vtu or .ply written by rdmesh or rdmesh-py mesh (with the "
                                   "cell data 'deviation')")
    view.add_argument("-o", "--output", required=True, help="the PNG to write")
    view.add_argument("--size", default="1000x750", help="WIDTHxHEIGHT pixels (%(default)s)")
    view.add_argument("--labels", type=int, default=5,
                      help="label this many faces of largest deviation (%(default)s)")
    view.add_argument("--elev", type=float, default=25.0, help="view elevation, degrees")
    view.add_argument("--azim", type=float, default=-60.0, help="view azimuth, degrees")
    view.add_argument("--title", help="title (default: file, triangles, largest deviation)")
    view.add_argument("--json", action="store_true",
                      help="print the colour range and the labels as one JSON line")
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    commands = {"health": cmd_health, "status": cmd_status, "info": cmd_info, "mesh": cmd_mesh,
                "batch": cmd_batch, "view": cmd_view}
    try:
        return commands[args.command](args)
    except RdmeshError as error:
        print("rdmesh-py: %s" % error, file=sys.stderr)
        return 1
    except (OSError, ValueError) as error:
        print("rdmesh-py: %s" % error, file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
