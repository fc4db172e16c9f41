// The page's binding to the WASM core (src/web/wasm_api.cpp; docs/architecture.md, "Browser build"): the
// core refines and decides what to ask for; this module only moves bytes between it and the network, fetch
// for the HTTP modes (receiver, multilevel), a WebSocket for the session modes (sender, sender-plain, vi,
// dag; one binary message = one TCP protocol frame, both ways). Nothing here waits on the core or the core
// on it: a frame applies what has arrived and returns.
//
//   const core = await loadCore('pmstream_core.js');
//   const models = await core.catalogue(server);
//   const viewer = openViewer(core, { server, mode, model, tolerance, ... });
//   const report = viewer.frame({ eye, target, up, fovyDeg, width, height });   // per displayed frame
//   viewer.set({ tolerance: 2 });   // options changed on the open viewer, the mesh kept
// applyBudgetMs and adaptBudgetMs bound the core's work in a frame (applying what arrived; adapting the
// mesh, sender and receiver): what does not fit carries to the next frames. Absent: the native defaults.
// A degenerate camera (eye on the target, a zero up or one along the view) is refused for that frame only:
// report.refused says why, the mesh and the rest of the report stay as they were.

const SESSION_MODES = new Set(['sender', 'sender-plain', 'vi', 'dag']);
const FRAME_HEADER_BYTES = 5;  // u32 payload length (little-endian) + u8 type (docs/protocol.md)
// Reconnects (session modes) and fetch retries wait twice as long each time, from BASE_DELAY_MS up to
// MAX_DELAY_MS; a fetch is given up after FETCH_ATTEMPTS, a socket after RECONNECT_ATTEMPTS in a row.
const BASE_DELAY_MS = 250;
const MAX_DELAY_MS = 8000;
const FETCH_ATTEMPTS = 5;
const RECONNECT_ATTEMPTS = 12;
// The headers a fetch answer cost on the wire, as far as the page can tell: the status line and each header.
const STATUS_LINE_BYTES = 17;

const backoff = (attempt) => Math.min(BASE_DELAY_MS * 2 ** Math.max(0, attempt - 1), MAX_DELAY_MS);
const trimSlash = (url) => url.replace(/\/+$/, '');

class Core {
  constructor(module) {
    this.m = module;
  }

  // The last call's failure as the core worded it.
  error() {
    return this.m.UTF8ToString(this.m._pms_last_error());
  }

  text(ptr) {
    return this.m.UTF8ToString(ptr);
  }

  // `f(ptr, size)` with `bytes` copied into the core's memory for the call.
  withBytes(bytes, f) {
    const ptr = this.m._pms_alloc(bytes.length);
    try {
      this.m.HEAPU8.set(bytes, ptr);
      return f(ptr, bytes.length);
    } finally {
      this.m._pms_free(ptr);
    }
  }

  withString(text, f) {
    const size = this.m.lengthBytesUTF8(text) + 1;
    const ptr = this.m._pms_alloc(size);
    try {
      this.m.stringToUTF8(text, ptr, size);
      return f(ptr);
    } finally {
      this.m._pms_free(ptr);
    }
  }

  // GET /models, parsed: [{name, faces, vertices, ...}].
  async catalogue(server) {
    const answer = await fetch(`${trimSlash(server)}/models`);
    if (!answer.ok) throw new Error(`GET /models: ${answer.status}`);
    const json = await answer.json();
    if (!json || !Array.isArray(json.models)) throw new Error('GET /models: not the catalogue');
    return json.models;
  }
}

// The emscripten module at `url` (relative to the page), instantiated; `overrides` go to its factory
// (node passes wasmBinary).
export async function loadCore(url = 'pmstream_core.js', overrides = {}) {
  const base = globalThis.document?.baseURI ?? import.meta.url;
  const { default: create } = await import(new URL(url, base).href);
  return new Core(await create(overrides));
}

export function openViewer(core, options) {
  return new Viewer(core, options);
}

class Viewer {
  constructor(core, options) {
    this.core = core;
    this.m = core.m;
    this.options = options;
    this.server = trimSlash(options.server);
    this.onError = options.onError ?? (() => {});
    this.onStatus = options.onStatus ?? (() => {});
    this.mode = options.mode ?? 'sender';
    this.session = SESSION_MODES.has(this.mode);
    const coreOptions = {
      mode: this.mode,
      model: options.model,
      tolerance: options.tolerance ?? 1,
      morphFrames: options.morphFrames ?? 8,
      inFlight: options.inFlight ?? 4,
      ...(options.applyBudgetMs ? { applyBudgetMs: options.applyBudgetMs } : {}),
      ...(options.adaptBudgetMs ? { adaptBudgetMs: options.adaptBudgetMs } : {}),
      dag: options.dag ?? {},
      receiver: options.receiver ?? {},
      multilevel: options.multilevel ?? {},
    };
    this.handle = core.withString(JSON.stringify(coreOptions), (ptr) => this.m._pms_viewer_open(ptr));
    if (!this.handle) throw new Error(core.error());
    this.cameraPtr = this.m._pms_alloc(40);
    this.closed = false;
    this.failed = false;
    this.report = null;
    this.attempts = 0;   // reconnects since the last session that opened
    this.timers = new Set();
    this.openSocket = options.WebSocket ?? globalThis.WebSocket;
    if (this.session) this.connect();
  }

