"""`rdmesh mesh --compress` (issue 37): a .glb with EXT_meshopt_compression and
KHR_mesh_quantization that three.js reads, with meshoptimizer's decoder, as the same triangles
as the plain file of the same mesh (every vertex within 2% of the requested deviation, face ids
and edge ids unchanged), at most a quarter of its bytes, and clean in the Khronos validator
both as written and decoded back to a plain glTF."""

import json
import struct

import numpy as np
import pytest

import conftest

CORPUS_MODEL = "nist_ctc_02_asme1_ap242.stp"  # issue 37's example: 391,808 bytes plain
SHARE = 0.015  # kCompressRoundingShare (engine/include/rdmesh/options.h)

# conftest's three.js loader with meshoptimizer's decoder (three ships it), also returning the
# binary tables the compressed file names in extras: per edges primitive its edge table, and
# the root's per-face surface types.
THREE_MESHOPT_MJS = conftest.THREE_LOAD_MJS.replace(
    "const bytes =",
    "import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';\n"
    "const print = console.log.bind(console);\n"
    "console.log = console.warn = () => {};  // three's notes on de-interleaving\n"
    "const flat = (a) => Array.from({length: a.count}, (_, i) => a.getX(i));\n"
    "// Quantized attributes as floats (clone() keeps Int16 and would round the world values).\n"
    "const floats = (a) => new THREE.Float32BufferAttribute(\n"
    "    Array.from({length: a.count}, (_, i) => [a.getX(i), a.getY(i), a.getZ(i)]).flat(), 3);\n"
    "const bytes =", 1).replace(
    "g.attributes.position.clone()", "floats(g.attributes.position)", 1).replace(
    "g.attributes.normal.clone()", "floats(g.attributes.normal)", 1).replace(
    "Array.from(g.attributes._face_id.array)", "flat(g.attributes._face_id)", 1).replace(
    "Array.from(g.attributes._edge_id.array)", "flat(g.attributes._edge_id)", 1).replace(
    "new GLTFLoader().parse(buffer, '', (gltf) => {",
    "new GLTFLoader().setMeshoptDecoder(MeshoptDecoder).parse(buffer, '', async (gltf) => {\n"
    "  const array = async (i) => Array.from((await gltf.parser.getDependency('accessor', i)).array);\n"
    "  const tables = {edges: [], surface_type: null};\n"
    "  for (const m of gltf.parser.json.meshes) for (const p of m.primitives) {\n"
    "    const t = p.extras && p.extras.edge_table;\n"
    "    if (t) tables.edges.push({id: await array(t.id), flags: await array(t.flags),\n"
    "                              dihedral: await array(t.dihedral), faces: await array(t.faces)});\n"
    "  }\n"
    "  const r = gltf.parser.json.extras && gltf.parser.json.extras.rdmesh;\n"
    "  if (r && r.faces) tables.surface_type = await array(r.faces.surface_type);\n", 1).replace(
    "console.log(JSON.stringify({extras:", "print(JSON.stringify({tables, extras:", 1)
assert "tables, extras" in THREE_MESHOPT_MJS and "flat(g.attributes._edge_id)" in THREE_MESHOPT_MJS
assert "floats(g.attributes.normal)" in THREE_MESHOPT_MJS

