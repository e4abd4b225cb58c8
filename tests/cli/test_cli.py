"""End-to-end tests of `rdmesh mesh` and `rdmesh info`: options, JSON, exit codes, and every
output format read back by an independent reader with the triangle count the run reported."""

import os

import pytest

# Models that mesh in well under a second; nist_mbe_pmi_11.stp is used for info and timeouts.
FAST_MODELS = ["cq_red_cube_blue_cylinder.step", "axom_sliced_cylinder.step",
               "pyocc_eight_cyl.stp"]
FORMATS = [".msh", ".stl", ".obj", ".ply", ".vtu", ".glb"]
MESH_OPTIONS = ["--max-deviation", "--max-deviation-rel", "--rd-tolerance", "--max-triangles",
                "--min-edge-length", "--max-edge-length", "--nurbs", "--threads", "--faces",
                "--timeout", "--strict", "--json", "--quiet", "--output", "--edges", "--no-edges",
                "--msh-parametric", "--lod"]
JSON_FIELDS = ["triangles", "nodes", "seconds", "edge_seconds", "face_seconds", "load_seconds",
               "mesh_cpu_seconds", "requested_deviation",
               "estimated_deviation", "mesh_area", "exact_area", "faces_ok", "faces_failed",
               "output", "faces"]
FACE_FIELDS = ["id", "surface_type", "triangles", "deviation", "area_error", "status", "reason",
               "seconds"]


def gmsh_triangles(path):
    import gmsh

    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        count = 0
        for dim, tag in gmsh.model.getEntities(2):
            types, tags, _ = gmsh.model.mesh.getElements(dim, tag)
            assert all(t == 2 for t in types)  # 3-node triangles only
            count += sum(len(t) for t in tags)
        surfaces = len(gmsh.model.getEntities(2))
    finally:
        gmsh.finalize()
    return count, surfaces


def gmsh_lines(path):
    """{curve tag: [(a, b), ...]} of the 2-node line elements (type 1) an MSH file holds, as Gmsh
    reads them (no other element lies on a curve), and the set of triangle sides {a, b}."""
    import gmsh

    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        lines, sides = {}, set()
        for dim, tag in gmsh.model.getEntities(1):
            types, _, nodes = gmsh.model.mesh.getElements(dim, tag)
            assert all(t == 1 for t in types)
            if len(types):
                lines[tag] = [(int(a), int(b)) for a, b in zip(nodes[0][::2], nodes[0][1::2])]
        for dim, tag in gmsh.model.getEntities(2):
            _, _, nodes = gmsh.model.mesh.getElements(dim, tag)
            for a, b, c in zip(nodes[0][::3], nodes[0][1::3], nodes[0][2::3]):
                sides |= {frozenset((a, b)), frozenset((b, c)), frozenset((c, a))}
    finally:
        gmsh.finalize()
    return lines, sides


def meshio_triangles(path):
    import meshio

    mesh = meshio.read(str(path))
    assert all(block.type in ("triangle", "line") for block in mesh.cells)
    return sum(len(block.data) for block in mesh.cells if block.type == "triangle"), mesh


def test_help_lists_every_option_with_defaults(run):
    result = run("mesh", "--help")
    assert result.code == 0
    for option in MESH_OPTIONS:
        assert option in result.stdout, option
    assert "model units" in result.stdout
    assert "--max-deviation-rel FLOAT=0.001" in result.stdout
    assert "--threads INT=0" in result.stdout
    assert run("info", "--help").code == 0
    assert run("--help").code == 0


def test_info_json(run, data_dir):
    info = run("info", data_dir / "nist_mbe_pmi_11.stp", "--json")
    assert info.code == 0, info.stderr
    model = info.json
    assert model["name"] == "nist_mbe_pmi_11.stp"
    assert model["format"] == "step"
    assert model["length_unit"] == "mm"
    assert model["faces"] == 10
    assert model["unique_faces"] == 10
    assert model["solids"] == 1
    assert model["closed"] is True
    assert sum(model["surface_types"].values()) == model["faces"]
    xmin, ymin, zmin, xmax, ymax, zmax = model["bbox"]
    diagonal = ((xmax - xmin) ** 2 + (ymax - ymin) ** 2 + (zmax - zmin) ** 2) ** 0.5
    assert model["diagonal"] == pytest.approx(diagonal)
    assert model["load_seconds"] >= 0

    assembly = run("info", data_dir / "cq_red_cube_blue_cylinder.step", "--json").json
    assert sorted(assembly["part_names"]) == ["blue_cylinder", "red_cube"]
    assert assembly["instances"] == 2
    assert assembly["length_unit"] == "m"
    assert assembly["unit_scale_mm"] == 1000.0


