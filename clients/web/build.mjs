// The build step (`npm run build [-- OUT_DIR]`, default dist/): the page and the npm modules it
// imports, vendored next to it, so OUT_DIR serves as static files with no network at run time.
import fs from 'fs';
import path from 'path';
import { fileURLToPath } from 'url';

const here = path.dirname(fileURLToPath(import.meta.url));
const out = path.resolve(process.argv[2] || path.join(here, 'dist'));
const modules = path.join(here, 'node_modules');

// What the import map of src/index.html names, copied under vendor/ with their own layout so the
// modules' relative imports resolve; the files those import are followed and copied too.
const entries = [
  ['three', 'build/three.module.js'],
  ['three', 'examples/jsm/loaders/GLTFLoader.js'],
  ['three', 'examples/jsm/controls/OrbitControls.js'],
  ['three', 'examples/jsm/environments/RoomEnvironment.js'],
  ['three', 'LICENSE'],
  ['meshoptimizer', 'meshopt_decoder.mjs'],
  ['meshoptimizer', 'LICENSE.md'],
];
const importPattern = /(?:\bfrom\s*|\bimport\s*\(?\s*)['"](\.{1,2}\/[^'"]+)['"]/g;

fs.rmSync(out, { recursive: true, force: true });
const copied = new Set();
const queue = entries.map(([pkg, file]) => [pkg, path.normalize(file)]);
while (queue.length) {
  const [pkg, file] = queue.pop();
  if (copied.has(`${pkg}/${file}`)) continue;
  copied.add(`${pkg}/${file}`);
  const from = path.join(modules, pkg, file);
  if (!fs.existsSync(from)) throw new Error(`missing ${from}: run npm install first`);
  const to = path.join(out, 'vendor', pkg, file);
  fs.mkdirSync(path.dirname(to), { recursive: true });
  fs.copyFileSync(from, to);
  if (!/\.m?js$/.test(file)) continue;
  for (const m of fs.readFileSync(from, 'utf8').matchAll(importPattern))
    queue.push([pkg, path.normalize(path.join(path.dirname(file), m[1]))]);
}
fs.copyFileSync(path.join(here, 'src', 'index.html'), path.join(out, 'index.html'));
console.log(`rdmesh viewer built in ${out}`);
