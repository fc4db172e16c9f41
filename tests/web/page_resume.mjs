// A killed and restarted server is resumed from: the page keeps its mesh through the outage and, once the
// server is back on the same port, refines on for a new view.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { environment, serveAndBrowse, closeAll, pathCameras, startServer, openPage, settle, screenshot } from './page_harness.mjs';

const env = environment();
const started = await serveAndBrowse(env);
const { model, browser, page, errors } = started;
let { server } = started;  // a new one after the restart
after(() => closeAll(browser, server));

for (const mode of ['sender', 'receiver']) {
  test(`mode ${mode} resumes from a restarted server`, async () => {
    await openPage(page, server, `#mode=${mode}`);
    const before = await settle(page);

    server.child.kill('SIGKILL');
    await new Promise((resolve) => server.child.once('exit', resolve));
    const held = await page.evaluate(() => window.pmstream.report.faces);
    assert.equal(held, before.faces, 'the mesh stays while the server is away');

    server = await startServer(env, [model], { httpPort: server.httpPort });
    await page.evaluate((c) => window.pmstream.setCamera(c), pathCameras(env, model, 'zoom').at(-1));
    const after = await settle(page);
    await screenshot(env, page, `resume_${mode}`);
    assert.ok(after.faces > before.faces, `faces ${before.faces} -> ${after.faces} after the restart`);
    // The browser logs the refused connections of the outage; the page itself reports nothing fatal.
    assert.deepEqual(errors.filter((e) => !/ERR_CONNECTION_REFUSED|WebSocket connection/.test(e)), []);
    await page.evaluate(() => window.pmstream.release());
  });
}