# Decodes every compressed buffer view into the fallback buffer and writes a plain .glb (only
# KHR_mesh_quantization left), which the validator can check to the last accessor.
DECOMPRESS_MJS = r"""
import fs from 'fs';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
const bytes = fs.readFileSync(process.argv[2]);
const jsonLength = bytes.readUInt32LE(12);
const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString());
const bin = bytes.subarray(28 + jsonLength);
await MeshoptDecoder.ready;
const fallback = json.buffers.findIndex((b) => b.extensions && b.extensions.EXT_meshopt_compression);
const out = new Uint8Array(json.buffers[fallback].byteLength);
for (const view of json.bufferViews) {
  const m = view.extensions.EXT_meshopt_compression;
  const target = new Uint8Array(m.count * m.byteStride);
  MeshoptDecoder.decodeGltfBuffer(target, m.count, m.byteStride,
      bin.subarray(m.byteOffset, m.byteOffset + m.byteLength), m.mode, m.filter || 'NONE');
  out.set(target.subarray(0, view.byteLength), view.byteOffset);
  view.buffer = 0;
  delete view.extensions;
}
json.buffers = [{byteLength: out.length}];
for (const list of ['extensionsUsed', 'extensionsRequired'])
  json[list] = json[list].filter((e) => e !== 'EXT_meshopt_compression');
let text = Buffer.from(JSON.stringify(json));
text = Buffer.concat([text, Buffer.alloc((4 - text.length % 4) % 4, 0x20)]);
const body = Buffer.concat([Buffer.from(out), Buffer.alloc((4 - out.length % 4) % 4)]);
const header = Buffer.alloc(12);
header.write('glTF', 0); header.writeUInt32LE(2, 4);
header.writeUInt32LE(12 + 8 + text.length + 8 + body.length, 8);
const chunk = (length, type) => { const b = Buffer.alloc(8); b.writeUInt32LE(length, 0); b.write(type, 4); return b; };
fs.writeFileSync(process.argv[2] + '.plain.glb', Buffer.concat(
    [header, chunk(text.length, 'JSON'), text, chunk(body.length, 'BIN\0'), body]));
console.log(JSON.stringify({views: json.bufferViews.length}));
"""


@pytest.fixture(scope="session")
def three_meshopt():
    return conftest._node_script("three", "three_load_meshopt.mjs", THREE_MESHOPT_MJS)


@pytest.fixture(scope="session")
def decompress():
    return conftest._node_script("three", "decompress_glb.mjs", DECOMPRESS_MJS)


def glb_json(path):
    data = path.read_bytes()
    (length,) = struct.unpack_from("<I", data, 12)
    return json.loads(data[20:20 + length])


def corners(loaded, kind):
    """Per drawn object of `kind`: world positions (n, 3) of each element's corners and their
    ids (face ids, instance-mapped, or edge ids)."""
    out = []
    for o in loaded["objects"]:
        if o["kind"] != kind:
            continue
        ids = np.array(o["face_id" if kind == "triangles" else "edge_id"], dtype=float)
        if "face_map" in o:
            ids = np.array([o["face_map"].get(str(int(f)), f) for f in ids], dtype=float)
        index = np.array(o["index"], dtype=np.int64)
        position = np.array(o["position"]).reshape(-1, 3)
        out.append((position[index], ids[index].astype(int)))
    return out


def same_elements(plain, packed, tolerance, per):
    """Every element (triangle or segment) of `packed` is one of `plain`'s with the same id,
    each corner within `tolerance`; returns the largest corner distance."""
    p_xyz = np.concatenate([x for x, _ in plain])
    p_ids = np.concatenate([i for _, i in plain])
    c_xyz = np.concatenate([x for x, _ in packed])
    c_ids = np.concatenate([i for _, i in packed])
    assert len(p_xyz) == len(c_xyz)
    # One id per element; group by it and match corners by nearest plain corner.
    p_el = p_ids.reshape(-1, per)
    c_el = c_ids.reshape(-1, per)
    assert (p_el == p_el[:, :1]).all() and (c_el == c_el[:, :1]).all()
    worst = 0.0
    for element_id in np.unique(p_el[:, 0]):
        pm = np.flatnonzero(p_el[:, 0] == element_id)
        cm = np.flatnonzero(c_el[:, 0] == element_id)
        assert len(pm) == len(cm), f"id {element_id}: {len(pm)} plain, {len(cm)} compressed"
        pts = p_xyz.reshape(-1, per, 3)[pm].reshape(-1, 3)
        unique, inverse = np.unique(pts, axis=0, return_inverse=True)
        plain_keys = {tuple(sorted(k)) for k in inverse.reshape(-1, per)}
        c_pts = c_xyz.reshape(-1, per, 3)[cm].reshape(-1, 3)
        d = np.linalg.norm(c_pts[:, None, :] - unique[None, :, :], axis=2)
        nearest = d.argmin(axis=1)
        worst = max(worst, float(d.min(axis=1).max()))
        packed_keys = {tuple(sorted(k)) for k in nearest.reshape(-1, per)}
        assert packed_keys == plain_keys, f"id {element_id}: the elements differ"
    assert worst <= tolerance, (worst, tolerance)
    return worst


