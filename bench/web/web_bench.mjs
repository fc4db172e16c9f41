// pmstream-bench's `web` group in the browser (src/bench/bench_web.cpp runs it): Debian's chromium headless
// with software WebGL at 1280×720, driven by playwright-core, against a `pmstream serve` the group started.
// Prints one JSON object on stdout: {skipped} when it cannot run here, else what each figure needs:
//   firstPicture  per cold page load: ms from navigation start to the first frame drawn with the base mesh,
//                 the model's bytes (the viewer's up and down) and the site's (resource timing) until then
//   refine        per repeat: the WASM module's refinement run along the path (src/web/bench_api.cpp)
//   flights       per mode: each frame's draw time and the page's time for it (wall), along the path, and
//                 each animation-frame callback's thread CPU time (tracing)
//   replay        the sender flight's recorded buffer changes drawn again from memory, same cameras
//   laps          per lap of the orbit: JS heap (after a collection) and WASM memory
//   profile       the sender flight once more under Chromium's CPU profiler: where the main thread's time goes
//
//   node bench/web/web_bench.mjs CONFIG.json
// CONFIG: {url, model, pmsUrl, pathFile, modes, tolerance, loads, refineRepeats, laps, lapSeconds,
//          settleSeconds}; the path file is `pmstream path`'s JSON.
import { existsSync, readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const SOURCE_DIR = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const CHROMIUM = process.env.PMSTREAM_CHROMIUM || '/usr/bin/chromium';
const WIDTH = 1280, HEIGHT = 720;
const OPEN_DEADLINE_MS = 120000;  // the page up and the model's base mesh in

function print(result) {
  process.stdout.write(`${JSON.stringify(result)}\n`);
}

function loadPlaywright() {
  if (!existsSync(CHROMIUM)) return { skipped: `chromium is not installed at ${CHROMIUM}` };
  try {
    return { playwright: createRequire(path.join(SOURCE_DIR, 'web/package.json'))('playwright-core') };
  } catch {
    return { skipped: 'playwright-core is not installed (npm ci in web/)' };
  }
}

function cameras(pathFile) {
  return JSON.parse(readFileSync(pathFile, 'utf8')).frames.map((c) => (
    { eye: c.eye, target: c.target, up: c.up, fovyDeg: c.fovy_deg, width: c.width, height: c.height }));
}

function hash(config, mode) {
  return `#model=${encodeURIComponent(config.model)}&mode=${mode}&tau=${config.tolerance}`;
}

// A page of its own (a fresh context: an empty HTTP cache), its errors collected; with `camera`, the
// viewer's first view.
async function newPage(browser, camera) {
  const context = await browser.newContext({ viewport: { width: WIDTH, height: HEIGHT } });
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.setDefaultTimeout(OPEN_DEADLINE_MS);
  if (camera) await page.addInitScript((c) => { window.pmstreamInitialCamera = c; }, camera);
  return { context, page, errors };
}

async function openPage(browser, config, mode, camera) {
  const opened = await newPage(browser, camera);
  await opened.page.goto(`${config.url}/${hash(config, mode)}`);
  await opened.page.waitForFunction(() => window.pmstream?.ready);
  return opened;
}

// Until the viewer says the view is served (a frame first, so it has seen the camera); false at the deadline.
async function settle(page, seconds) {
  await page.evaluate(() => window.pmstream.nextFrame());
  try {
    await page.waitForFunction(() => window.pmstream.settled(), null, { timeout: seconds * 1000, polling: 100 });
    return true;
  } catch {
    return false;
  }
}

// Cold loads: navigation start to the first picture, and the bytes until then.
async function firstPictures(browser, config, camera) {
  const out = [];
  for (let i = 0; i < config.loads; ++i) {
    const { context, page, errors } = await newPage(browser, camera);
    await page.goto(`${config.url}/${hash(config, 'sender')}`);
    await page.waitForFunction(() => window.pmstream?.bench.firstPicture);
    out.push(await page.evaluate(() => {
      const first = window.pmstream.bench.firstPicture;
      const entries = [...performance.getEntriesByType('navigation'), ...performance.getEntriesByType('resource')];
      const before = entries.filter((e) => e.responseEnd <= first.ms);
      const siteBytes = before.reduce((sum, e) => sum + e.transferSize, 0);
      // The last of the page's files in (the WASM module among them); the rest is the model's open.
      const siteMs = before.reduce((last, e) => Math.max(last, e.responseEnd), 0);
      const mark = (name) => performance.getEntriesByName(name)[0]?.startTime ?? 0;
      return { ...first, siteBytes, siteMs, coreMs: mark('pmstream:core'), viewerMs: mark('pmstream:viewer') };
    }));
    out.at(-1).errors = errors;
    await context.close();
  }
  return out;
}

// The WASM module's refinement run over the model's .pms along the path's cameras `laps` times over, `repeats`
// runs after an untimed one (the first runs partly on the baseline compiler's code).
async function refine(browser, config, cams) {
  const { context, page } = await newPage(browser, null);
  await page.goto(`${config.url}/js/pmstream.js`);  // any page of the site's origin
  const lap = cams.flatMap((c) => [...c.eye, ...c.target, ...c.up, c.fovyDeg, c.width, c.height]);
  const flat = Array.from({ length: config.refineLaps }, () => lap).flat();
  const runs = await page.evaluate(async ({ url, pmsUrl, flat, count, tolerance, repeats }) => {
    const { default: create } = await import(`${url}/pmstream_core.js`);
    const m = await create();
    const bytes = new Uint8Array(await (await fetch(`${url}${pmsUrl}`)).arrayBuffer());
    const pms = m._pms_alloc(bytes.length);
    m.HEAPU8.set(bytes, pms);
    const camerasPtr = m._pms_alloc(flat.length * 4);
    new Float32Array(m.HEAPU8.buffer, camerasPtr, flat.length).set(flat);
    const out = [];
    for (let i = 0; i <= repeats; ++i) {
      const run = JSON.parse(m.UTF8ToString(m._pms_bench_refine(pms, bytes.length, camerasPtr, count, tolerance)));
      if (i) out.push(run);
    }
    return out;
  }, { url: config.url, pmsUrl: config.pmsUrl, flat, count: cams.length * config.refineLaps, tolerance: config.tolerance,
       repeats: config.refineRepeats });
  await context.close();
  return runs;
}

// One camera per displayed frame; the log of the frames drawn meanwhile.
function fly(page, cams) {
  return page.evaluate(async (cams) => {
    const p = window.pmstream;
    p.bench.startLog();
    for (const c of cams) {
      p.setCamera(c);
      await p.nextFrame();
    }
    await p.nextFrame();  // the last camera's frame drawn
    return p.bench.takeLog();
  }, cams);
}

// `run()` under Chromium's tracing: its result, and the thread CPU time (not the wall time, which on a
// shared machine includes the time the page's thread waited for a core) of each animation-frame callback
// on the page's main thread, in ms. The page does one callback a frame: its viewer frame, buffer uploads,
// render call and overlay.
async function withFrameCpu(context, page, run) {
  const cdp = await context.newCDPSession(page);
  const events = [];
  cdp.on('Tracing.dataCollected', (e) => events.push(...e.value));
  await cdp.send('Tracing.start', { categories: 'devtools.timeline,disabled-by-default-devtools.timeline',
                                    transferMode: 'ReportEvents' });
  const result = await run();
  const complete = new Promise((resolve) => cdp.once('Tracing.tracingComplete', resolve));
  await cdp.send('Tracing.end');
  await complete;
  await cdp.detach();
  const frames = events.filter((e) => e.name === 'FireAnimationFrame' && e.ph === 'X' && e.tdur !== undefined);
  return { result, frameCpuMs: frames.map((e) => e.tdur / 1000) };
}

// Each mode along the path from its first view settled.
async function flights(browser, config, cams) {
  const out = {};
  for (const mode of config.modes) {
    process.stderr.write(`web_bench: flight, ${mode}\n`);
    const { context, page, errors } = await openPage(browser, config, mode, cams[0]);
    const settled = await settle(page, config.settleSeconds);
    const { result: log, frameCpuMs } = await withFrameCpu(context, page, () => fly(page, cams));
    const report = await page.evaluate(() => window.pmstream.report);
    out[mode] = { settledBeforeFlight: settled, log, frameCpuMs, downBytes: report.downBytes, faces: report.faces,
                  errors };
    await context.close();
  }
  return out;
}

// The sender flight again with its buffer changes recorded, then the same page drawing them from memory
// along the same cameras: what streaming costs the frame rate, in one run. Recording copies each change
// once more inside the streamed frames, so the streamed side is if anything the slower for it.
async function streamAndReplay(browser, config, cams) {
  const { context, page, errors } = await openPage(browser, config, 'sender', cams[0]);
  const settled = await settle(page, config.settleSeconds);
  await page.evaluate(() => window.pmstream.bench.record());
  const streamed = await fly(page, cams);
  const frames = await page.evaluate(() => window.pmstream.bench.replay());
  const replayed = await fly(page, cams);
  await context.close();
  return { settledBeforeFlight: settled, frames, streamed, replayed, errors };
}

// Where a profile's samples fall: the WASM core, three.js, the page's modules, or the browser's own work.
function category(frame) {
  const url = frame.url ?? '';
  if (url.startsWith('wasm://') || url.endsWith('.wasm')) return 'WASM core';
  if (url.includes('/vendor/')) return 'three.js';
  if (url.endsWith('/pmstream.js') || url.endsWith('/pmstream_core.js')) return 'pmstream.js + emscripten glue';
  if (url.includes('/js/')) return 'page modules';
  // (idle), (program), (garbage collector): the profiler's own names; else a browser built-in (WebGL, DOM).
  return frame.functionName?.startsWith('(') ? frame.functionName : 'browser built-ins (WebGL, DOM)';
}

// Self time by category and by function (the top ones), from a CDP profile.
function summarize(profile, top = 12) {
  const nodes = new Map(profile.nodes.map((n) => [n.id, n.callFrame]));
  const byCategory = new Map(), byFunction = new Map();
  let total = 0;
  profile.samples.forEach((id, i) => {
    const ms = (profile.timeDeltas[i + 1] ?? 0) / 1000;
    const frame = nodes.get(id);
    const name = `${frame.functionName || '(anonymous)'} ${(frame.url ?? '').split('/').pop()}`.trim();
    byCategory.set(category(frame), (byCategory.get(category(frame)) ?? 0) + ms);
    byFunction.set(name, (byFunction.get(name) ?? 0) + ms);
    total += ms;
  });
  const sorted = (map, n) => [...map].sort((a, b) => b[1] - a[1]).slice(0, n).map(([name, ms]) => ({ name, ms }));
  return { totalMs: total, categories: sorted(byCategory, Infinity), functions: sorted(byFunction, top) };
}

// The sender flight under the sampling profiler (its own flight: the profiler slows what it watches).
async function profileFlight(browser, config, cams) {
  const { context, page } = await openPage(browser, config, 'sender', cams[0]);
  await settle(page, config.settleSeconds);
  const cdp = await context.newCDPSession(page);
  await cdp.send('Profiler.enable');
  await cdp.send('Profiler.start');
  const log = await fly(page, cams);
  const { profile } = await cdp.send('Profiler.stop');
  await context.close();
  return { ...summarize(profile), flightMs: log.length ? log.at(-1).t - log[0].t : 0,
           stepMs: log.reduce((sum, f) => sum + f.stepMs, 0) };
}

// Laps of the orbit, each `lapSeconds` long (the camera follows the wall clock), sampled after each.
async function laps(browser, config, cams) {
  const { context, page, errors } = await openPage(browser, config, 'sender', cams[0]);
  const cdp = await context.newCDPSession(page);
  const out = [];
  for (let lap = 0; lap < config.laps; ++lap) {
    const frames = await page.evaluate(async ({ cams, ms }) => {
      const p = window.pmstream, start = performance.now();
      let frames = 0;
      for (let t = 0; t < ms; t = performance.now() - start, ++frames) {
        p.setCamera(cams[Math.min(cams.length - 1, Math.floor((t / ms) * cams.length))]);
        await p.nextFrame();
      }
      return frames;
    }, { cams, ms: config.lapSeconds * 1000 });
    await cdp.send('HeapProfiler.collectGarbage');
    const heap = await cdp.send('Runtime.getHeapUsage');
    const wasmBytes = await page.evaluate(() => window.pmstream.bench.wasmBytes);
    out.push({ frames, heapUsedBytes: heap.usedSize, heapTotalBytes: heap.totalSize, wasmBytes });
  }
  await context.close();
  return { laps: out, errors };
}

async function main() {
  const config = JSON.parse(readFileSync(process.argv[2], 'utf8'));
  const { playwright, skipped } = loadPlaywright();
  if (skipped) return print({ skipped });
  const cams = cameras(config.pathFile);
  const browser = await playwright.chromium.launch({
    executablePath: CHROMIUM, headless: true,
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
           '--enable-precise-memory-info'],
  });
  try {
    const result = { browser: browser.version() };
    // First, right after the bench's native runs: the two sides of the ratio as close in time as they can be.
    process.stderr.write('web_bench: refinement in WASM\n');
    result.refine = await refine(browser, config, cams);
    process.stderr.write('web_bench: first pictures\n');
    result.firstPicture = await firstPictures(browser, config, cams[0]);
    process.stderr.write(`web_bench: flights (${config.modes.join(', ')})\n`);
    result.flights = await flights(browser, config, cams);
    process.stderr.write('web_bench: streamed and replayed\n');
    result.replay = await streamAndReplay(browser, config, cams);
    process.stderr.write(`web_bench: ${config.laps} laps of ${config.lapSeconds} s\n`);
    result.memory = await laps(browser, config, cams);
    process.stderr.write('web_bench: the sender flight profiled\n');
    result.profile = await profileFlight(browser, config, cams);
    print(result);
  } finally {
    await browser.close();
  }
}

main().catch((error) => {
  process.stderr.write(`web_bench: ${error?.stack ?? error}\n`);
  process.exit(1);
});
