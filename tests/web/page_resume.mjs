// A killed and restarted server is resumed from: the page keeps its mesh through the outage and, once the
// server is back on the same port, refines on for a new view.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { environment, terrainModel, startServer, openBrowser, openPage, settle, screenshot } from './page_harness.mjs';

const env = environment();
let server, browser, page, errors, model;

before(async () => {
  model = terrainModel(env);
  server = await startServer(env, [model]);
  ({ browser, page, errors } = await openBrowser(env));
});
after(async () => {
  await browser?.close();
  await server?.stop();
});

for (const mode of ['sender', 'receiver']) {
  test(`mode ${mode} resumes from a restarted server`, async () => {
    await openPage(page, server, `#mode=${mode}`);
    const before = await settle(page);
    const b = await page.evaluate(() => window.pmstream.bounds());
    const c = b.min.map((v, i) => (v + b.max[i]) / 2), s = Math.max(...b.max.map((v, i) => v - b.min[i]));

    server.child.kill('SIGKILL');
    await new Promise((resolve) => server.child.once('exit', resolve));
    const held = await page.evaluate(() => window.pmstream.report.faces);
    assert.equal(held, before.faces, 'the mesh stays while the server is away');

    server = await startServer(env, [model], { httpPort: server.httpPort });
    await page.evaluate(([c, s]) => window.pmstream.setCamera({
      eye: [c[0], c[1] + 0.08 * s, c[2] + 0.1 * s], target: [c[0], c[1], c[2] - 0.2 * s], up: [0, 1, 0],
      fovyDeg: 60, width: 800, height: 600 }), [c, s]);
    const after = await settle(page);
    await screenshot(env, page, `resume_${mode}`);
    assert.ok(after.faces > before.faces, `faces ${before.faces} -> ${after.faces} after the restart`);
    // The browser logs the refused connections of the outage; the page itself reports nothing fatal.
    assert.deepEqual(errors.filter((e) => !/ERR_CONNECTION_REFUSED|WebSocket connection/.test(e)), []);
    await page.evaluate(() => window.pmstream.release());
  });
}