def write_decoded_msh(loaded, path):
    """The triangles three.js reads (world metres, +Y up) as MSH 4.1 in the model's frame (mm,
    +Z up), one element block per face id, for the yardstick."""
    points, blocks = [], {}
    for xyz, ids in corners(loaded, "triangles"):
        # xyz: three corners per triangle, in order; ids: the corners' face ids.
        model = np.stack([xyz[:, 0], -xyz[:, 2], xyz[:, 1]], axis=1) * 1e3
        base = len(points)
        points.extend(model)
        for t, face in enumerate(ids[::3]):
            blocks.setdefault(int(face), []).append(base + 3 * t + np.arange(1, 4))
    count = sum(len(b) for b in blocks.values())
    lines = ["$MeshFormat", "4.1 0 8", "$EndMeshFormat", "$Nodes",
             "1 %d 1 %d" % (len(points), len(points)), "2 1 0 %d" % len(points)]
    lines += [str(i + 1) for i in range(len(points))]
    lines += ["%.17g %.17g %.17g" % tuple(p) for p in points]
    lines += ["$EndNodes", "$Elements", "%d %d 1 %d" % (len(blocks), count, count)]
    tag = 1
    for face in sorted(blocks):
        lines.append("2 %d 2 %d" % (face, len(blocks[face])))
        for corner in blocks[face]:
            lines.append("%d %d %d %d" % (tag, *corner))
            tag += 1
    lines.append("$EndElements")
    path.write_text("\n".join(lines) + "\n")


def mesh_pair(run, model, tmp_path, *options):
    """The compressed file and the plain file of the same mesh: --compress meshes to
    (1 - SHARE) of the deviation, which a plain run asks for directly (as an absolute deviation
    computed as the engine computes it, so the mesh is the same to the bit)."""
    packed = tmp_path / "packed.glb"
    result = run("mesh", model, "-o", packed, "--compress", "--json", *options)
    assert result.code == 0, result.stderr
    report = result.json
    plain = tmp_path / "plain.glb"
    plain_run = run("mesh", model, "-o", plain, "--json", "--max-deviation",
                    repr(report["requested_deviation"] * (1 - SHARE)))
    assert plain_run.code == 0, plain_run.stderr
    assert plain_run.json["triangles"] == report["triangles"]
    assert plain_run.json["nodes"] == report["nodes"]
    return packed, plain, report


