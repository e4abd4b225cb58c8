"""`rdmesh --cache-dir`: the persistent store of parsed models, across processes. A second run
reads the model that the first one parsed and wrote, and writes the same mesh bytes; a damaged
entry is parsed again; the directory keeps to its size limit."""

import os
import subprocess

import pytest

MODELS = ["cq_red_cube_blue_cylinder.step", "axom_sliced_cylinder.step", "pyocc_eight_cyl.stp",
          "nist_mbe_pmi_11.stp"]


def entries(store):
    return sorted(p for p in store.iterdir() if p.suffix == ".rdm")


@pytest.mark.parametrize("model", MODELS)
def test_second_process_reads_the_store(run, data_dir, tmp_path, model):
    store = tmp_path / "store"
    outputs = []
    reports = []
    for i in range(2):
        out = tmp_path / f"run{i}.msh"
        result = run("mesh", data_dir / model, "-o", out, "--cache-dir", store, "--json",
                     "--quiet")
        assert result.code == 0, result.stderr
        reports.append(result.json)
        outputs.append(out.read_bytes())
    assert reports[0]["from_store"] is False
    assert reports[1]["from_store"] is True
    assert "store_problem" not in reports[1]
    assert len(entries(store)) == 1
    assert outputs[0] == outputs[1]
    # Without a store: the same bytes again (every load goes through the same canonical form).
    plain = tmp_path / "plain.msh"
    result = run("mesh", data_dir / model, "-o", plain, "--json", "--quiet")
    assert result.code == 0, result.stderr
    assert "from_store" not in result.json
    assert plain.read_bytes() == outputs[0]


def test_info_reads_the_store_through_the_environment(cli, data_dir, tmp_path):
    store = tmp_path / "store"
    env = dict(os.environ, RDMESH_CACHE_DIR=str(store))
    infos = []
    for _ in range(2):
        completed = subprocess.run([str(cli), "info", str(data_dir / MODELS[0]), "--json"],
                                   capture_output=True, text=True, env=env, timeout=300)
        assert completed.returncode == 0, completed.stderr
        infos.append(__import__("json").loads(completed.stdout.splitlines()[-1]))
    assert [info["from_store"] for info in infos] == [False, True]
    for field in ("faces", "edges", "instances", "part_names", "bbox", "length_unit"):
        assert infos[0][field] == infos[1][field], field
    assert len(infos[1]["part_names"]) == 2


@pytest.mark.parametrize("damage", ["flip", "truncate"])
def test_damaged_entry_is_parsed_again(run, data_dir, tmp_path, damage):
    store = tmp_path / "store"
    model = data_dir / "pyocc_eight_cyl.stp"
    first = tmp_path / "first.msh"
    assert run("mesh", model, "-o", first, "--cache-dir", store, "--quiet").code == 0
    [entry] = entries(store)
    good = entry.read_bytes()
    if damage == "flip":
        bad = bytearray(good)
        bad[len(bad) // 2] ^= 0x40
        entry.write_bytes(bytes(bad))
    else:
        entry.write_bytes(good[: len(good) // 2])
    again = tmp_path / "again.msh"
    result = run("mesh", model, "-o", again, "--cache-dir", store, "--json", "--quiet")
    assert result.code == 0, result.stderr
    assert result.json["from_store"] is False
    assert ("checksum" if damage == "flip" else "truncated") in result.json["store_problem"]
    assert again.read_bytes() == first.read_bytes()
    assert entry.read_bytes() == good  # written again, whole


def test_store_keeps_to_its_limit(run, data_dir, tmp_path):
    store = tmp_path / "store"
    assert run("info", data_dir / MODELS[0], "--cache-dir", store, "--quiet").code == 0
    [entry] = entries(store)
    limit = entry.stat().st_size * 2 + 100
    for model in MODELS[1:]:
        result = run("info", data_dir / model, "--cache-dir", store, "--cache-dir-bytes", limit,
                     "--quiet")
        assert result.code == 0, result.stderr
        sizes = [p.stat().st_size for p in entries(store)]
        assert sum(sizes) <= limit or len(sizes) == 1, sizes


def test_unusable_store_still_loads(run, data_dir, tmp_path):
    store = tmp_path / "not_a_directory"
    store.write_text("a file where the store should be")
    result = run("info", data_dir / MODELS[0], "--cache-dir", store, "--json")
    assert result.code == 0, result.stderr
    assert result.json["from_store"] is False
    assert "cannot write" in result.json["store_problem"]
    assert "warning" in result.stderr
