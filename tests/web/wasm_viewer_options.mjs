// An open viewer's options changed in place (viewer.set, pms_viewer_set) and degenerate cameras, through the
// binding as the page uses it: after set() the same viewer settles on the mesh the native client gets along
// the same path at the new options, with what it held kept (no second open, only what the new options add
// comes down); a camera with eye on target is refused for that frame only; set() refuses what needs a new
// viewer and changes nothing then.
import fs from 'node:fs';
import { check, expectSameFaces, fly, loadNodeCore, nativeMesh, servedTerrain, tcpSockets, tempDir } from './core_support.mjs';
import { openViewer } from '../../web/js/pmstream.js';

const core = await loadNodeCore();
const dir = tempDir();
const served = await servedTerrain(dir);
const http = `http://127.0.0.1:${served.httpPort}`;
const last = served.cameras[served.cameras.length - 1];

function open(mode, tolerance, extra = {}) {
  const errors = [];
  const viewer = openViewer(core, {
    server: http, mode, model: 'terrain', tolerance, morphFrames: 0, dag: { maxOps: 300 },
    WebSocket: tcpSockets(served.tcpPort, []),
    onError: (message) => errors.push(message),
    ...extra,
  });
  return { viewer, errors };
}

function native(mode, tolerance, server, more = []) {
  return nativeMesh(dir, ['--server', server, '--mode', mode, '--model', 'terrain', '--path', served.path,
                          '--tolerance', String(tolerance), ...more]);
}

try {
  // τ lowered on an open viewer of each transport: the mesh refines from what it holds.
  for (const [mode, from, to, server] of [['multilevel', 40, 4, http], ['receiver', 4, 1, http],
                                          ['sender', 4, 1, `127.0.0.1:${served.tcpPort}`]]) {
    const { viewer, errors } = open(mode, from);
    const before = await fly(viewer, served.cameras);
    viewer.set({ tolerance: to });
    const after = await fly(viewer, [last]);
    check(errors.length === 0, `${mode}: ${errors}`);
    check(after.faces > before.faces, `${mode}: τ ${from} -> ${to} refines: ${before.faces} -> ${after.faces} faces`);
    check(after.receivedTotal > before.receivedTotal, `${mode}: more came, after what was held`);
    expectSameFaces(viewer.mesh(), native(mode, to, server), `${mode} at τ ${to} after set()`);
    console.log(`${mode}: τ ${from} -> ${to}: ${before.faces} -> ${after.faces} faces, ` +
                `${after.downBytes - before.downBytes} more bytes down`);
    viewer.close();
  }

  // The multilevel LOD budget: a coarser LOD from the levels held, nothing fetched.
  {
    const { viewer, errors } = open('multilevel', 4);
    const fine = await fly(viewer, served.cameras);
    const budget = Math.max(1, fine.faces >> 1);
    viewer.set({ multilevel: { budget } });
    const coarse = await fly(viewer, [last]);
    check(errors.length === 0, `multilevel budget: ${errors}`);
    check(coarse.faces <= budget && coarse.faces < fine.faces, `budget ${budget}: ${coarse.faces} faces`);
    check(coarse.downBytes === fine.downBytes, 'a coarser LOD needs nothing new');

    // What needs a new viewer, and values out of range, are refused with nothing changed.
    for (const bad of [{ mode: 'dag' }, { receiver: { fetch: 'blocks' } }, { tolerance: -1 }, { dag: { traversal: 'free' } }]) {
      let threw = false;
      try {
        viewer.set(bad);
      } catch {
        threw = true;
      }
      check(threw, `set(${JSON.stringify(bad)}) is refused`);
    }
    check(viewer.frame(last).faces === coarse.faces, 'a refused set() changed nothing');

    // A degenerate camera: that frame refused, the mesh kept, the viewer still good.
    for (const bad of [{ ...last, target: [...last.eye] }, { ...last, up: [0, 0, 0] }]) {
      const r = viewer.frame(bad);
      check(typeof r.refused === 'string' && r.refused.includes('camera'), `refused: ${JSON.stringify(r.refused)}`);
      check(r.faces === coarse.faces, 'the refused frame keeps the mesh');
    }
    const good = viewer.frame(last);
    check(good.refused === '' && good.faces === coarse.faces && errors.length === 0, 'the next good camera works');
    viewer.close();
  }
  console.log('set() and degenerate cameras: ok');
} finally {
  served.stop();
  fs.rmSync(dir, { recursive: true, force: true });
}
