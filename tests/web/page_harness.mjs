// What every browser test of the page shares: a `pmstream serve` child on loopback with a small model and
// the built site, Debian's chromium driven by playwright-core (software WebGL), the console watched for
// errors, screenshots kept under the build dir, and waits that each end at a deadline.
//
// Run as `node tests/web/page_NAME.mjs BUILD_DIR`. A test that cannot run here (no chromium, no built site,
// no playwright-core) prints "SKIPPED: why" and exits 0; ctest reads that line as a skip.
import { spawn, execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const SOURCE_DIR = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
export const CHROMIUM = process.env.PMSTREAM_CHROMIUM || '/usr/bin/chromium';
const DEADLINE_MS = 60000;  // any one wait: model opened, refinement settled, a server started

export function skip(why) {
  console.log(`SKIPPED: ${why}`);
  process.exit(0);
}

// The build dir, its pmstream binary and site, and playwright-core from web/node_modules; skips when absent.
export function environment() {
  const build = path.resolve(process.argv[2] || process.env.PMSTREAM_BUILD_DIR || path.join(SOURCE_DIR, 'build'));
  const pmstream = path.join(build, 'pmstream');
  const site = path.join(build, 'web');
  if (!existsSync(pmstream)) skip(`${pmstream} is not built`);
  if (!existsSync(CHROMIUM)) skip(`chromium is not installed at ${CHROMIUM}`);
  for (const file of ['index.html', 'js/pmstream.js', 'pmstream_core.js', 'pmstream_core.wasm', 'vendor/three.module.js']) {
    if (!existsSync(path.join(site, file))) skip(`the site is not built (${path.join(site, file)} missing; PMSTREAM_WEB=ON)`);
  }
  let playwright;
  try {
    playwright = createRequire(path.join(SOURCE_DIR, 'web/package.json'))('playwright-core');
  } catch {
    skip('playwright-core is not installed (npm ci in web/)');
  }
  const artifacts = path.join(build, 'web-artifacts');
  mkdirSync(artifacts, { recursive: true });
  return { build, pmstream, site, artifacts, playwright };
}

// A terrain built once per build dir (`pmstream build` writes atomically, so parallel tests may race).
export function terrainModel(env, faces = 20000) {
  const dir = path.join(env.artifacts, 'models');
  mkdirSync(dir, { recursive: true });
  const file = path.join(dir, `terrain_${faces}.pms`);
  if (!existsSync(file)) {
    execFileSync(env.pmstream, ['build', `terrain:${faces}`, '-o', file], { stdio: 'ignore', timeout: DEADLINE_MS });
  }
  return file;
}

// ../shared/models/NAME.ply.xz built once into the artifacts, or null where ../shared is absent.
export function sharedModel(env, name) {
  const source = path.join(SOURCE_DIR, '..', 'shared', 'models', `${name}.ply.xz`);
  if (!existsSync(source)) return null;
  const file = path.join(env.artifacts, 'models', `${name}.pms`);
  mkdirSync(path.dirname(file), { recursive: true });
  if (!existsSync(file)) execFileSync(env.pmstream, ['build', source, '-o', file], { stdio: 'ignore', timeout: DEADLINE_MS });
  return file;
}

// A scripted path (`pmstream path KIND`, docs/cli.md) over the model, as the cameras the page's hook takes.
export function pathCameras(env, model, kind = 'zoom', frames = 24) {
  const file = path.join(env.artifacts, `path_${path.basename(model, '.pms')}_${kind}_${frames}.json`);
  execFileSync(env.pmstream, ['path', kind, '--model', model, '--frames', String(frames), '-o', file,
                              '--width', '800', '--height', '600', '--fovy', '60'], { stdio: 'ignore' });
  return readJson(file).frames.map((c) => (
    { eye: c.eye, target: c.target, up: c.up, fovyDeg: c.fovy_deg, width: c.width, height: c.height }));
}

// `pmstream serve` on loopback; resolves once its `listening` line names the ports.
export function startServer(env, models, { httpPort = 0, extra = [] } = {}) {
  const args = ['serve', ...models, '--host', '127.0.0.1', '--port', '0', '--http-port', String(httpPort),
                '--web-root', env.site, '--json', ...extra];
  const child = spawn(env.pmstream, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  process.on('exit', () => child.kill('SIGKILL'));  // a test that throws outside node:test's hooks
  let stderr = '';
  child.stderr.on('data', (d) => { stderr += d; });
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => { child.kill('SIGKILL'); reject(new Error(`serve did not listen: ${stderr}`)); }, DEADLINE_MS);
    let out = '';
    child.stdout.on('data', (d) => {
      out += d;
      for (const line of out.split('\n')) {
        if (!line.startsWith('{')) continue;
        const event = JSON.parse(line);
        if (event.event !== 'listening') continue;
        clearTimeout(timer);
        const url = `http://127.0.0.1:${event.http_port}`;
        resolve({ child, url, httpPort: event.http_port, tcp: `127.0.0.1:${event.port}`, stop: () => stopChild(child) });
        return;
      }
    });
    child.on('exit', (code) => { clearTimeout(timer); reject(new Error(`serve exited ${code}: ${stderr}`)); });
  });
}

