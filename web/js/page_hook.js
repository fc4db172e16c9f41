// window.pmstream: what a script driving the page may read and do (the browser tests, tests/web/page_*.mjs).
// The camera a script sets is handed to the viewer verbatim, its viewport included, so a flight is the
// native viewer's path camera for camera. `bench` is what pmstream-bench's driver (bench/web/web_bench.mjs)
// reads: the first picture's time, each drawn frame's CPU time, the WASM memory, a recorded flight replayed.
import { FrameRecorder, FramePlayer } from './frame_recorder.js';

// The bench's view of the page. Times are performance.now(): milliseconds since navigation started.
function benchHook(app) {
  let firstPicture = null, log = null, recorder = null;
  app.afterDraw = () => {
    const now = performance.now();
    if (!firstPicture && app.report && !app.report.opening && app.geometry.triangleCount > 0) {
      firstPicture = { ms: now, downBytes: app.report.downBytes, upBytes: app.report.upBytes,
                       faces: app.geometry.triangleCount };
    }
    log?.push({ t: now, stepMs: app.stepMs, coreMs: app.coreMs, renderMs: app.renderMs,
                faces: app.geometry.triangleCount });
  };
  return {
    get firstPicture() { return firstPicture; },
    get wasmBytes() { return app.core?.m.HEAPU8.buffer.byteLength ?? 0; },
    // Every drawn frame from now until takeLog(): {t, stepMs (the page's frame work), coreMs (the viewer's
    // frame() of it), renderMs (three.js's render()), faces}.
    startLog() { log = []; },
    takeLog() { const taken = log ?? []; log = null; return taken; },
    // The viewer's buffer changes, frame by frame, until replay().
    record() {
      recorder = new FrameRecorder();
      app.onBuffers = (b) => recorder.record(b);
    },
    // From an empty mesh, the recorded frames one per displayed frame, instead of the viewer's.
    replay() {
      app.onBuffers = null;
      app.newGeometry();
      app.replay = new FramePlayer(recorder?.frames ?? []);
      recorder = null;
      return app.replay.frames.length;
    },
  };
}

export function installHook(app) {
  const waiting = [];
  const hook = {
    get ready() { return Boolean(app.report && !app.report.opening); },
    get report() { return app.report; },
    get state() { return { ...app.state }; },
    // Viewers opened, and option changes the open viewer took in place.
    get opens() { return app.opens; },
    get tunes() { return app.tunes; },
    get errors() { return [...app.errors]; },
    get uploads() {
      const g = app.geometry;
      return { vertices: g.uploadedVertices, triangles: g.uploadedTriangles, reallocations: app.reallocations,
               vertexSlots: g.vertexCount, triangleSlots: g.triangleCount };
    },
    // The camera the viewer was last handed.
    get camera() { return app.cameraForViewer(); },
    // cam: {eye, target, up, fovyDeg, width, height}
    setCamera(cam) { app.script(cam); },
    release() { app.script(null); },
    // Resolves with the report of the next frame the viewer runs.
    nextFrame() { return new Promise((resolve) => waiting.push(resolve)); },
    settled() { return app.viewer?.settled() ?? false; },
    totals() { return app.viewer?.totals(); },
    bounds() { return app.viewer?.bounds(); },
    mesh() {
      const m = app.viewer.mesh();
      return { positions: Array.from(m.positions), faces: Array.from(m.faces) };
    },
    set(key, value) { app.change(key, value); },
    bench: benchHook(app),
    // The picture with or without the model, as the canvas's RGBA rows (bottom row first): the tests
    // compare the two to find the model's silhouette. `reversed`: every triangle wound the other way for
    // this picture (the shading must not depend on it).
    pixels(showModel, reversed = false) {
      const { renderer, scene, camera } = app.view;
      const index = app.geometry.mesh.geometry.getIndex();
      const swap = () => {
        const a = index.array;
        for (let i = 0; i + 2 < a.length; i += 3) [a[i + 1], a[i + 2]] = [a[i + 2], a[i + 1]];
        index.clearUpdateRanges();
        index.needsUpdate = true;
      };
      if (reversed) swap();
      app.geometry.mesh.visible = showModel;
      renderer.render(scene, camera);
      app.geometry.mesh.visible = true;
      if (reversed) swap();
      const gl = renderer.getContext();
      const out = new Uint8Array(gl.drawingBufferWidth * gl.drawingBufferHeight * 4);
      gl.readPixels(0, 0, gl.drawingBufferWidth, gl.drawingBufferHeight, gl.RGBA, gl.UNSIGNED_BYTE, out);
      return { width: gl.drawingBufferWidth, height: gl.drawingBufferHeight, rgba: out };
    },
    // The pixel box (bottom-up rows) the mesh's vertices in front of the camera project into (may exceed the canvas).
    projectedBox() {
      const { camera, renderer } = app.view;
      const gl = renderer.getContext();
      const m = app.viewer.mesh(), p = m.positions, used = new Uint8Array(p.length / 3);
      for (const v of m.faces) used[v] = 1;
      const box = { x0: Infinity, y0: Infinity, x1: -Infinity, y1: -Infinity };
      const e = camera.projectionMatrix.clone().multiply(camera.matrixWorldInverse).elements;
      for (let v = 0; v < used.length; ++v) {
        if (!used[v]) continue;
        const [x, y, z] = [p[3 * v], p[3 * v + 1], p[3 * v + 2]];
        const w = e[3] * x + e[7] * y + e[11] * z + e[15];
        if (w <= 0) continue;
        const sx = ((e[0] * x + e[4] * y + e[8] * z + e[12]) / w + 1) / 2 * gl.drawingBufferWidth;
        const sy = ((e[1] * x + e[5] * y + e[9] * z + e[13]) / w + 1) / 2 * gl.drawingBufferHeight;
        box.x0 = Math.min(box.x0, sx); box.x1 = Math.max(box.x1, sx);
        box.y0 = Math.min(box.y0, sy); box.y1 = Math.max(box.y1, sy);
      }
      return box;
    },
  };
  app.afterFrame = (report) => {
    for (const resolve of waiting.splice(0)) resolve(report);
  };
  window.pmstream = hook;
  // A camera a script set before the page's own code ran (playwright's addInitScript): the viewer opens
  // with it, so a scripted flight has no other view in its history.
  if (window.pmstreamInitialCamera) app.script(window.pmstreamInitialCamera);
}
