"""The logic of bench/performance/parse_e2e.py (issue 34's end-to-end table): the KiCad sample,
the summary, and a whole run on stand-in binaries. No rdmesh needed."""

import importlib.util
import json
import math
import os
import pathlib
import stat

import pytest

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "bench" / "performance" / "parse_e2e.py"


@pytest.fixture(scope="module")
def e2e():
    spec = importlib.util.spec_from_file_location("parse_e2e", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def make_library(root, folders):
    for folder, count in folders.items():
        d = root / folder
        d.mkdir(parents=True)
        for i in range(count):
            (d / ("part_%02d.step" % i)).write_text("x")
            (d / ("part_%02d.wrl" % i)).write_text("x")


def test_kicad_sample_two_per_folder_fixed_by_seed(e2e, tmp_path):
    make_library(tmp_path / "a", {"A.3dshapes": 10, "B.3dshapes": 1, "C.3dshapes": 5})
    sample = e2e.kicad_sample(tmp_path / "a", "34")
    by_folder = {}
    for p in sample:
        by_folder.setdefault(p.parent.name, []).append(p.name)
    assert {k: len(v) for k, v in by_folder.items()} == {"A.3dshapes": 2, "B.3dshapes": 1,
                                                         "C.3dshapes": 2}
    assert all(p.suffix == ".step" for p in sample)
    assert sample == e2e.kicad_sample(tmp_path / "a", "34")
    # A folder's choice does not depend on the other folders.
    make_library(tmp_path / "b", {"A.3dshapes": 10, "Z.3dshapes": 3})
    other = e2e.kicad_sample(tmp_path / "b", "34")
    assert [p.name for p in other if p.parent.name == "A.3dshapes"] == by_folder["A.3dshapes"]
    # Another seed picks other files somewhere (10 choose 2 and 5 choose 2: not all equal).
    seeds = {tuple(p.name for p in e2e.kicad_sample(tmp_path / "a", s)) for s in range(8)}
    assert len(seeds) > 1


def test_geomean_and_last_json(e2e):
    assert e2e.geomean([0.5, 2.0]) == pytest.approx(1.0)
    assert e2e.geomean([1.0, 4.0, None]) == pytest.approx(2.0)
    assert e2e.geomean([]) is None
    assert e2e.last_json('noise\n{"a": 1}\ntext after\n') == {"a": 1}
    assert e2e.last_json("{broken\n") is None


def test_load_stages_reports_what_is_there(e2e):
    assert e2e.load_stages({"load_seconds": 1.0, "seconds": 2.0}) is None
    stages = {"read": 0.1, "transfer": 0.2}
    assert e2e.load_stages({"load_seconds": 1.0, "load_stages": stages}) == {
        "load_stages": stages}
    assert e2e.flat_stages({"load_stages": stages}) == stages
    assert e2e.flat_stages({"load_stages": {"occt": {"parse": 1.0}, "n": "x"}, "load_x": 2}) == {
        "load_stages.occt.parse": 1.0, "load_x": 2}


def row(e2e, name, group, ours, plain, load=None, read=None):
    runs = {"rdmesh": [{"wall": w, "cpu": w, "code": 0, "report": {
                "faces": [{}] * 40, "load_seconds": load or w / 2, "seconds": 0.01,
                "triangles": 100, "requested_deviation": 0.01}} for w in ours],
            "plain": [{"wall": w, "cpu": w, "code": 0, "report": {
                "faces": 40, "read_seconds": (read or w / 2) / 2,
                "transfer_seconds": (read or w / 2) / 2, "triangles": 90,
                "deflection": 0.011}} for w in plain]}
    path = pathlib.Path(__file__)
    r = e2e.summarize_file(path, group, runs)
    r["name"] = name
    return r


def test_summary_medians_ratios_and_files_above_one(e2e):
    rows = [row(e2e, "k1", "kicad", [1.0, 9.0, 1.0], [2.0, 2.0, 0.1]),  # medians 1 / 2
            row(e2e, "k2", "kicad", [3.0, 3.0, 3.0], [1.5, 1.5, 1.5]),  # 2.0x
            row(e2e, "c1", "corpus", [1.0, 1.0, 1.0], [4.0, 4.0, 4.0])]  # 0.25x
    assert rows[0]["ratio"] == pytest.approx(0.5)
    assert rows[0]["faces"] == 40 and rows[0]["deflection_ratio"] == pytest.approx(1.1)
    s = e2e.summarize(rows)
    assert s["kicad"]["ratio_geomean"] == pytest.approx(1.0)
    assert s["corpus"]["ratio_geomean"] == pytest.approx(0.25)
    assert s["all"]["ratio_geomean"] == pytest.approx(math.exp(math.log(0.25) / 3))
    assert s["max_ratio"] == {"name": "k2", "ratio": pytest.approx(2.0)}
    assert [a["name"] for a in s["above_1"]] == ["k2"]
    # load_seconds = wall/2 of rdmesh, read+transfer = wall/2 of plain: the same ratio.
    assert s["kicad"]["load_ratio_geomean"] == pytest.approx(1.0)


def test_failed_side_is_listed_not_averaged(e2e):
    ok = row(e2e, "k1", "kicad", [1.0] * 3, [2.0] * 3)
    runs = {"rdmesh": [{"wall": 1.0, "cpu": 1.0, "code": 3, "report": None,
                        "error": "cannot read"}] * 3,
            "plain": [{"wall": 1.0, "cpu": 1.0, "code": 0, "report": {}}] * 3}
    bad = e2e.summarize_file(pathlib.Path(__file__), "corpus", runs)
    s = e2e.summarize([ok, bad])
    assert s["measured"] == 1 and s["corpus"]["files"] == 0
    assert s["failed"][0]["errors"] == {"rdmesh": "cannot read"}


STAND_IN = """#!/bin/sh
# A stand-in for %(what)s: records its arguments, writes its output file, prints a JSON line.
echo "$@" >> %(log)s
%(body)s
"""


def stand_in(path, what, log, body):
    path.write_text(STAND_IN % {"what": what, "log": log, "body": body})
    path.chmod(path.stat().st_mode | stat.S_IEXEC)
    return path


def test_whole_run_on_stand_ins(e2e, tmp_path):
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    for name in ("a.step", "b.stp", "notes.txt"):
        (corpus / name).write_text("ISO-10303-21;")
    log = tmp_path / "calls.log"
    rdmesh = stand_in(tmp_path / "rdmesh", "rdmesh", log, """
if [ "$1" = "--help" ]; then echo usage; exit 0; fi
touch "$4"
echo '{"faces": [{}, {}], "load_seconds": 0.01, "seconds": 0.001, "triangles": 8,
 "load_stages": {"parse": 0.004, "transfer": 0.005},
 "requested_deviation": 0.001}' | tr -d '\\n'; echo""")
    plain = stand_in(tmp_path / "plain_runner", "plain_runner", log, """
if [ $# -eq 0 ]; then echo usage >&2; exit 2; fi
touch "$2"
echo '{"read_seconds": 0.01, "transfer_seconds": 0.01, "faces": 2, "triangles": 6,
 "deflection": 0.001}' | tr -d '\\n'; echo""")
    out, results = tmp_path / "PARSE.md", tmp_path / "parse.json"
    assert e2e.main(["--no-kicad", "--corpus", str(corpus), "--rdmesh", str(rdmesh),
                     "--plain-runner", str(plain), "--out", str(out), "--json",
                     str(results)]) == 0
    data = json.loads(results.read_text())
    assert [r["name"] for r in data["rows"]] == ["a.step", "b.stp"]
    assert all(not r["errors"] and r["faces"] == 2 for r in data["rows"])
    calls = log.read_text().splitlines()
    mesh_calls = [c for c in calls if c.startswith("mesh ")]
    # 3 rounds for each of the 2 files, then 7 pairs on the file nearest 50 faces.
    assert len(mesh_calls) == 3 * 2 + 7
    assert all("--max-deviation-rel 0.001 --json" in c for c in mesh_calls)
    plain_calls = [c for c in calls if c.endswith(".plain.msh")]
    assert len(plain_calls) == 3 * 2 + 7
    assert "--help" in calls and "" in calls  # the fixed cost: rdmesh --help, bare plain_runner
    text = out.read_text()
    assert text.index("## Summary") < text.index("## Per file")
    assert "| corpus | 2 |" in text and "load average before" in text
    assert "parse 0.004, transfer 0.005 |" in text  # the per-file stages column
    assert "parse 0.01 s (40%)" in text  # the summary: 2 x 0.004 of 2 x 0.01
    # --results-only renders the same markdown from the JSON.
    again = tmp_path / "again.md"
    e2e.main(["--results-only", str(results), "--out", str(again)])
    assert again.read_text() == text


def test_child_env_drops_what_changes_a_run(e2e, monkeypatch):
    monkeypatch.setenv("RDMESH_CACHE_DIR", "/tmp/store")
    monkeypatch.setenv("RDMESH_STEP_READER", "rdmesh")
    env = e2e.child_env()
    assert "RDMESH_CACHE_DIR" not in env and "RDMESH_STEP_READER" not in env
    assert env["PATH"] == os.environ["PATH"]
    assert e2e.child_env(["RDMESH_STEP_READER=rdmesh"])["RDMESH_STEP_READER"] == "rdmesh"