def test_info_human(run, data_dir):
    result = run("info", data_dir / "cq_red_cube_blue_cylinder.step")
    assert result.code == 0
    assert "9 faces" in result.stdout
    assert "red_cube" in result.stdout


@pytest.mark.parametrize("model", FAST_MODELS)
@pytest.mark.parametrize("extension", FORMATS)
def test_every_format_reads_back(run, data_dir, tmp_path, gltf_validate, model, extension):
    output = tmp_path / ("out" + extension)
    result = run("mesh", data_dir / model, "-o", output, "--json")
    assert result.code == 0, result.stderr
    report = result.json
    triangles = report["triangles"]
    assert triangles > 0
    assert output.is_file()

    if extension == ".msh":
        # Both Gmsh and meshio read it, with the same triangles.
        count, surfaces = gmsh_triangles(output)
        assert surfaces == len(report["faces"])
        meshio_count, mesh = meshio_triangles(output)
        assert meshio_count == count
        assert len(mesh.points) == report["nodes"]
    elif extension == ".glb":
        validation = gltf_validate(output)
        assert validation["errors"] == 0, validation["messages"]
        count = validation["triangles"]  # counts every placed instance
    else:
        count, mesh = meshio_triangles(output)
        if extension in (".ply", ".vtu"):  # points per face; node_id: the watertight nodes
            assert len(set(mesh.point_data["node_id"].ravel())) == report["nodes"]
            assert len(mesh.points) >= report["nodes"]
        if extension == ".ply":
            assert mesh.cell_data["face_id"][0].min() >= 1
        if extension == ".vtu":
            assert mesh.point_data["Normals"].shape == (len(mesh.points), 3)
            assert set(mesh.cell_data["face_id"][0]) <= {f["id"] for f in report["faces"]}
    assert count == triangles


def test_json_report(run, data_dir, tmp_path):
    output = tmp_path / "cq.msh"
    result = run("mesh", data_dir / "cq_red_cube_blue_cylinder.step", "-o", output, "--json")
    assert result.code == 0, result.stderr
    report = result.json
    for field in JSON_FIELDS:
        assert field in report, field
    assert report["output"] == str(output)
    assert report["seconds"] >= 0 and report["load_seconds"] >= 0
    # The stages' wall times lie within the run's; each face's within the face stage's.
    assert report["edge_seconds"] + report["face_seconds"] <= report["seconds"] + 1e-6
    # The meshing CPU time: positive, and at most the wall time on as many threads as cores.
    assert 0 < report["mesh_cpu_seconds"] <= (os.cpu_count() or 1) * report["seconds"] + 0.05
    assert 0 <= max(face["seconds"] for face in report["faces"]) <= report["face_seconds"] + 1e-6
    assert report["faces_ok"] == 9 and report["faces_failed"] == 0
    assert len(report["faces"]) == 9
    assert sum(face["triangles"] for face in report["faces"]) == report["triangles"]
    for face in report["faces"]:
        for field in FACE_FIELDS:
            assert field in face, field
        assert face["status"] == "ok"
        assert face["area_error"] < 0.05
        assert face["deviation"] <= report["estimated_deviation"] + 1e-12
    assert report["requested_deviation"] > 0
    assert report["exact_area"] == pytest.approx(report["mesh_area"], rel=0.05)
    # The human summary goes to stderr with --json.
    assert "triangles" in result.stderr and str(output) in result.stderr


def test_human_report(run, data_dir, tmp_path):
    output = tmp_path / "cyl.stl"
    result = run("mesh", data_dir / "axom_sliced_cylinder.step", "-o", output)
    assert result.code == 0, result.stderr
    for word in ["5 ok, 0 failed", "triangles", "nodes", "requested", "estimated", str(output)]:
        assert word in result.stdout, word
    assert run("mesh", data_dir / "axom_sliced_cylinder.step", "-o", output, "-q").stdout == ""