@pytest.mark.parametrize("model", ["corpus", "pyocc_eight_cyl.stp"])
def test_compressed_glb_reads_as_the_plain_one(run, data_dir, shared_dir, tmp_path, model,
                                               gltf_validate, three_load, three_meshopt,
                                               decompress, request):
    meshbench = None
    if model == "corpus":
        path = shared_dir / "corpus" / CORPUS_MODEL
        if not path.is_file():
            pytest.skip(f"{path} is absent")
        meshbench = request.getfixturevalue("meshbench")  # the yardstick: corpus model only
    else:
        path = data_dir / model
    packed, plain, report = mesh_pair(run, path, tmp_path)
    requested = report["requested_deviation"]
    assert requested > 0

    # Size: at most a quarter of the plain file, edges included. A small model's file is mostly
    # the JSON of its nodes, meshes and materials, which both files share (eight solids: 0.48x).
    ratio = packed.stat().st_size / plain.stat().st_size
    assert ratio <= (0.25 if model == "corpus" else 0.6), ratio

    # The validator: clean as written, and decoded back to plain buffers (which it checks to
    # every accessor's bounds and index).
    validation = gltf_validate(packed)
    assert validation["errors"] == 0 and validation["warnings"] == 0, validation["messages"]
    assert validation["triangles"] == report["triangles"]
    decompress(packed)
    decoded = gltf_validate(str(packed) + ".plain.glb")
    assert decoded["errors"] == 0 and decoded["warnings"] == 0, decoded["messages"]
    assert decoded["triangles"] == report["triangles"]
    layout = glb_json(packed)
    assert {"EXT_meshopt_compression", "KHR_mesh_quantization"} <= set(layout["extensionsRequired"])

    # three.js: the same triangles with the same face ids, every vertex within 2% of the
    # requested deviation (metres in glTF, mm in the model), the same edge segments with the
    # same edge ids.
    a = three_load(plain)
    b = three_meshopt(packed)
    tolerance = 0.02 * requested * 1e-3
    worst = same_elements(corners(a, "triangles"), corners(b, "triangles"), tolerance, 3)
    assert worst <= SHARE * requested * 1e-3 * (1 + 1e-4)
    same_elements(corners(a, "lines"), corners(b, "lines"), tolerance, 2)
    # The rounding fits in what the mesh left free: estimated deviation + rounding <= request.
    assert report["estimated_deviation"] + worst * 1e3 <= requested * (1 + 1e-9)

    # Normals: octahedral 10-bit, within 0.25 degrees of the plain file's (matched by position;
    # a node on a seam is in its face twice, with two normals: the nearer one counts).
    for o_plain, o_packed in zip([o for o in a["objects"] if o["kind"] == "triangles"],
                                 [o for o in b["objects"] if o["kind"] == "triangles"]):
        p = np.array(o_plain["position"]).reshape(-1, 3)
        n = np.array(o_plain["normal"]).reshape(-1, 3)
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        q = np.array(o_packed["position"]).reshape(-1, 3)
        m = np.array(o_packed["normal"]).reshape(-1, 3)
        m /= np.linalg.norm(m, axis=1, keepdims=True)
        fp = np.array(o_plain["face_id"])
        fq = np.array(o_packed["face_id"])
        for f in np.unique(fq):
            i = np.flatnonzero(fp == f)
            j = np.flatnonzero(fq == f)
            d = np.linalg.norm(q[j][:, None, :] - p[i][None, :, :], axis=2)
            coincident = d <= d.min(axis=1, keepdims=True) + 1e-9
            cosine = np.where(coincident, m[j] @ n[i].T, -1.0).max(axis=1)
            angle = np.degrees(np.arccos(np.clip(cosine, -1, 1)))
            assert angle.max() < 0.25, (f, angle.max())

    # The edge table, in binary accessors where that is smaller, says what the plain file's
    # JSON says.
    plain_edges = {}
    for primitive in (p for m in a["primitives"] for p in m):
        for e in (primitive["extras"] or {}).get("edges", []):
            plain_edges[e["id"]] = e
    assert plain_edges
    packed_edges = {}
    for table in b["tables"]["edges"]:
        at = 0
        for eid, flags, dihedral in zip(table["id"], table["flags"], table["dihedral"]):
            count = flags >> 8
            packed_edges[eid] = {"faces": table["faces"][at:at + count], "seam": bool(flags & 1),
                                 "sharp": bool(flags & 2), "dihedral": dihedral}
            at += count
        assert at == len(table["faces"])
    for primitive in (p for m in b["primitives"] for p in m):  # tables kept in JSON
        for e in (primitive["extras"] or {}).get("edges", []):
            packed_edges[e["id"]] = e
    if model == "corpus":
        assert b["tables"]["edges"], "the corpus model's edge tables are smaller in binary"
    assert packed_edges.keys() == plain_edges.keys()
    for eid, e in plain_edges.items():
        c = packed_edges[eid]
        assert (c["faces"], c["seam"], c["sharp"]) == (e["faces"], e["seam"], e["sharp"]), eid
        assert abs(c["dihedral"] - e["dihedral"]) <= 1e-5 * max(1.0, abs(e["dihedral"]))

    # The yardstick on the triangles three.js decoded (rounding included): within the request,
    # and no farther than the plain mesh's measure plus the rounding.
    if meshbench is not None:
        write_decoded_msh(b, tmp_path / "decoded.msh")
        decoded = meshbench(path, tmp_path / "decoded.msh")
        plain_msh = tmp_path / "plain.msh"
        assert run("mesh", path, "-o", plain_msh, "--max-deviation",
                   repr(requested * (1 - SHARE))).code == 0
        measured = meshbench(path, plain_msh)
        assert decoded["faces_covered"] == measured["faces_covered"]
        assert decoded["hausdorff_rel"] <= measured["hausdorff_rel"] + 1.01 * SHARE * 1e-3
        assert decoded["hausdorff_rel"] <= 1e-3, decoded

    # Per face its surface type, as the run reported it.
    types = b["extras"]["rdmesh"]["faces"]["surface_types"]
    codes = b["tables"]["surface_type"]
    for face in report["faces"]:
        assert types[codes[face["id"] - 1]] == face["surface_type"]


