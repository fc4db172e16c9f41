// The page loads with no console error, draws the base mesh where the model projects, refines when the
// camera comes close (faces and bytes down rise in the overlay), and its link reopens the same view.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { environment, sharedModel, serveAndBrowse, closeAll, pathCameras, openPage, settle, overlayNumbers, screenshot } from './page_harness.mjs';

const env = environment();
const bunny = sharedModel(env, 'bunny');  // a closed, curved silhouette beside the terrain, when ../shared has it
const { model, server, browser, page, errors } = await serveAndBrowse(env, bunny ? [bunny] : []);
after(() => closeAll(browser, server));

// Pixels that differ from the sky drawn alone: inside the model's projected box, and a fair part of it.
async function silhouette() {
  return page.evaluate(() => {
    const hook = window.pmstream;
    const sky = hook.pixels(false), shot = hook.pixels(true), box = hook.projectedBox();
    let inside = 0, outside = 0, boxPixels = 0;
    for (let y = 0; y < shot.height; ++y) {
      for (let x = 0; x < shot.width; ++x) {
        const i = 4 * (y * shot.width + x);
        const inBox = x >= box.x0 - 1 && x <= box.x1 + 1 && y >= box.y0 - 1 && y <= box.y1 + 1;
        boxPixels += inBox;
        const differs = Math.abs(sky.rgba[i] - shot.rgba[i]) + Math.abs(sky.rgba[i + 1] - shot.rgba[i + 1]) +
          Math.abs(sky.rgba[i + 2] - shot.rgba[i + 2]) > 6;
        if (differs) inBox ? ++inside : ++outside;
      }
    }
    return { inside, outside, boxPixels, total: shot.width * shot.height };
  });
}

// The base mesh drawn, and only where the model projects.
async function expectSilhouette(name) {
  const report = await settle(page);
  assert.ok(report.faces > 0, 'the base mesh has faces');
  const s = await silhouette();
  await screenshot(env, page, name);
  assert.ok(s.inside > 0.02 * s.total, `the model covers a visible part of the picture (${s.inside} of ${s.total})`);
  assert.ok(s.inside > 0.3 * s.boxPixels, `the model fills its projected box (${s.inside} of ${s.boxPixels})`);
  assert.equal(s.outside, 0, 'nothing drawn outside the model\'s projection');
}

// The model's pixels whose colour changes when every triangle is wound the other way. Lighting goes by the
// normal, not the winding, so none should: a view-dependent mesh may hold fold-overs (thin triangles wound
// backwards amid their neighbours), which lighting by winding draws as dark lines.
async function shadingByWinding() {
  return page.evaluate(() => {
    const hook = window.pmstream;
    const sky = hook.pixels(false), shot = hook.pixels(true), reversed = hook.pixels(true, true);
    let model = 0, changed = 0;
    const differ = (a, b, i) => Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]) > 24;
    for (let i = 0; i < shot.rgba.length; i += 4) {
      if (!differ(sky.rgba, shot.rgba, i)) continue;
      ++model;
      changed += differ(shot.rgba, reversed.rgba, i);
    }
    return { model, changed };
  });
}

test('the bunny (../shared) draws its silhouette where it projects, lit the same whatever the winding', { skip: !bunny && '../shared/models/bunny.ply.xz absent' }, async () => {
  await openPage(page, server, '#model=bunny');
  await expectSilhouette('load_bunny');
  const { model: pixels, changed } = await shadingByWinding();
  assert.ok(pixels > 0 && changed <= 0.001 * pixels, `${changed} of the model's ${pixels} pixels change with the winding`);
  assert.deepEqual(errors, []);
});

test('the page loads with no console error and draws the base mesh where the model projects', async () => {
  await openPage(page, server, `#model=${path.basename(model, '.pms')}`);
  await expectSilhouette('load_base_mesh');
  assert.deepEqual(errors, []);
});

test('moving the camera close raises faces and bytes down in the overlay', async () => {
  const far = await overlayNumbers(page);
  // The end of `pmstream path zoom`: a close-up of a surface point.
  await page.evaluate((c) => window.pmstream.setCamera(c), pathCameras(env, model, 'zoom').at(-1));
  await settle(page);
  const near = await overlayNumbers(page);
  await screenshot(env, page, 'load_close_up');
  assert.ok(near.faces > far.faces * 1.5, `faces ${far.faces} -> ${near.faces}`);
  assert.ok(near.down > far.down, `bytes down ${far.down} -> ${near.down}`);
  assert.deepEqual(errors, []);
});

test('a camera move uploads the changed ranges, not the whole mesh', async () => {
  const { before, frames } = await page.evaluate(async () => {
    const hook = window.pmstream, start = hook.camera, before = hook.uploads, frames = [];
    for (let i = 1; i <= 8; ++i) {
      hook.setCamera({ ...start, eye: start.eye.map((v, k) => v + (start.target[k] - v) * 0.02 * i) });
      await hook.nextFrame();
      frames.push(hook.uploads);
    }
    return { before, frames };
  });
  // Only a frame that outgrew the arrays uploads them whole.
  let reallocations = before.reallocations;
  for (const f of frames) {
    if (f.reallocations === reallocations) {
      assert.ok(f.vertices < f.vertexSlots && f.triangles < f.triangleSlots, `uploads ${JSON.stringify(f)}`);
    }
    reallocations = f.reallocations;
  }
  assert.ok(frames.some((f) => f.vertices > 0 || f.triangles > 0), `the move changed nothing: ${JSON.stringify(frames)}`);
  await page.evaluate(() => window.pmstream.release());
  assert.deepEqual(errors, []);
});
test('the link carries model, mode, tolerance and camera', async () => {
  await page.selectOption('#mode', 'vi');
  await page.fill('#tolerance', '2');
  await page.dispatchEvent('#tolerance', 'change');
  await page.waitForFunction(() => window.pmstream.ready);
  await page.waitForFunction(() => location.hash.includes('mode=vi') && location.hash.includes('tau=2') && location.hash.includes('eye='));
  const link = await page.evaluate(() => location.href);
  const before = await page.evaluate(() => window.pmstream.state);
  const other = await browser.newPage({ viewport: { width: 800, height: 600 } });
  await other.goto(link);
  await other.waitForFunction(() => window.pmstream?.ready);
  const after = await other.evaluate(() => window.pmstream.state);
  await other.close();
  assert.equal(after.model, before.model);
  assert.equal(after.mode, 'vi');
  assert.equal(after.tolerance, 2);
  for (const key of ['eye', 'target']) {
    after[key].forEach((v, i) => assert.ok(Math.abs(v - before[key][i]) <= 1e-4 * Math.max(1, Math.abs(v)), `${key} ${after[key]} vs ${before[key]}`));
  }
  assert.deepEqual(errors, []);
});