@pytest.mark.parametrize("model", ["sphere.step", "cylinder.step"])
def test_msh_passes_the_yardstick(run, shared_dir, tmp_path, meshbench, model):
    path = shared_dir / "yardstick" / "models" / model
    output = tmp_path / "out.msh"
    result = run("mesh", path, "-o", output, "--json", "--max-deviation-rel", "1e-3")
    assert result.code == 0, result.stderr
    score = meshbench(path, output)
    assert score["triangles"] == result.json["triangles"]
    assert score["faces_covered"] == score["faces"]
    assert score["free_edges"] == 0
    assert score["nonmanifold_edges"] == 0
    assert score["inverted"] == 0


def test_face_subset(run, data_dir, tmp_path):
    output = tmp_path / "subset.vtu"
    result = run("mesh", data_dir / "cq_red_cube_blue_cylinder.step", "-o", output, "--json",
                 "--faces", "1,3-4")
    assert result.code == 0, result.stderr
    report = result.json
    statuses = {face["id"]: face["status"] for face in report["faces"]}
    assert [i for i, s in statuses.items() if s == "ok"] == [1, 3, 4]
    assert report["faces_ok"] == 3
    count, _ = meshio_triangles(output)
    assert count == report["triangles"]


def test_bad_model_files(run, data_dir, tmp_path):
    missing = tmp_path / "missing.step"
    result = run("mesh", missing, "-o", tmp_path / "out.msh")
    assert result.code == 3
    assert "missing.step" in result.stderr and "no such file" in result.stderr

    garbage = tmp_path / "garbage.step"
    garbage.write_bytes(os.urandom(4096))
    result = run("info", garbage, "--json")
    assert result.code == 3
    assert "garbage.step" in result.stderr
    assert result.json["error"]["code"] == "parse_error"
    assert result.json["exit_code"] == 3

    empty = tmp_path / "empty.stp"
    empty.write_bytes(b"")
    result = run("mesh", empty, "-o", tmp_path / "out.msh")
    assert result.code == 3 and "empty" in result.stderr

    half = tmp_path / "half.stp"
    whole = (data_dir / "nist_mbe_pmi_11.stp").read_bytes()
    half.write_bytes(whole[: len(whole) // 2])
    result = run("mesh", half, "-o", tmp_path / "out.msh")
    assert result.code == 3 and "truncated" in result.stderr


def test_usage_errors(run, data_dir, tmp_path):
    model = data_dir / "axom_sliced_cylinder.step"
    out = tmp_path / "out.msh"
    assert run("mesh", model).code == 2  # no -o
    assert run("mesh", model, "-o", out, "--no-such-flag").code == 2
    assert run().code == 2
    result = run("mesh", model, "-o", out, "--max-deviation", "-1")
    assert result.code == 2 and "--max-deviation" in result.stderr
    result = run("mesh", model, "-o", out, "--max-deviation", "abc")
    assert result.code == 2
    result = run("mesh", model, "-o", out, "--faces", "2,x")
    assert result.code == 2 and "'x'" in result.stderr
    result = run("mesh", model, "-o", out, "--faces", "99")
    assert result.code == 2 and "99" in result.stderr
    result = run("mesh", model, "-o", tmp_path / "out.xyz")
    assert result.code == 2 and ".msh" in result.stderr
    assert not out.exists()


def test_unwritable_output(run, data_dir, tmp_path):
    out = tmp_path / "no_such_dir" / "out.glb"
    result = run("mesh", data_dir / "axom_sliced_cylinder.step", "-o", out)
    assert result.code == 5
    assert str(out) in result.stderr


def test_timeout(run, data_dir, tmp_path):
    result = run("mesh", data_dir / "nist_mbe_pmi_11.stp", "-o", tmp_path / "out.msh",
                 "--timeout", "0.05", "--json", timeout=60)
    assert result.code == 4
    assert "timed out" in result.stderr
    assert result.json["error"]["code"] == "deadline_exceeded"
    assert not (tmp_path / "out.msh").exists()


def test_instanced_assembly(run, shared_dir, tmp_path, gltf_validate):
    """An assembly that places one part several times: glTF stores the part's mesh once and
    draws it per instance; every format holds as many triangles as the run reports."""
    model = shared_dir / "corpus" / "gmsh_presse_asm.step"
    assert model.is_file(), model
    info = run("info", model, "--json").json
    assert info["unique_faces"] < info["faces"]
    assert info["instances"] >= 2
    for extension in (".glb", ".obj", ".msh"):
        output = tmp_path / ("assembly" + extension)
        result = run("mesh", model, "-o", output, "--json", "--timeout", "300")
        assert result.code == 0, result.stderr
        if extension == ".glb":
            validation = gltf_validate(output)
            assert validation["errors"] == 0, validation["messages"]
            count = validation["triangles"]
        elif extension == ".obj":
            count, _ = meshio_triangles(output)
        else:
            count, surfaces = gmsh_triangles(output)
        assert count == result.json["triangles"]


def obj_lines(path):
    """Vertex positions (1-based list) and `l` records of an OBJ file."""
    positions, lines = [None], []
    for record in open(path):
        fields = record.split()
        if fields and fields[0] == "v":
            positions.append(tuple(float(v) for v in fields[1:4]))
        elif fields and fields[0] == "l":
            lines.append([int(v) for v in fields[1:]])
    return positions, lines


@pytest.mark.parametrize("model", FAST_MODELS)
def test_edges_as_lines(run, data_dir, tmp_path, model):
    """--edges (the default): every edge of the model as line elements on its curve entity that
    join nodes of the triangles, read the same by Gmsh and meshio; the OBJ has one `l` per edge
    at the same points; --no-edges leaves them out."""
    output = tmp_path / "out.msh"
    result = run("mesh", data_dir / model, "-o", output, "--json")
    assert result.code == 0, result.stderr
    lines, triangle_sides = gmsh_lines(output)
    assert lines
    _, mesh = meshio_triangles(output)
    segments = 0
    for tag, polyline in lines.items():
        for (a, b), (c, _) in zip(polyline, polyline[1:] + [(polyline[-1][1], None)]):
            assert b == c, f"curve {tag}: line elements do not follow each other"
            assert frozenset((a, b)) in triangle_sides, f"curve {tag}: {a}-{b} is no triangle side"
        segments += len(polyline)
    assert sum(len(b.data) for b in mesh.cells if b.type == "line") == segments

    plain = tmp_path / "plain.msh"
    assert run("mesh", data_dir / model, "-o", plain, "-q", "--no-edges").code == 0
    assert gmsh_lines(plain)[0] == {}
    assert gmsh_triangles(plain)[0] == result.json["triangles"]

    obj = tmp_path / "out.obj"
    assert run("mesh", data_dir / model, "-o", obj, "-q").code == 0
    positions, records = obj_lines(obj)
    assert len(records) == len(lines)
    points = {tuple(p) for p in mesh.points}
    for record in records:
        for index in record:
            assert positions[index] in points


def test_msh_parametric_round_trips_the_parameters(run, data_dir, tmp_path):
    """--msh-parametric writes t on curve nodes and (u, v) on surface nodes, which Gmsh reads
    back; the nodes are the default file's. meshio 5 reads only the default file."""
    import gmsh
    import meshio

    model = data_dir / "axom_sliced_cylinder.step"
    plain, parametric = tmp_path / "plain.msh", tmp_path / "parametric.msh"
    assert run("mesh", model, "-o", plain, "-q").code == 0
    assert run("mesh", model, "-o", parametric, "-q", "--msh-parametric").code == 0
    with pytest.raises((Exception, SystemExit)):  # meshio 5 exits on "parametric nodes"
        meshio.read(str(parametric))
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(parametric))
        with_params = 0
        for dim, tag in gmsh.model.getEntities():
            if dim == 0:
                continue
            tags, _, params = gmsh.model.mesh.getNodes(dim, tag, returnParametricCoord=True)
            assert len(params) == dim * len(tags), (dim, tag)
            with_params += len(tags)
        all_tags, coords, _ = gmsh.model.mesh.getNodes()
    finally:
        gmsh.finalize()
    mesh = meshio.read(str(plain))
    assert with_params > 0
    assert len(all_tags) == len(mesh.points)
    assert sorted(map(tuple, coords.reshape(-1, 3).tolist())) == sorted(
        map(tuple, mesh.points.tolist()))


@pytest.mark.parametrize("name,tol,bound,both_ways",
                         [("gmsh_periodic_u_cst.step", "1e-4", 1.05, False),
                          ("gmsh_periodic_u_cst.step", "3e-4", 1.05, False),
                          ("gmsh_angled.step", "3e-3", 1.05, False),
                          ("gmsh_solid_56.step", "1e-4", 1.05, False),
                          ("gmsh_wrenchnut.stp", "3e-4", 1.0, False),
                          ("gmsh_wrenchnut.stp", "1e-4", 1.0, False),
                          ("gmsh_wrenchnut.stp", "1e-3", 1.05, True),
                          ("gmsh_periodic_u_cst.step", "1e-3", 1.05, True)])
def test_delivered_deviation_meets_the_request(run, shared_dir, tmp_path, meshbench, name, tol,
                                               bound, both_ways):
    """Cases that missed the request, each met now, by the engine's estimate and by the yardstick.
    gmsh_periodic_u_cst at 1e-4 (3.0x): the fold guard blocked the splits; a face still over the
    criteria is refined again from its own result. At 3e-4 (5.85x): a fan of slivers standing on
    one (u,v) line that the surface bends, which no split could refine; a flip that takes a corner
    off the line (ReshapeByFlip) lets them be split. gmsh_angled at 3e-3 (1.20x): cylinder
    triangles tilted against the surface, whose plane heights missed their edges' sagitta by the
    cosine between the normals (MeasureEdgeHeights). The yardstick finds some 5% more than the
    estimate at places: periodic_u_cst at 1e-4 measured 1.053x (1.026x before MeasureEdgeHeights
    moved its nodes), an interior edge's height along its corners' mean normal short of its
    sagitta; 1.021x since the edge grids leave room for edge gaps, which moved its nodes again
    (the estimate is no better). gmsh_solid_56 at 1e-4 (2.08x): a cone edge across
    the axis whose peak ConeDeviation lost to rounding (face 11), and edge 94's chords, which took
    the whole deviation though the edge lies 0.019 mm outside face 47's trim (the edge grid now
    leaves room for that gap). gmsh_wrenchnut at 3e-4 and 1e-4 (1.022x, 1.035x): thin
    triangles tilted over an uneven B-spline parametrisation, where the sampled estimate reads
    short; the final check measures each estimated triangle again as the distance to the nearest
    surface point (DenseDeviation) and splits the ones over, which gives 0.997x and 0.998x, so
    these are held to the request itself. Both ways (the yardstick also measures from points of
    each face to the mesh): gmsh_wrenchnut at 1e-3 read 1.104x that way, a fan of slivers at a
    corner of B-spline face 6 where the surface bends away between the final check's samples (now
    split where a sample's reading plus the cell's sag passes the request) and where bisecting
    the sliver's long edge never reached it (now split at the point); gmsh_periodic_u_cst read
    1.062x before the final check looked from the surface side. Skipped only without the shared
    corpus."""
    model = shared_dir / "corpus" / name
    if not model.exists():
        pytest.skip(f"{model} is not there (the shared corpus)")
    output = tmp_path / "out.msh"
    result = run("mesh", model, "-o", output, "--json", "--max-deviation-rel", tol)
    assert result.code == 0, result.stderr
    report = result.json
    assert all(f["reason"] == "" for f in report["faces"])
    assert report["faces_over_criteria"] == 0
    assert report["estimated_deviation"] <= report["requested_deviation"]
    score = meshbench(model, output, both_ways=both_ways)
    assert score["hausdorff_sym_rel" if both_ways else "hausdorff_rel"] <= bound * float(tol)
    assert score["free_edges"] == 0 and score["inverted"] == 0


def test_face_whose_trim_lies_off_its_edges_says_so(run, shared_dir, tmp_path, meshbench):
    """brepnet_132907 at 1e-4 of the diagonal (2.2e-3 mm): the pcurves of torus face 77 lie up to
    7.1e-3 mm from their edges' 3D curves, within the edges' tolerance. The mesh follows the 3D
    curves (shared with the neighbours), so seen from the face it misses by that much along the
    boundary (the yardstick read 3.08x both ways, and nothing was reported). The face says why,
    and the estimate covers what the yardstick reads. Skipped only without the shared corpus."""
    model = shared_dir / "corpus" / "brepnet_132907_4ed3eae8_0.stp"
    if not model.exists():
        pytest.skip(f"{model} is not there (the shared corpus)")
    output = tmp_path / "out.msh"
    result = run("mesh", model, "-o", output, "--json", "--max-deviation-rel", "1e-4")
    assert result.code == 0, result.stderr
    face = next(f for f in result.json["faces"] if f["id"] == 77)
    assert face["reason"].startswith("the B-rep prevents the requested deviation"), face
    assert face["deviation"] > result.json["requested_deviation"]
    score = meshbench(model, output, both_ways=True)
    assert score["hausdorff_sym_rel"] > 1.05e-4  # the miss is real
    diagonal = result.json["requested_deviation"] / 1e-4
    assert score["hausdorff_sym_rel"] * diagonal <= result.json["estimated_deviation"]


def test_face_the_brep_keeps_from_the_request_says_so(run, shared_dir, tmp_path):
    """brepnet_52890 at 3e-5 of the diagonal (7.6e-4 mm): face 42's edges lie up to 1.1e-3 mm
    off its B-spline surface, within their tolerance, and the trims (pcurves) of cylinder faces 45,
    51, 79, 85 and 158 lie 9.1e-4 to 1.6e-3 mm from their edges' 3D curves, which the mesh follows
    (the yardstick reads 8.0e-4 to 1.5e-3 mm from those faces to the mesh). No mesh of them can
    meet the request; each is meshed and says why, in --json (its reason, its deviation,
    faces_over_criteria) and in the human summary. Skipped only without the shared corpus."""
    model = shared_dir / "corpus" / "brepnet_52890_dc92327c_3.stp"
    if not model.exists():
        pytest.skip(f"{model} is not there (the shared corpus)")
    result = run("mesh", model, "-o", tmp_path / "out.msh", "--json", "--max-deviation-rel", "3e-5")
    assert result.code == 0, result.stderr
    report = result.json
    brep = [f for f in report["faces"] if f["reason"].startswith("the B-rep prevents")]
    assert [f["id"] for f in brep] == [42, 45, 51, 79, 85, 158]
    for face in brep:
        assert face["status"] == "ok" and face["triangles"] > 0
        assert face["deviation"] > report["requested_deviation"]
    assert report["faces_over_criteria"] >= 6
    assert "faces meshed over the criteria:" in result.stderr
    assert "face 42 (bspline): the B-rep prevents" in result.stderr


def test_a_miss_the_brep_explains_is_reported_as_the_breps(run, shared_dir, tmp_path):
    """gmsh_periodic_u_cst at 3e-5 of the diagonal (3.81e-3 mm): both B-spline faces have edges
    up to 5.8-7.6e-3 mm off their surface, so neither can meet the request. Each stays within the
    request plus its own gap, and its reason is the B-rep's alone. Face 3 used to keep triangles
    0.12 mm off, which it reported as "beyond that, some triangles could not be refined": large
    triangles beside finely refined ones inherited the generation cap (refine.cpp's
    kMaxGeneration), which now spares a triangle still large against its face. Skipped only
    without the shared corpus."""
    model = shared_dir / "corpus" / "gmsh_periodic_u_cst.step"
    if not model.exists():
        pytest.skip(f"{model} is not there (the shared corpus)")
    result = run("mesh", model, "-o", tmp_path / "out.msh", "--json", "--max-deviation-rel", "3e-5")
    assert result.code == 0, result.stderr
    faces = {f["id"]: f for f in result.json["faces"]}
    beyond = "beyond that, some triangles could not be refined"
    for face, gap in ((1, 7.7e-3), (3, 5.9e-3)):
        assert faces[face]["reason"].startswith("the B-rep prevents"), face
        assert beyond not in faces[face]["reason"], face
        assert faces[face]["deviation"] < 3.81e-3 + gap, face