function stopChild(child) {
  if (child.exitCode !== null) return Promise.resolve();
  return new Promise((resolve) => { child.once('exit', resolve); child.kill('SIGTERM'); });
}

// Chromium with software WebGL, a page of a fixed size, and every console error and page error recorded.
export async function openBrowser(env, { width = 800, height = 600 } = {}) {
  const browser = await env.playwright.chromium.launch({
    executablePath: CHROMIUM, headless: true,
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
  return { browser, ...await newPage(browser, { width, height }) };
}

// A page of its own in `browser`, its console errors and page errors collected in `errors`.
export async function newPage(browser, { width = 800, height = 600 } = {}) {
  const page = await browser.newPage({ viewport: { width, height } });
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => errors.push(`page: ${e.message}`));
  page.setDefaultTimeout(DEADLINE_MS);
  return { page, errors };
}

// What most test files start with: the terrain served (and `extra` models), a browser and a page; close
// with closeAll.
export async function serveAndBrowse(env, extra = []) {
  const model = terrainModel(env);
  const server = await startServer(env, [model, ...extra]);
  return { model, server, ...await openBrowser(env) };
}

export async function closeAll(browser, server) {
  await browser?.close();
  await server?.stop();
}

// The page for a server and a state (url_state.js), opened until the model's base mesh is in; with
// `camera`, the viewer's first view is that one ({eye, target, up, fovyDeg, width, height}).
export async function openPage(page, server, hash = '', camera = null) {
  if (camera) await page.addInitScript((c) => { window.pmstreamInitialCamera = c; }, camera);
  await page.goto('about:blank');  // a new document: a hash change alone would keep the page
  await page.goto(`${server.url}/${hash}`);
  await page.waitForFunction(() => window.pmstream?.ready, null, { timeout: DEADLINE_MS });
}

// Until the viewer's last view is satisfied, nothing in flight or in motion. A frame first, so that the
// viewer has seen the camera set last (settled() speaks of the view before until then).
export async function settle(page) {
  await page.evaluate(() => window.pmstream.nextFrame());
  await page.waitForFunction(() => window.pmstream.settled(), null, { timeout: DEADLINE_MS, polling: 100 });
  return page.evaluate(() => window.pmstream.report);
}

export async function overlayNumbers(page) {
  return page.$eval('#stats', (e) => Object.fromEntries(Object.entries(e.dataset).map(([k, v]) => [k, Number(v)])));
}

export async function screenshot(env, page, name) {
  const file = path.join(env.artifacts, `${name}.png`);
  await page.screenshot({ path: file });
  return file;
}

export function readJson(file) {
  return JSON.parse(readFileSync(file, 'utf8'));
}
