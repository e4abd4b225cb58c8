"""Levels of detail (`rdmesh mesh --lod`, issue 15 item 4): one run reads the model once and
writes one whole watertight mesh per level, coarsest first (OUT.lodN.EXT, N = 0 the coarsest),
each byte for byte the file of a separate run at that level's --max-deviation-rel."""

import numpy as np
import pytest

from test_cli import meshio_triangles

LEVELS = ["1e-2", "1e-3", "1e-4"]
# Bundled models and a corpus model, all closed solids (so watertight means no open side).
MODELS = ["axom_sliced_cylinder.step", "pyocc_eight_cyl.stp"]
CORPUS_MODEL = "nist_mbe_pmi_2.stp"


def open_sides(triangles):
    """Triangle sides used by an odd number of triangles: 0 for a watertight mesh of closed
    solids. (Even counts above 2 occur: at 1e-2 two B-rep edges between the same two vertices,
    such as the halves of a small circle, can each be one chord, and the chords coincide.)"""
    t = np.asarray(triangles, dtype=np.int64)
    sides = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, counts = np.unique(sides, axis=0, return_counts=True)
    return int((counts % 2 == 1).sum())


def level_paths(tmp_path, stem, extension, count=len(LEVELS)):
    return [tmp_path / f"{stem}.lod{i}{extension}" for i in range(count)]


def check_levels(run, model, tmp_path, extension, levels=LEVELS):
    """Meshes `model` with --lod, checks each level against a separate run at its deviation,
    and returns the levels' reports (coarsest first)."""
    result = run("mesh", model, "-o", tmp_path / f"lod{extension}", "--lod", ",".join(levels),
                 "--json")
    assert result.code == 0, result.stderr
    report = result.json
    ordered = sorted(levels, key=float, reverse=True)
    assert [r["level"] for r in report["levels"]] == list(range(len(levels)))
    assert [r["max_deviation_rel"] for r in report["levels"]] == [float(v) for v in ordered]
    paths = level_paths(tmp_path, "lod", extension, len(levels))
    assert [r["output"] for r in report["levels"]] == [str(p) for p in paths]
    assert not (tmp_path / f"lod{extension}").exists()
    for level, path, level_report in zip(ordered, paths, report["levels"]):
        single = tmp_path / f"single{level}{extension}"
        alone = run("mesh", model, "-o", single, "--max-deviation-rel", level, "--json")
        assert alone.code == 0, alone.stderr
        assert path.read_bytes() == single.read_bytes(), f"level {level} differs from a run"
        assert level_report["triangles"] == alone.json["triangles"]
        assert level_report["faces"] == [dict(f, seconds=g["seconds"]) for f, g in
                                         zip(alone.json["faces"], level_report["faces"])]
    triangles = [r["triangles"] for r in report["levels"]]
    assert triangles == sorted(triangles) and len(set(triangles)) == len(triangles), triangles
    return report["levels"], paths


@pytest.mark.parametrize("model", MODELS)
def test_lod_levels_equal_separate_runs(run, data_dir, tmp_path, model):
    reports, paths = check_levels(run, data_dir / model, tmp_path, ".msh")
    for path, report in zip(paths, reports):
        count, mesh = meshio_triangles(path)
        assert count == report["triangles"]
        triangles = np.concatenate([c.data for c in mesh.cells if c.type == "triangle"])
        assert open_sides(triangles) == 0, f"{path.name} is not watertight"
        assert report["faces_failed"] == 0


def test_lod_corpus_model(run, shared_dir, tmp_path):
    model = shared_dir / "corpus" / CORPUS_MODEL
    if not model.is_file():
        pytest.skip(f"{model} is not there (the shared corpus)")
    reports, paths = check_levels(run, model, tmp_path, ".msh")
    for path, report in zip(paths, reports):
        count, mesh = meshio_triangles(path)
        triangles = np.concatenate([c.data for c in mesh.cells if c.type == "triangle"])
        assert open_sides(triangles) == 0, f"{path.name} is not watertight"
        assert report["faces_failed"] == 0


@pytest.mark.parametrize("extension", [".stl", ".obj", ".ply", ".vtu"])
def test_lod_other_formats(run, data_dir, tmp_path, extension):
    check_levels(run, data_dir / "pyocc_eight_cyl.stp", tmp_path, extension, ["2e-3", "5e-2"])


def test_lod_glb_loads_in_three(run, data_dir, tmp_path, gltf_validate, three_load):
    """Each level's .glb is validator-clean, loads in three.js with a face id on every triangle
    covering every face, and the levels get finer."""
    model = data_dir / "pyocc_eight_cyl.stp"
    faces = run("info", model, "--json").json["faces"]
    reports, paths = check_levels(run, model, tmp_path, ".glb")
    for path, report in zip(paths, reports):
        validation = gltf_validate(path)
        assert validation["errors"] == 0 and validation["warnings"] == 0, validation["messages"]
        assert validation["triangles"] == report["triangles"]
        loaded = three_load(path)
        triangles = [o for o in loaded["objects"] if o["kind"] == "triangles"]
        face_ids = set()
        count = 0
        for o in triangles:
            face_id = np.array(o["face_id"])
            if "face_map" in o:
                face_id = np.array([o["face_map"].get(str(int(f)), f) for f in face_id])
            corners = face_id[np.array(o["index"]).reshape(-1, 3)]
            assert (corners == corners[:, :1]).all()
            face_ids |= set(int(f) for f in corners[:, 0])
            count += len(corners)
        assert count == report["triangles"]
        assert face_ids == set(range(1, faces + 1))


def test_lod_usage_errors(run, data_dir, tmp_path):
    model = data_dir / "axom_sliced_cylinder.step"
    out = tmp_path / "out.msh"
    for flags, message in [
        (["--lod", "1e-2,abc"], "not a number"),
        (["--lod", "1e-2,1e-2"], "equal"),
        (["--lod", "0"], "(0, 0.5]"),
        (["--lod", "1e-2,1e-3", "--max-deviation-rel", "1e-3"], "--max-deviation-rel"),
        (["--lod", "1e-2,1e-3", "--max-deviation", "0.1"], "--max-deviation"),
        (["--lod", "1e-2,1e-3", "--max-triangles", "1000"], "--max-triangles"),
        (["--lod", ",".join(["1e-2"] + [f"{k}e-3" for k in range(1, 9)])], "at most 8"),
    ]:
        result = run("mesh", model, "-o", out, *flags)
        assert result.code == 2, (flags, result.stderr)
        assert message in result.stderr, (flags, result.stderr)
    assert not list(tmp_path.iterdir())
