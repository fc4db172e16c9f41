// What the WASM core's node tests share (tests/web/wasm_*.mjs): the module loaded from the assembled site,
// a model built and served by the native pmstream, a path flown frame by frame, meshes compared as sets.
// A test whose inputs are missing (no web build, no pmstream) exits with SKIP_CODE and says why.
import { createRequire } from 'node:module';
import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import readline from 'node:readline';
import { pathToFileURL } from 'node:url';

export const SKIP_CODE = 77;
export const webDir = process.env.PMSTREAM_WEB_DIR;
export const pmstream = process.env.PMSTREAM_BINARY;

export function skip(why) {
  console.log(`SKIPPED: ${why}`);
  process.exit(SKIP_CODE);
}

export function check(condition, message) {
  if (!condition) throw new Error(message);
}

// The emscripten module through the page's binding (web/js/pmstream.js). Emscripten 3.1.6's ES6 output
// reads the wasm with require and __dirname under node; the binary is handed over directly.
export async function loadNodeCore() {
  const wasm = webDir && path.join(webDir, 'pmstream_core.wasm');
  if (!wasm || !fs.existsSync(wasm)) skip(`no WASM core in PMSTREAM_WEB_DIR (${webDir}): build the target web`);
  globalThis.require ??= createRequire(import.meta.url);
  globalThis.__dirname ??= webDir;
  const { loadCore } = await import('../../web/js/pmstream.js');
  return loadCore(pathToFileURL(path.join(webDir, 'pmstream_core.js')).href, { wasmBinary: fs.readFileSync(wasm) });
}

export function tempDir() {
  return fs.mkdtempSync(path.join(os.tmpdir(), 'pmstream-web-'));
}

// Its progress lines are left out; a failure's message carries its stderr.
function run(...args) {
  return execFileSync(pmstream, args, { stdio: ['ignore', 'pipe', 'pipe'] }).toString();
}

// A terrain built, its orbit path, and `pmstream serve` on free loopback ports: {tcpPort, httpPort, path,
// cameras, stop()}.
export async function servedTerrain(dir, faces = 20000, frames = 12) {
  if (!pmstream || !fs.existsSync(pmstream)) skip(`no pmstream binary (PMSTREAM_BINARY=${pmstream})`);
  const model = path.join(dir, 'terrain.pms');
  run('build', `terrain:${faces}`, '-o', model);
  const pathFile = path.join(dir, 'path.json');
  run('path', 'orbit', '--model', model, '--frames', String(frames), '-o', pathFile, '--width', '640', '--height', '480');
  const server = spawn(pmstream, ['serve', model, '--host', '127.0.0.1', '--port', '0', '--http-port', '0', '--json'],
                       { stdio: ['ignore', 'pipe', 'inherit'] });
  const lines = readline.createInterface({ input: server.stdout });
  const listening = await new Promise((resolve, reject) => {
    lines.on('line', (line) => {
      const event = JSON.parse(line);
      if (event.event === 'listening') resolve(event);
    });
    server.on('exit', (code) => reject(new Error(`pmstream serve exited (${code})`)));
  });
  return {
    tcpPort: listening.port,
    httpPort: listening.http_port,
    path: pathFile,
    cameras: readCameras(pathFile),
    stop: () => server.kill('SIGTERM'),
  };
}

export function readCameras(file) {
  const json = JSON.parse(fs.readFileSync(file, 'utf8'));
  const list = Array.isArray(json) ? json : json.cameras ?? json.frames;
  return list.map((c) => ({ eye: c.eye, target: c.target, up: c.up, fovyDeg: c.fovy_deg, width: c.width, height: c.height }));
}

// `pmstream stream` (lock-step) along the same path, its last mesh saved: what the WASM flight must end on.
export function nativeMesh(dir, args) {
  const out = path.join(dir, `native-${Math.random().toString(36).slice(2)}.ply`);
  const mode = args[args.indexOf('--mode') + 1];
  const morphs = ['sender', 'receiver', 'multilevel'].includes(mode) ? ['--geomorph-frames', '0'] : [];
  run('stream', ...args, '--save-mesh', out, ...morphs);
  return readPly(out);
}