  // ---- per displayed frame ----

  frame(camera) {
    if (this.closed || this.failed) return this.report ?? { opening: true, frame: 0, faces: 0 };
    const f = new Float32Array(this.m.HEAPU8.buffer, this.cameraPtr, 10);
    f.set([...camera.eye, ...camera.target, ...(camera.up ?? [0, 1, 0]), camera.fovyDeg ?? 60]);
    const ptr = this.m._pms_viewer_frame(this.handle, this.cameraPtr, camera.width, camera.height);
    if (!ptr) return this.fail(this.core.error());
    const report = JSON.parse(this.core.text(ptr));
    if (this.session) this.flush();
    else this.fetchGets();
    if (!report.opening) this.attempts = 0;
    this.report = report;
    return report;
  }

  // Changes options on the open viewer, keeping its mesh: any of tolerance, morphFrames,
  // dag: {traversal, budget, maxOps}, receiver: {prefetch, background}, multilevel: {budget}. The model, the mode and
  // receiver.fetch need a new viewer. Throws (and changes nothing) for a value the core refuses.
  set(options) {
    if (this.closed || this.failed) return;
    const ok = this.core.withString(JSON.stringify(options), (ptr) => this.m._pms_viewer_set(this.handle, ptr));
    if (!ok) throw new Error(this.core.error());
    Object.assign(this.options, options);
  }

  // Views into the core's memory, valid until the next call into the viewer (memory may grow then).
  buffers() {
    const t = this.m._pms_viewer_buffers(this.handle);
    if (!t) return this.fail(this.core.error());
    const u32 = new Uint32Array(this.m.HEAPU8.buffer, t, 10);
    const [positions, normals, colors, indices, vertexCount, triangleCount, cv, cvCount, ct, ctCount] = u32;
    const buffer = this.m.HEAPU8.buffer;
    const ranges = (ptr, count) => {
      const pairs = new Uint32Array(buffer, ptr, 2 * count);
      const out = [];
      for (let i = 0; i < count; ++i) out.push([pairs[2 * i], pairs[2 * i + 1]]);
      return out;
    };
    return {
      positions: new Float32Array(buffer, positions, 3 * vertexCount),
      normals: new Float32Array(buffer, normals, 3 * vertexCount),
      colors: new Uint8Array(buffer, colors, 4 * vertexCount),
      indices: new Uint32Array(buffer, indices, 3 * triangleCount),
      vertexCount,
      triangleCount,
      changedVertices: ranges(cv, cvCount),
      changedTriangles: ranges(ct, ctCount),
    };
  }

  // {min, max} of the model once it is open, else null.
  bounds() {
    const ptr = this.m._pms_viewer_bounds(this.handle);
    return ptr ? JSON.parse(this.core.text(ptr)) : null;
  }

  wantsFaceIds() {
    return this.mode === 'receiver';
  }

  // The receiver's face-id frame: RGBA, face slot + 1 in RGB (R the low byte), 0 = background.
  setFaceIds(rgba, width, height) {
    const bytes = rgba instanceof Uint8Array ? rgba : new Uint8Array(rgba.buffer ?? rgba);
    const ok = this.core.withBytes(bytes, (ptr) => this.m._pms_viewer_face_ids(this.handle, ptr, width, height));
    if (!ok) this.fail(this.core.error());
  }

  // The mesh now, copied: {positions: Float32Array, faces: Uint32Array}.
  mesh() {
    const t = this.m._pms_viewer_mesh(this.handle);
    if (!t) return this.fail(this.core.error());
    const [positions, vertexCount, faces, faceCount] = new Uint32Array(this.m.HEAPU8.buffer, t, 4);
    return {
      positions: new Float32Array(this.m.HEAPU8.buffer, positions, 3 * vertexCount).slice(),
      faces: new Uint32Array(this.m.HEAPU8.buffer, faces, 3 * faceCount).slice(),
    };
  }

  settled() {
    return !this.failed && this.m._pms_viewer_settled(this.handle) === 1;
  }

  totals() {
    const ptr = this.m._pms_viewer_totals(this.handle);
    return ptr ? JSON.parse(this.core.text(ptr)) : {};
  }

