// The HTTP modes in node over fetch, as the page runs them (web/js/pmstream.js): a receiver-driven and a
// multilevel flight against `pmstream serve`, each settled at the path's last camera on the mesh the native
// client (`pmstream stream`, lock-step) ends on along the same path at the same tolerance.
import fs from 'node:fs';
import { expectSameFaces, fly, loadNodeCore, nativeMesh, servedTerrain, tempDir, check } from './core_support.mjs';

const core = await loadNodeCore();
const dir = tempDir();
const served = await servedTerrain(dir);
const server = `http://127.0.0.1:${served.httpPort}`;
try {
  const models = await core.catalogue(server);
  check(models.some((m) => m.name === 'terrain'), 'the catalogue lists the terrain');
  // Multilevel at a tolerance whose level is not the finest, so the LOD the rule picks is what is compared.
  for (const [mode, tolerance] of [['receiver', 1], ['multilevel', 40]]) {
    const viewer = (await import('../../web/js/pmstream.js')).openViewer(core, {
      server, mode, model: 'terrain', tolerance, morphFrames: 0,
      onError: (message) => { throw new Error(`${mode}: ${message}`); },
    });
    const first = viewer.frame(served.cameras[0]);
    check(first.opening, `${mode}: the first frame opens without waiting`);
    const report = await fly(viewer, served.cameras);
    check(report.downBytes > 0 && report.faces > 0, `${mode}: bytes came and faces show`);
    if (mode === 'multilevel') check(report.levels && report.levels.loaded > 0, 'multilevel reports its levels');
    const want = nativeMesh(dir, ['--server', server, '--mode', mode, '--model', 'terrain', '--path', served.path,
                                  '--tolerance', String(tolerance)]);
    expectSameFaces(viewer.mesh(), want, mode);
    console.log(`${mode}: ${report.faces} faces, ${report.downBytes} bytes down, the native client's mesh`);
    viewer.close();
  }
} finally {
  served.stop();
  fs.rmSync(dir, { recursive: true, force: true });
}