// A PLY as pmstream writes it (export_ply.cpp): positions and faces.
export function readPly(file) {
  const bytes = fs.readFileSync(file);
  const end = bytes.indexOf('end_header\n') + 'end_header\n'.length;
  const header = bytes.subarray(0, end).toString().split('\n');
  const binary = header.some((l) => l.startsWith('format binary_little_endian'));
  let vertices = 0, faces = 0, element = '';
  const props = [];
  for (const line of header) {
    const w = line.split(' ');
    if (w[0] === 'element') {
      element = w[1];
      if (element === 'vertex') vertices = Number(w[2]);
      else faces = Number(w[2]);
    } else if (w[0] === 'property' && element === 'vertex') props.push(w[1]);
  }
  const positions = new Float32Array(3 * vertices), indices = new Uint32Array(3 * faces);
  if (binary) {
    const view = new DataView(bytes.buffer, bytes.byteOffset + end);
    const size = { float: 4, uchar: 1 };
    const stride = props.reduce((sum, t) => sum + size[t], 0);
    for (let v = 0; v < vertices; ++v)
      for (let k = 0; k < 3; ++k) positions[3 * v + k] = view.getFloat32(v * stride + 4 * k, true);
    let at = vertices * stride;
    for (let f = 0; f < faces; ++f, at += 13)
      for (let k = 0; k < 3; ++k) indices[3 * f + k] = view.getInt32(at + 1 + 4 * k, true);
  } else {
    const rows = bytes.subarray(end).toString().trim().split('\n');
    for (let v = 0; v < vertices; ++v) {
      const w = rows[v].split(' ');
      for (let k = 0; k < 3; ++k) positions[3 * v + k] = Number(w[k]);
    }
    for (let f = 0; f < faces; ++f) {
      const w = rows[vertices + f].split(' ');
      for (let k = 0; k < 3; ++k) indices[3 * f + k] = Number(w[1 + k]);
    }
  }
  return { positions, faces: indices };
}

// A mesh as the multiset of its faces, each its three corner positions rotated to start at the least:
// equal for the same surface whatever the vertex and face numbering.
export function faceSet(mesh) {
  const corner = (v) => `${mesh.positions[3 * v]},${mesh.positions[3 * v + 1]},${mesh.positions[3 * v + 2]}`;
  const keys = [];
  for (let f = 0; f < mesh.faces.length / 3; ++f) {
    const c = [0, 1, 2].map((k) => corner(mesh.faces[3 * f + k]));
    if (c[0] === c[1] || c[1] === c[2] || c[0] === c[2]) continue;  // a free slot's degenerate triangle
    let first = 0;
    for (let k = 1; k < 3; ++k) if (c[k] < c[first]) first = k;
    keys.push([c[first], c[(first + 1) % 3], c[(first + 2) % 3]].join(' '));
  }
  return keys.sort();
}

export function expectSameFaces(got, want, what) {
  const a = faceSet(got), b = faceSet(want);
  check(a.length > 0, `${what}: an empty mesh`);
  check(a.length === b.length, `${what}: ${a.length} faces, the native build ${b.length}`);
  for (let i = 0; i < a.length; ++i) check(a[i] === b[i], `${what}: face ${i} differs: ${a[i]} vs ${b[i]}`);
}

// One displayed frame's worth of the event loop: the answers that came are delivered before the next frame.
export const nextTick = () => new Promise((resolve) => setTimeout(resolve, 1));

// The flight frame by frame, then frames at its last camera until the viewer is settled (bounded).
export async function fly(viewer, cameras, maxFrames = 20000) {
  for (const camera of cameras) {
    viewer.frame(camera);
    await nextTick();
  }
  for (let i = 0; i < maxFrames; ++i) {
    const report = viewer.frame(cameras[cameras.length - 1]);
    if (report.settled) return report;
    await nextTick();
  }
  throw new Error(`not settled after ${maxFrames} frames`);
}

// What the binding needs of a WebSocket, over a TCP socket to `port`; `sockets` collects them, so the test
// can cut one.
export function tcpSockets(port, sockets) {
  return class TcpSocket {
    constructor() {
      this.binaryType = 'arraybuffer';
      this.socket = net.connect(port, '127.0.0.1', () => this.onopen?.());
      this.socket.on('data', (data) => this.onmessage?.({ data: data.buffer.slice(data.byteOffset, data.byteOffset + data.length) }));
      this.socket.on('close', () => this.onclose?.({ reason: 'TCP closed' }));
      this.socket.on('error', () => {});
      sockets.push(this);
    }
    send(bytes) { this.socket.write(bytes); }
    close() { this.socket.destroy(); }
  };
}