  close() {
    if (this.closed) return;
    this.closed = true;
    for (const timer of this.timers) clearTimeout(timer);
    if (this.ws) {
      const ws = this.ws;
      this.ws = null;
      ws.close();
    }
    this.m._pms_free(this.cameraPtr);
    this.m._pms_viewer_close(this.handle);
  }

  // ---- private ----

  fail(message) {
    if (!this.failed) {
      this.failed = true;
      this.onError(message);
    }
    return this.report ?? { opening: true, frame: 0, faces: 0 };
  }

  later(f, ms) {
    const timer = setTimeout(() => {
      this.timers.delete(timer);
      if (!this.closed) f();
    }, ms);
    this.timers.add(timer);
  }

  // The session modes' socket: <server>/ws with the ws: scheme.
  connect() {
    const url = `${this.server.replace(/^http/, 'ws')}/ws`;
    let ws;
    try {
      ws = new this.openSocket(url);
    } catch (e) {
      return this.lost(null, String(e));
    }
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    this.wsOpen = false;
    ws.onopen = () => {
      if (this.ws !== ws) return;
      this.wsOpen = true;
      performance.mark('pmstream:connected');  // the bench's first-picture breakdown
      if (!this.m._pms_session_connected(this.handle)) return this.fail(this.core.error());
      this.onStatus(this.attempts ? 'reconnected: resuming' : 'connected');
      this.flush();
    };
    ws.onmessage = (event) => {
      if (this.ws !== ws || this.failed) return;
      if (!this.bytesIn) performance.mark('pmstream:first-bytes');
      this.bytesIn = true;
      const bytes = new Uint8Array(event.data);
      const ok = this.core.withBytes(bytes, (ptr, size) => this.m._pms_session_bytes(this.handle, ptr, size));
      if (!ok) this.fail(this.core.error());
    };
    ws.onclose = (event) => this.lost(ws, `closed${event?.reason ? `: ${event.reason}` : ''}`);
    ws.onerror = () => this.lost(ws, 'socket error');
  }

  lost(ws, reason) {
    if (this.closed || this.failed || (ws && this.ws !== ws)) return;
    this.ws = null;
    const wasOpen = this.wsOpen;
    this.wsOpen = false;
    // The frames that came whole are applied first: one may be the server's ERROR, which is final.
    if (wasOpen && !this.m._pms_session_disconnected(this.handle)) return this.fail(this.core.error());
    if (++this.attempts > RECONNECT_ATTEMPTS) return this.fail(`server: connection lost (${reason})`);
    const delay = backoff(this.attempts);
    this.onStatus(`connection lost (${reason}): reconnecting in ${Math.round(delay)} ms`);
    this.later(() => this.connect(), delay);
  }

  // The frames the core queued, one WebSocket message each.
  flush() {
    if (!this.ws || !this.wsOpen) return;
    const sizePtr = this.m._pms_alloc(4);
    try {
      const ptr = this.m._pms_session_outgoing(this.handle, sizePtr);
      if (!ptr) return this.fail(this.core.error());
      const size = new Uint32Array(this.m.HEAPU8.buffer, sizePtr, 1)[0];
      const bytes = new Uint8Array(this.m.HEAPU8.buffer, ptr, size).slice();
      const view = new DataView(bytes.buffer);
      for (let at = 0; at < size;) {
        const end = at + FRAME_HEADER_BYTES + view.getUint32(at, true);
        this.ws.send(bytes.subarray(at, end));
        at = end;
      }
    } finally {
      this.m._pms_free(sizePtr);
    }
  }

  // The HTTP modes' GETs: each fetched at once (the core posts no more than its pipe's room).
  fetchGets() {
    const ptr = this.m._pms_http_gets(this.handle);
    if (!ptr) return this.fail(this.core.error());
    for (const [id, target] of JSON.parse(this.core.text(ptr))) this.fetchGet(id, target, 1);
  }

  async fetchGet(id, target, attempt) {
    let answer, body;
    try {
      answer = await fetch(this.server + target);
      body = new Uint8Array(await answer.arrayBuffer());
    } catch (e) {
      if (this.closed || this.failed) return;
      if (attempt < FETCH_ATTEMPTS) {
        this.onStatus(`GET ${target} failed (${e.message ?? e}): retrying`);
        return this.later(() => this.fetchGet(id, target, attempt + 1), backoff(attempt));
      }
      this.core.withString(`GET ${target}: ${e.message ?? e}`, (reason) => this.m._pms_http_fail(this.handle, id, reason));
      return;
    }
    if (this.closed || this.failed) return;
    let headerBytes = STATUS_LINE_BYTES;
    answer.headers.forEach((value, name) => { headerBytes += name.length + value.length + 4; });
    const ok = this.core.withBytes(body, (p, n) =>
      this.m._pms_http_deliver(this.handle, id, answer.status, p, n, n + headerBytes));
    if (!ok) this.fail(this.core.error());
  }
}
