// Each of the six modes, picked in the page's mode switch, opens the model, streams and settles; the
// multilevel LOD slider changes the face count.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { environment, serveAndBrowse, closeAll, openPage, settle, overlayNumbers, screenshot } from './page_harness.mjs';

const env = environment();
const { server, browser, page, errors } = await serveAndBrowse(env);
after(() => closeAll(browser, server));

async function pick(mode) {
  if (!page.url().startsWith(server.url)) await openPage(page, server);
  await page.selectOption('#mode', mode);
  await page.waitForFunction((m) => window.pmstream.state.mode === m && window.pmstream.ready, mode);
  return settle(page);
}

for (const mode of ['sender', 'sender-plain', 'vi', 'dag', 'receiver', 'multilevel']) {
  test(`mode ${mode} streams and settles`, async () => {
    const report = await pick(mode);
    const shown = await overlayNumbers(page);
    await screenshot(env, page, `mode_${mode}`);
    assert.ok(report.faces > 0 && shown.faces === report.faces, `faces ${report.faces}, overlay ${shown.faces}`);
    assert.ok(shown.down > 0, 'bytes came down');
    assert.ok(report.receivedTotal > 0 && shown.received === report.receivedTotal, `${report.receivedUnit} received`);
    assert.deepEqual(errors, []);
  });
}

// The slider goes to the open viewer (viewer.set): no new viewer, the levels held kept.
test('the LOD slider changes the face count', async () => {
  await pick('multilevel');
  const opens = await page.evaluate(() => window.pmstream.opens);
  const faces = [];
  for (const position of ['400', '900']) {
    await page.$eval('#lod', (e, v) => { e.value = v; e.dispatchEvent(new Event('input')); e.dispatchEvent(new Event('change')); }, position);
    await page.waitForFunction((v) => window.pmstream.state.lod === Number(v) && window.pmstream.ready, position);
    faces.push((await settle(page)).faces);
    await screenshot(env, page, `lod_${position}`);
  }
  assert.ok(faces[1] > faces[0], `faces at a coarse and a fine LOD: ${faces}`);
  assert.equal(await page.evaluate(() => window.pmstream.opens), opens, 'the slider reopened the viewer');
  assert.ok(await page.evaluate(() => window.pmstream.tunes) >= 2, 'the slider went to the open viewer');
  assert.deepEqual(errors, []);
});
