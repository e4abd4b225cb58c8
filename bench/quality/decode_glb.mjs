// Reads a .glb as a viewer does (three.js GLTFLoader with meshoptimizer's decoder) and prints
// its drawn triangles as JSON: world positions (metres, +Y up), face ids (an instance's own, via
// extras.rdmesh.face_ids) and indices, per triangle object. bench/quality/glb_size.py runs it
// from a directory where npm installed three (the tests' node_tools).
//   node decode_glb.mjs FILE.glb
import fs from 'fs';
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';

const print = console.log.bind(console);
console.log = console.warn = () => {};
const bytes = fs.readFileSync(process.argv[2]);
const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
new GLTFLoader().setMeshoptDecoder(MeshoptDecoder).parse(buffer, '', (gltf) => {
  gltf.scene.updateMatrixWorld(true);
  const objects = [];
  gltf.scene.traverse((o) => {
    if (!o.isMesh || !o.geometry.attributes._face_id) return;
    const g = o.geometry, p = g.attributes.position, ids = g.attributes._face_id;
    let map = null;
    for (let q = o; q && !map; q = q.parent) map = q.userData?.rdmesh?.face_ids || null;
    const v = new THREE.Vector3();
    const position = [], face = [];
    for (let i = 0; i < p.count; ++i) {
      v.fromBufferAttribute(p, i).applyMatrix4(o.matrixWorld);
      position.push(v.x, v.y, v.z);
      const id = Math.round(ids.getX(i));
      face.push(map && map[String(id)] !== undefined ? map[String(id)] : id);
    }
    objects.push({ position, face, index: Array.from(g.index.array) });
  });
  print(JSON.stringify(objects));
}, (error) => { console.error(String(error)); process.exit(1); });
