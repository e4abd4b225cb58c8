"""The viewer page (clients/web, issue 37) in Debian's headless Chromium: built by its own npm
build step, served on loopback, opened with ?url= on a .glb written with --compress. Through the
page's JavaScript (tests/web/drive_viewer.mjs, over the DevTools protocol) the test checks the
triangle count against the CLI's report, the face id picked at known pixels against a ray cast
here through the plain file's triangles, that the B-rep edges are drawn (and go when hidden),
and saves a screenshot that must not be blank. A --lod run loads coarse first, then fine."""

import functools
import http.server
import importlib.util
import json
import os
import pathlib
import shutil
import struct
import subprocess
import threading
import zlib

import numpy as np
import pytest

HERE = pathlib.Path(__file__).resolve().parent
MODEL = "cq_red_cube_blue_cylinder.step"  # bundled; a red cube and a blue cylinder
SHARE = 0.015  # kCompressRoundingShare: a --compress run meshes to (1 - SHARE) of the deviation
BACKGROUND = (0xF2, 0xF3, 0xF5)  # the page's scene background
VIEWPORT = (960, 640)  # drive_viewer.mjs's page size, CSS pixels


def _env(name):
    value = os.environ.get(name)
    assert value, f"{name} is not set (run these tests through ctest)"
    return pathlib.Path(value)


def _cli_fixtures():
    """tests/cli/conftest.py (its node script runner and three.js loader), under another name."""
    spec = importlib.util.spec_from_file_location("cli_fixtures", HERE.parent / "cli" / "conftest.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def site(tmp_path_factory):
    """The page as its build step makes it: clients/web copied under the build tree, `npm ci`
    (the pinned three.js and meshoptimizer), `npm run build` into a directory served as is."""
    source, work = _env("RDMESH_WEB_SOURCE"), _env("RDMESH_WEB_DIR")
    work.mkdir(parents=True, exist_ok=True)
    for name in ("package.json", "package-lock.json", "build.mjs"):
        shutil.copy2(source / name, work / name)
    shutil.copytree(source / "src", work / "src", dirs_exist_ok=True)
    stamp = work / "node_modules" / ".rdmesh-lock"
    lock = (source / "package-lock.json").read_text()
    if not stamp.is_file() or stamp.read_text() != lock:
        subprocess.run(["npm", "ci", "--no-audit", "--no-fund"], cwd=work, check=True,
                       capture_output=True, timeout=600)
        stamp.write_text(lock)
    out = tmp_path_factory.mktemp("site")
    subprocess.run(["npm", "run", "build", "--", str(out)], cwd=work, check=True,
                   capture_output=True, timeout=120)
    assert (out / "index.html").is_file() and (out / "vendor" / "three").is_dir()
    return out


@pytest.fixture(scope="session")
def server(site):
    """A loopback HTTP server for the built page and the files the tests put next to it."""
    handler = functools.partial(_QuietHandler, directory=str(site))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}"
    httpd.shutdown()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@pytest.fixture(scope="session")
def chromium():
    path = shutil.which("chromium")
    assert path, "Debian's chromium is not installed (scripts/install-deps.sh)"
    return path


def rdmesh(*args):
    completed = subprocess.run([str(_env("RDMESH_CLI")), *map(str, args)], capture_output=True,
                               text=True, timeout=300)
    assert completed.returncode == 0, completed.stderr
    lines = [line for line in completed.stdout.splitlines() if line.strip()]
    return json.loads(lines[-1]) if "--json" in args else None


def drive(chromium, url, screenshot, pixels=()):
    completed = subprocess.run(
        ["node", "--experimental-websocket", str(HERE / "drive_viewer.mjs"), chromium, url,
         str(screenshot), json.dumps([list(p) for p in pixels])],
        capture_output=True, text=True, timeout=90)
    assert completed.returncode == 0, completed.stderr
    return json.loads(completed.stdout.splitlines()[-1])


def png_pixels(path):
    """(height, width, channels) uint8 pixels of an 8-bit non-interlaced RGB(A) PNG."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    at, idat = 8, b""
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        at += 12 + length
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
    assert depth == 8 and interlace == 0 and colour in (2, 6), (depth, colour, interlace)
    channels = 3 if colour == 2 else 4
    stride = width * channels
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(height, stride + 1)
    out = np.zeros((height, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.int64)
    for y in range(height):
        kind, line = raw[y, 0], raw[y, 1:].astype(np.int64)
        if kind == 0:
            cur = line
        elif kind == 1:  # Sub: a running sum per channel
            cur = np.cumsum(line.reshape(-1, channels), axis=0).ravel() & 255
        elif kind == 2:
            cur = (line + prev) & 255
        else:  # Average, Paeth: left to right
            cur = line.copy()
            for x in range(stride):
                a = cur[x - channels] if x >= channels else 0
                b = prev[x]
                c = prev[x - channels] if x >= channels else 0
                if kind == 3:
                    cur[x] = (line[x] + (a + b) // 2) & 255
                else:
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    predictor = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                    cur[x] = (line[x] + predictor) & 255
        out[y] = cur
        prev = cur
    return out.reshape(height, width, channels)


def triangles_of(loaded):
    """World corners (n, 3, 3) and face ids (n,) of every drawn triangle of three_load's output."""
    xyz, ids = [], []
    for o in loaded["objects"]:
        if o["kind"] != "triangles":
            continue
        face = np.array(o["face_id"], dtype=float)
        if "face_map" in o:
            face = np.array([o["face_map"].get(str(int(f)), f) for f in face])
        index = np.array(o["index"], dtype=np.int64).reshape(-1, 3)
        xyz.append(np.array(o["position"]).reshape(-1, 3)[index])
        ids.append(face[index[:, 0]].astype(int))
    return np.concatenate(xyz), np.concatenate(ids)


