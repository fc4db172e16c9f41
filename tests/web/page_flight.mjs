// A scripted flight in the page ends on the native viewer's mesh: the same path, τ and mode through
// `pmstream stream --save-mesh`, compared as vertex and face sets (page_mesh_compare.mjs). The page hands
// each path camera to the viewer verbatim, one displayed frame each, then settles at the last.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import path from 'node:path';
import { environment, serveAndBrowse, closeAll, pathCameras, newPage, openPage, settle, screenshot } from './page_harness.mjs';
import { readPly, compareMeshes } from './page_mesh_compare.mjs';

const env = environment();
const TOLERANCE = 1;
const FRAMES = 24;
const { model: file, server, browser } = await serveAndBrowse(env);
after(() => closeAll(browser, server));
const model = path.basename(file, '.pms');
const cameras = pathCameras(env, file, 'zoom', FRAMES);
const flight = path.join(env.artifacts, `path_${model}_zoom_${FRAMES}.json`);

function nativeMesh(mode) {
  const out = path.join(env.artifacts, `flight_native_${mode}.ply`);
  const http = mode === 'receiver' || mode === 'multilevel';
  execFileSync(env.pmstream, ['stream', '--server', http ? server.url : server.tcp, '--mode', mode, '--model', model,
                              '--path', flight, '--tolerance', String(TOLERANCE), '--save-mesh', out],
               { stdio: 'ignore', timeout: 120000 });
  return readPly(out);
}

// A page of its own per flight: the first path camera is the viewer's first view.
async function pageMesh(mode) {
  const { page, errors } = await newPage(browser);
  await openPage(page, server, `#model=${model}&mode=${mode}&tau=${TOLERANCE}`, cameras[0]);
  for (const camera of cameras) {
    await page.evaluate((cam) => { window.pmstream.setCamera(cam); return window.pmstream.nextFrame(); }, camera);
  }
  await settle(page);
  await screenshot(env, page, `flight_${mode}`);
  const mesh = await page.evaluate(() => window.pmstream.mesh());
  await page.close();
  return { mesh, errors };
}

for (const mode of ['sender', 'sender-plain', 'vi', 'dag', 'receiver', 'multilevel']) {
  test(`a flight in mode ${mode} ends on the native viewer's mesh`, async () => {
    const { mesh: browserMesh, errors } = await pageMesh(mode);
    const difference = compareMeshes(browserMesh, nativeMesh(mode));
    assert.equal(difference, '', `page vs native: ${difference}`);
    assert.deepEqual(errors, []);
  });
}