def test_compressed_instanced_assembly(run, shared_dir, tmp_path, gltf_validate, three_load,
                                       three_meshopt):
    """Instances keep their face-id maps on the nodes that now carry the grid and draw one copy
    of the mesh OCCT wrote per instance."""
    model = shared_dir / "corpus" / "gmsh_presse_asm.step"
    if not model.is_file():
        pytest.skip(f"{model} is absent")
    packed, plain, report = mesh_pair(run, model, tmp_path)
    assert gltf_validate(packed)["errors"] == 0
    a, b = three_load(plain), three_meshopt(packed)
    assert any("face_map" in o for o in b["objects"])
    # OCCT writes a mesh per node; the compressed file keeps one of equal copies. The solids'
    # edge meshes become one.
    def drawn(layout, mode):
        return [n["mesh"] for n in layout["nodes"] if "mesh" in n and
                layout["meshes"][n["mesh"]]["primitives"][0].get("mode", 4) == mode]

    p_layout, c_layout = glb_json(plain), glb_json(packed)
    assert len(drawn(c_layout, 4)) == len(drawn(p_layout, 4))
    assert len(set(drawn(c_layout, 4))) < len(set(drawn(p_layout, 4))) == len(drawn(p_layout, 4))
    assert len(drawn(c_layout, 1)) == 1 < len(drawn(p_layout, 1))
    groups = c_layout["meshes"][drawn(c_layout, 1)[0]]["primitives"][0]["extras"]["groups"]
    assert [g["name"] for g in groups] == [p_layout["meshes"][m]["name"]
                                           for m in drawn(p_layout, 1)]
    same_elements(corners(a, "triangles"), corners(b, "triangles"),
                  0.02 * report["requested_deviation"] * 1e-3, 3)


def test_compressed_levels(run, data_dir, tmp_path, gltf_validate, three_meshopt):
    """--lod with --compress: every level compressed, each within its own level's budget."""
    model = data_dir / "pyocc_eight_cyl.stp"
    out = tmp_path / "levels.glb"
    result = run("mesh", model, "-o", out, "--compress", "--lod", "1e-2,1e-3")
    assert result.code == 0, result.stderr
    sizes = []
    for level in range(2):
        path = tmp_path / f"levels.lod{level}.glb"
        assert "EXT_meshopt_compression" in glb_json(path)["extensionsRequired"]
        assert gltf_validate(path)["errors"] == 0
        loaded = three_meshopt(path)
        assert [o for o in loaded["objects"] if o["kind"] == "triangles"]
        sizes.append(path.stat().st_size)
    assert sizes[0] < sizes[1]


def test_compress_usage(run, data_dir, tmp_path):
    model = data_dir / "axom_sliced_cylinder.step"
    refused = run("mesh", model, "-o", tmp_path / "out.msh", "--compress")
    assert refused.code == 2 and "--compress writes .glb only" in refused.stderr
    budget = run("mesh", model, "-o", tmp_path / "out.glb", "--compress", "--max-triangles", "100")
    assert budget.code == 2 and "--compress needs a max deviation" in budget.stderr
