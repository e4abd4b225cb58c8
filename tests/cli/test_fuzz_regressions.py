"""The inputs of tests/data/fuzz (crashes and hangs found by fuzzing): `rdmesh mesh` ends each
with the exit code and message its README documents, and never dies by a signal."""

import os
import pathlib
import re

import pytest

TIMEOUT = 2  # --timeout for every case; the slow and hanging ones end 2 s later (the watchdog)


def documented_cases(data_dir):
    """{file: (exit code, message fragment)} from the table in tests/data/fuzz/README.md."""
    cases = {}
    for line in (data_dir / "fuzz" / "README.md").read_text().splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) == 6 and re.fullmatch(r"`[\w.]+\.step`", cells[0]) and cells[4].isdigit():
            cases[cells[0].strip("`")] = (int(cells[4]), cells[5])
    return cases


# Read at collection, so that each case is a test of its own (conftest checks the variable).
CASES = documented_cases(pathlib.Path(os.environ["RDMESH_TEST_DATA"])) \
    if os.environ.get("RDMESH_TEST_DATA") else {}


def check_run(result, code, message):
    assert result.code >= 0, "died by signal %d" % -result.code
    assert result.code == code, result.stderr
    assert message in result.stderr
    if code == 0:  # meshed, with the failed faces reported
        assert result.json["faces_failed"] > 0
        return
    error = result.json
    assert error["exit_code"] == code
    assert message in error["error"]["message"]


def test_every_file_is_documented(data_dir):
    files = sorted(path.name for path in (data_dir / "fuzz").glob("*.step"))
    assert files and sorted(documented_cases(data_dir)) == files


@pytest.mark.parametrize("name", sorted(CASES))
def test_documented_exit(run, data_dir, tmp_path, name):
    code, message = CASES[name]
    result = run("mesh", data_dir / "fuzz" / name, "-o", tmp_path / "out.msh", "--json",
                 "--timeout", TIMEOUT, timeout=60)
    check_run(result, code, message)


def test_deep_parentheses_are_refused(run, data_dir, tmp_path):
    model = (data_dir / "axom_sliced_cylinder.step").read_text()
    data = model.index("DATA;") + len("DATA;")
    depth = 100000
    deep = tmp_path / "deep_parentheses.step"
    deep.write_text(model[:data] + "\n#99999=FOO(" + "(" * depth + "1" + ")" * depth + ");"
                    + model[data:])
    result = run("mesh", deep, "-o", tmp_path / "out.msh", "--json", timeout=60)
    check_run(result, 3, "parentheses nested more than 1000 deep")
