// The protocol has client and server derive the same view and criteria from a camera (docs/architecture.md,
// "Browser build"): the WASM core's make_view, cone trigonometry and node tests against the native build's
// (view_probe_native), bit for bit, on many random cameras and nodes, degenerate ones included.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import { check, loadNodeCore, skip } from './core_support.mjs';

const INPUTS = 30, OUTPUTS = 62, CASES = 4000;
const probe = process.env.PMSTREAM_VIEW_PROBE;
if (!probe || !fs.existsSync(probe)) skip(`no view_probe_native (PMSTREAM_VIEW_PROBE=${probe})`);
const core = await loadNodeCore();
const m = core.m;

// A deterministic generator (mulberry32), so a failure names a case that reproduces.
let seed = 44;
const random = () => {
  seed = (seed + 0x6d2b79f5) | 0;
  let t = Math.imul(seed ^ (seed >>> 15), 1 | seed);
  t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
  return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
};
const between = (lo, hi) => lo + (hi - lo) * random();

const input = new Float32Array(CASES * INPUTS);
for (let i = 0; i < CASES; ++i) {
  const c = input.subarray(i * INPUTS, (i + 1) * INPUTS);
  for (let k = 0; k < 9; ++k) c[k] = between(-10, 10);           // eye, target, up
  if (i % 97 === 0) c.set(c.subarray(0, 3), 3);                   // eye == target: refused
  c[9] = i % 89 === 0 ? 180 : between(1, 170);                    // fovy (180: refused)
  c[10] = Math.floor(between(1, 4096));
  c[11] = Math.floor(between(1, 4096));
  for (let k = 0; k < 3; ++k) {
    const a = between(-5, 5), b = between(-5, 5);
    c[12 + k] = Math.min(a, b);
    c[15 + k] = Math.max(a, b);
  }
  c[18] = between(0, 8);                                          // tolerance in pixels
  for (let k = 0; k < 3; ++k) c[19 + k] = between(-5, 5);         // node position
  c[22] = between(0, 1);                                          // radius
  c[23] = between(0, 0.1);                                        // mu
  c[24] = between(0, 0.1);                                        // delta
  const axis = [between(-1, 1), between(-1, 1), between(-1, 1)];
  const length = Math.hypot(...axis) || 1;
  for (let k = 0; k < 3; ++k) c[25 + k] = axis[k] / length;
  c[28] = between(0, 1.8);                                        // cone angle, past pi/2 too
  c[29] = 0;
}

const inPtr = m._pms_alloc(input.byteLength), outPtr = m._pms_alloc(CASES * OUTPUTS * 4);
new Float32Array(m.HEAPU8.buffer, inPtr, input.length).set(input);
m._pms_probe_view_math(inPtr, outPtr, CASES);
const wasm = new Uint32Array(m.HEAPU8.buffer.slice(outPtr, outPtr + CASES * OUTPUTS * 4));
const native = new Uint32Array(new Uint8Array(execFileSync(probe, { input: Buffer.from(input.buffer) })).buffer);
check(native.length === wasm.length, `native gave ${native.length} floats, the WASM core ${wasm.length}`);

let refused = 0, culled = 0;
for (let i = 0; i < CASES; ++i) {
  for (let k = 0; k < OUTPUTS; ++k) {
    const a = wasm[i * OUTPUTS + k], b = native[i * OUTPUTS + k];
    check(a === b, `case ${i}, output ${k}: WASM bits ${a.toString(16)}, native ${b.toString(16)}`);
  }
  const tests = new Float32Array(wasm.buffer, (i * OUTPUTS + 61) * 4, 1)[0];
  if (tests < 0) ++refused;
  else if (tests & 3) ++culled;
}
check(refused > 0 && refused < CASES / 10, `${refused} refused cameras: the degenerate ones only`);
check(culled > 0, 'some nodes culled');
console.log(`${CASES} cameras and nodes bit for bit (${refused} refused, ${culled} culled)`);
