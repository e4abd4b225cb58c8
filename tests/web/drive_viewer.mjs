// Drives the viewer page in headless Chromium over the DevTools protocol (node
// --experimental-websocket; Node 20 has no WebSocket without it):
//   node --experimental-websocket drive_viewer.mjs CHROMIUM PAGE_URL SCREENSHOT.png PIXELS_JSON
// Waits for the page's levels to load, then prints one JSON line: the page's stats after each
// level, its stats now, for each pixel [x, y] of PIXELS_JSON the ray through it and what the
// page picks there, the hover label with the mouse over the first pixel, the stats with edges
// hidden, and the deviation toggle's stats; saves a screenshot of the loaded page (edges shown,
// the mouse over the first pixel) to SCREENSHOT.png.
import { spawn } from 'child_process';
import fs from 'fs';
import os from 'os';
import path from 'path';

const [chromium, pageUrl, screenshot, pixelsJson] = process.argv.slice(2);
const pixels = JSON.parse(pixelsJson || '[]');
const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'rdmesh-chromium-'));
const browser = spawn(chromium, [
  '--headless=new', '--no-sandbox', '--no-first-run', '--no-default-browser-check',
  '--disable-extensions', '--disable-background-networking', '--mute-audio',
  // WebGL without a GPU: ANGLE on SwiftShader, Chromium's software renderer.
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
  '--window-size=960,640', '--force-device-scale-factor=1', '--hide-scrollbars',
  `--user-data-dir=${profile}`, '--remote-debugging-port=0', 'about:blank',
], { stdio: ['ignore', 'ignore', 'pipe'] });

function finish(code, message) {
  if (message) console.error(message);
  browser.on('exit', () => {
    // Chromium's helper processes may still be writing to the profile for a moment.
    try {
      fs.rmSync(profile, { recursive: true, force: true, maxRetries: 10, retryDelay: 100 });
    } catch (error) {
      console.error(`left ${profile}: ${error.message}`);
    }
    process.exit(code);
  });
  browser.kill('SIGKILL');
}
setTimeout(() => finish(3, 'timed out'), 45000).unref();

const endpoint = await new Promise((resolve, reject) => {
  let text = '';
  browser.stderr.on('data', (chunk) => {
    text += chunk;
    const m = /DevTools listening on (ws:\/\/\S+)/.exec(text);
    if (m) resolve(m[1]);
  });
  browser.on('exit', (code) => reject(new Error(`chromium exited (${code}): ${text}`)));
}).catch((e) => finish(2, String(e)));

const port = new URL(endpoint).port;
const targets = await (await fetch(`http://127.0.0.1:${port}/json/list`)).json();
const page = targets.find((t) => t.type === 'page');
const socket = new WebSocket(page.webSocketDebuggerUrl);
await new Promise((resolve) => socket.addEventListener('open', resolve));
let nextId = 0;
const waiting = new Map();
const consoleLines = [];
socket.addEventListener('message', (event) => {
  const message = JSON.parse(event.data);
  if (message.id !== undefined && waiting.has(message.id)) {
    waiting.get(message.id)(message);
    waiting.delete(message.id);
  } else if (message.method === 'Runtime.consoleAPICalled') {
    consoleLines.push(message.params.args.map((a) => a.value ?? a.description).join(' '));
  } else if (message.method === 'Log.entryAdded') {
    consoleLines.push(`${message.params.entry.level}: ${message.params.entry.text} ${message.params.entry.url || ''}`);
  } else if (message.method === 'Runtime.exceptionThrown') {
    consoleLines.push(message.params.exceptionDetails.exception?.description || 'exception');
  }
});
function send(method, params = {}) {
  const id = ++nextId;
  socket.send(JSON.stringify({ id, method, params }));
  return new Promise((resolve) => waiting.set(id, resolve));
}
async function evaluate(expression) {
  const reply = await send('Runtime.evaluate', { expression, awaitPromise: true, returnByValue: true });
  if (reply.error || reply.result.exceptionDetails)
    finish(1, `page error in ${expression}: ${JSON.stringify(reply.error || reply.result.exceptionDetails)}\n` +
         consoleLines.join('\n'));
  return reply.result.result.value;
}

await send('Runtime.enable');
await send('Page.enable');
await send('Log.enable');
// A fixed page size, so that pixels name the same place on every machine.
await send('Emulation.setDeviceMetricsOverride', { width: 960, height: 640, deviceScaleFactor: 1, mobile: false });
await send('Page.navigate', { url: pageUrl });
// The page defines rdmeshViewer when its modules have loaded; its `ready` settles after the
// last level.
await evaluate(`new Promise((resolve, reject) => {
  const start = Date.now();
  (function poll() {
    if (window.rdmeshViewer) return resolve();
    if (Date.now() - start > 30000) return reject(new Error('no rdmeshViewer'));
    setTimeout(poll, 50);
  })();
})`);
const levels = await evaluate('rdmeshViewer.ready');
const stats = await evaluate('rdmeshViewer.stats()');
const picks = [];
for (const [x, y] of pixels)
  picks.push({ pixel: [x, y], ray: await evaluate(`rdmeshViewer.ray(${x}, ${y})`),
               pick: await evaluate(`rdmeshViewer.pick(${x}, ${y})`) });
// The mouse over the first pixel, so the screenshot shows what hovering there reports.
if (pixels.length)
  await send('Input.dispatchMouseEvent', { type: 'mouseMoved', x: pixels[0][0], y: pixels[0][1] });
const hover = await evaluate("document.getElementById('hover').textContent");
const shot = await send('Page.captureScreenshot', { format: 'png' });
fs.writeFileSync(screenshot, Buffer.from(shot.result.data, 'base64'));
await evaluate('rdmeshViewer.setEdges(false)');
const noEdges = await evaluate('rdmeshViewer.stats()');
await evaluate('rdmeshViewer.setEdges(true)');
await evaluate('rdmeshViewer.setDeviation(true)');
const deviation = await evaluate('rdmeshViewer.stats()');
console.log(JSON.stringify({ levels, stats, picks, hover, noEdges, deviation, console: consoleLines }));
finish(0);