def cast(triangles, origin, direction, margin):
    """The face id of the nearest triangle the ray hits (Moller-Trumbore), or None when the
    nearest hit lies within `margin` (barycentric) of its triangle's border: a pick there could
    go either way once positions are rounded."""
    xyz, ids = triangles
    o, d = np.array(origin), np.array(direction)
    e1, e2 = xyz[:, 1] - xyz[:, 0], xyz[:, 2] - xyz[:, 0]
    p = np.cross(d, e2)
    det = (e1 * p).sum(axis=1)
    ok = np.abs(det) > 1e-18
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = o - xyz[:, 0]
    u = (s * p).sum(axis=1) * inv
    q = np.cross(s, e1)
    v = (q * d).sum(axis=1) * inv
    t = (e2 * q).sum(axis=1) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    if not hit.any():
        return None
    k = np.flatnonzero(hit)[np.argmin(t[hit])]
    if min(u[k], v[k], 1 - u[k] - v[k]) < margin:
        return None
    return int(ids[k])


def test_viewer_in_chromium(site, server, chromium, tmp_path):
    model = _env("RDMESH_TEST_DATA") / MODEL
    report = rdmesh("mesh", model, "-o", site / "model.glb", "--compress", "--json")
    # The plain file of the same mesh, loaded by three.js in node: the independent reference.
    plain = tmp_path / "plain.glb"
    rdmesh("mesh", model, "-o", plain, "--max-deviation",
           repr(report["requested_deviation"] * (1 - SHARE)))
    cli = _cli_fixtures()
    reference = cli._node_script("three", "three_load.mjs", cli.THREE_LOAD_MJS)(plain)
    triangles = triangles_of(reference)
    segments = sum(len(o["index"]) // 2 for o in reference["objects"] if o["kind"] == "lines")

    screenshot = tmp_path / "viewer.png"
    width, height = VIEWPORT
    pixels = [(width // 2 + dx, height // 2 + dy) for dx in (0, -60, 60) for dy in (0, -40, 40)]
    result = drive(chromium, f"{server}/index.html?url=model.glb", screenshot, pixels)
    assert not result["console"], result["console"]
    stats = result["stats"]

    # Every triangle of the run is drawn, and every edge segment; hiding edges draws none.
    assert stats["triangles"] == report["triangles"] == stats["drawnTriangles"]
    assert stats["edgeSegments"] == segments > 0
    assert stats["drawnLines"] == segments
    assert 0 < stats["sharpSegments"] <= segments  # the cube's edges are sharp
    assert result["noEdges"]["drawnLines"] == 0
    assert stats["hasSurfaceTypes"] and stats["hasDeviation"]
    assert result["deviation"]["drawnTriangles"] == report["triangles"]

    # Picks: the page's face id under each pixel is the one a ray through the plain file's
    # triangles meets first (pixels where that is ambiguous are left out).
    surface = {f["id"]: f["surface_type"] for f in report["faces"]}
    checked = 0
    for entry in result["picks"]:
        expected = cast(triangles, entry["ray"]["origin"], entry["ray"]["direction"], 0.02)
        if expected is None:
            continue
        assert entry["pick"] is not None, entry
        assert entry["pick"]["face"] == expected, entry
        assert entry["pick"]["surfaceType"] == surface[expected]
        checked += 1
    assert checked >= 3, result["picks"]
    # Hovering the first pixel (the centre) names its face and surface type.
    first = result["picks"][0]["pick"]
    assert result["hover"].startswith(f"face {first['face']} · {first['surfaceType']}")

    # The screenshot shows the model: many pixels away from the background, several colours
    # (the red cube, the blue cylinder, dark edges).
    image = png_pixels(screenshot)[..., :3].astype(int)
    assert image.shape[:2] == (height, width)
    assert (stats["width"], stats["height"]) == VIEWPORT
    away = np.abs(image - np.array(BACKGROUND)).sum(axis=2) > 30
    assert away.mean() > 0.05, away.mean()
    reds = ((image[..., 0] > image[..., 2] + 40) & away).sum()
    blues = ((image[..., 2] > image[..., 0] + 40) & away).sum()
    assert reds > 500 and blues > 500, (reds, blues)


def test_viewer_levels_coarse_then_fine(site, server, chromium, tmp_path):
    model = _env("RDMESH_TEST_DATA") / "pyocc_eight_cyl.stp"
    rdmesh("mesh", model, "-o", site / "levels.glb", "--compress", "--lod", "2e-2,1e-3")
    result = drive(chromium, f"{server}/index.html?url=levels.lod0.glb,levels.lod1.glb",
                   tmp_path / "levels.png")
    levels = result["levels"]
    assert [level["level"] for level in levels] == [0, 1]
    assert levels[0]["triangles"] < levels[1]["triangles"]
    assert result["stats"]["name"] == "levels.lod1.glb"
    assert result["stats"]["drawnTriangles"] == levels[1]["triangles"]
