// A session mode in node with the frames moved over a raw TCP socket to the TCP port (node's net): the same
// core and binding the page's WebSocket carries (one message = one frame there; any chunking here). Each
// mode's flight settles where the native client does along the same path; a connection cut mid-flight is
// resumed on the next socket.
import fs from 'node:fs';
import { check, expectSameFaces, fly, loadNodeCore, nativeMesh, nextTick, servedTerrain, tcpSockets, tempDir } from './core_support.mjs';
import { openViewer } from '../../web/js/pmstream.js';

const core = await loadNodeCore();
const dir = tempDir();
const served = await servedTerrain(dir);
try {
  for (const mode of ['sender', 'dag']) {
    const sockets = [];
    const statuses = [];
    const viewer = openViewer(core, {
      server: 'http://127.0.0.1:1', mode, model: 'terrain', tolerance: 1, morphFrames: 0,
      dag: { maxOps: 300 },
      WebSocket: tcpSockets(served.tcpPort, sockets),
      onError: (message) => { throw new Error(`${mode}: ${message}`); },
      onStatus: (text) => statuses.push(text),
    });
    check(viewer.frame(served.cameras[0]).opening, `${mode}: the first frame opens without waiting`);
    const half = served.cameras.length >> 1;
    if (mode === 'sender') {
      // Half the flight, then the socket cut: the binding reconnects and the core resumes the session.
      for (const camera of served.cameras.slice(0, half)) {
        viewer.frame(camera);
        await nextTick();
      }
      sockets[0].socket.destroy();
      for (let i = 0; i < 2000 && sockets.length < 2; ++i) {
        viewer.frame(served.cameras[half]);
        await nextTick();
      }
      check(sockets.length >= 2, 'a new socket after the cut');
      check(statuses.some((text) => text.includes('reconnecting')), 'the page is told of the reconnect');
    }
    const report = await fly(viewer, served.cameras.slice(mode === 'sender' ? half : 0));
    check(report.receivedTotal > 0, `${mode}: splits came`);
    const want = nativeMesh(dir, ['--server', `127.0.0.1:${served.tcpPort}`, '--mode', mode, '--model', 'terrain',
                                  '--path', served.path, '--tolerance', '1', ...(mode === 'dag' ? ['--max-ops', '300'] : [])]);
    expectSameFaces(viewer.mesh(), want, mode);
    console.log(`${mode}: ${report.faces} faces, ${report.downBytes} bytes down over ${sockets.length} socket(s)`);
    viewer.close();
  }
} finally {
  served.stop();
  fs.rmSync(dir, { recursive: true, force: true });
}
