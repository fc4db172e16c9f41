// The page: loads the WASM core, opens a viewer for the model and mode the URL names, and per displayed
// frame hands the camera to the viewer, uploads what changed and draws.
import { Vector2 } from 'three';
import { loadCore, openViewer } from './pmstream.js';
import { createScene, fitDepthRange } from './scene.js';
import { MeshGeometry } from './mesh_geometry.js';
import { CameraControls } from './camera_controls.js';
import { Overlay, FrameRate } from './overlay.js';
import { ModePanel } from './mode_panel.js';
import { FaceIdPass } from './face_id_pass.js';
import { parseState, formatState, MODES } from './url_state.js';
import { viewerOptions, viewerTuning, changeKind, modesFor } from './viewer_options.js';
import { installHook } from './page_hook.js';

// The link follows the camera once it rests: a history write costs the browser milliseconds, too many to
// spend while the camera moves (and Chrome throttles frequent ones), and a link is shared from a view.
const URL_EVERY_MS = 500;

class App {
  constructor() {
    this.state = parseState(location.hash);
    this.server = this.state.server || location.origin;
    this.view = createScene(document.getElementById('view'));
    this.controls = new CameraControls(this.view.camera, this.view.renderer.domElement);
    this.controls.setStyle(this.state.camera);
    this.overlay = new Overlay(document.getElementById('overlay'));
    this.panel = new ModePanel(document.getElementById('panel'), (key, value) => this.change(key, value));
    this.faceIds = new FaceIdPass(this.view.renderer);
    this.frameRate = new FrameRate();
    this.geometry = null;
    this.reallocations = 0;
    this.opens = 0;  // viewers opened, and options changed in place: what the page tests count
    this.tunes = 0;
    this.viewer = null;
    this.report = null;
    this.bounds = null;
    this.scripted = null;
    this.errors = [];
    this.failed = false;
    this.lastTime = 0;
    this.lastUrl = 0;
    this.pendingLink = '';  // the link the last check wanted: written once a check finds it again
    this.view.material.wireframe = this.state.wireframe;
  }

  async start() {
    this.overlay.say('loading the core…');
    this.core = await loadCore('pmstream_core.js');
    performance.mark('pmstream:core');  // the bench's first-picture breakdown
    this.models = await this.core.catalogue(this.server);
    if (!this.models.length) throw new Error(`${this.server} serves no model`);
    this.panel.setModels(this.models);
    if (!this.models.some((m) => m.name === this.state.model)) this.state.model = this.models[0].name;
    this.open();
    performance.mark('pmstream:viewer');
    if (this.state.eye && this.state.target) this.controls.set(this.state);
    window.addEventListener('keydown', (e) => this.key(e));
    window.addEventListener('hashchange', () => this.followLink());
    requestAnimationFrame((t) => this.loop(t));
  }

  model() {
    return this.models?.find((m) => m.name === this.state.model);
  }

  open() {
    const model = this.model();
    if (!modesFor(model, MODES).includes(this.state.mode)) this.state.mode = modesFor(model, MODES)[0];
    this.viewer?.close();
    this.replay = null;
    this.newGeometry();
    this.bounds = null;
    this.report = null;
    this.failed = false;
    this.opens++;
    this.viewer = openViewer(this.core, viewerOptions(this.state, this.server, model?.faces ?? 0, {
      onError: (message) => this.fail(message),
      onStatus: (text) => this.overlay.say(text),
    }));
    this.panel.show(this.state);
    this.overlay.reset();
    this.overlay.say(`opening ${this.state.model} (${this.state.mode})…`);
  }

  // An empty mesh on the GPU: a new model, or a replay starting over.
  newGeometry() {
    if (this.geometry) {
      this.view.scene.remove(this.geometry.mesh);
      this.geometry.mesh.geometry.dispose();
    }
    this.geometry = new MeshGeometry(this.view.material);
    this.view.scene.add(this.geometry.mesh);
  }

  fail(message) {
    this.errors.push(String(message));
    this.overlay.say(String(message), true);
  }

  change(key, value) {
    this.state[key] = value;
    if (key === 'camera') this.controls.setStyle(value);
    if (key === 'wireframe') this.view.material.wireframe = value;
    if (key === 'model') this.state.eye = this.state.target = null;  // frame the new model
    const kind = changeKind(key);
    if (kind === 'reopen') this.open();
    else if (kind === 'tune') this.tune([key]);
    else this.panel.show(this.state);
  }

  // Options the open viewer takes in place, its mesh kept; one it refuses is said in the overlay.
  tune(keys) {
    this.panel.show(this.state);
    try {
      for (const key of keys) this.viewer.set(viewerTuning(key, this.state, this.model()?.faces ?? 0));
      this.tunes++;
    } catch (error) {
      this.overlay.say(String(error?.message ?? error), true);
    }
  }

  // A link pasted into the address bar: the camera moves, options go to the open viewer, a new model,
  // mode or fetch style reopens it.
  followLink() {
    const next = parseState(location.hash);
    const differs = (keys) => keys.filter((k) => next[k] !== this.state[k]);
    const reopen = differs(['model', 'mode', 'fetch']).length > 0;
    const tuned = differs(['tolerance', 'traversal', 'budget', 'maxOps', 'prefetch', 'idleMb', 'lod']);
    this.state = { ...next, model: next.model || this.state.model };
    if (reopen) this.open();
    else if (tuned.length) this.tune(tuned);
    if (next.eye && next.target) this.controls.set(next);
  }

  key(e) {
    if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
    if (e.key === 'c') this.change('camera', this.state.camera === 'orbit' ? 'fly' : 'orbit');
    if (e.key === 'l') this.change('wireframe', !this.state.wireframe);
  }

  script(camera) {
    this.scripted = camera;
    if (camera) this.controls.set({ ...camera, fovy: camera.fovyDeg });
  }

  cameraForViewer() {
    if (this.scripted) return this.scripted;
    const c = this.controls.state();
    const size = this.view.renderer.getDrawingBufferSize(new Vector2());
    return { eye: c.eye, target: c.target, up: c.up, fovyDeg: c.fovy, width: size.x, height: size.y };
  }

  loop(time) {
    requestAnimationFrame((t) => this.loop(t));
    const seconds = this.lastTime ? Math.min(0.1, (time - this.lastTime) / 1000) : 0;
    this.lastTime = time;
    if (!this.scripted) this.controls.update(seconds);
    // The page's own CPU time for the frame (WASM frame, buffer updates, JS), for the bench.
    const start = performance.now();
    if (!this.failed) this.step();
    this.stepMs = performance.now() - start;
    fitDepthRange(this.view.camera, this.bounds);
    this.view.renderer.render(this.view.scene, this.view.camera);
    this.renderMs = performance.now() - start - this.stepMs;  // three.js issuing the draw
    this.afterDraw?.(time);
    this.frameRate.tick(time);
    if (this.report) this.overlay.show(this.report, this.frameRate.value(), this.model()?.vsplits, time);
    if (time - this.lastUrl > URL_EVERY_MS) this.writeLink(time);
  }

  // One viewer frame: the camera in, what changed out to the GPU, and the face ids back in when asked.
  step() {
    try {
      if (this.replay) this.replayFrame();
      else this.viewerFrame();
      this.afterFrame?.(this.report);
    } catch (error) {
      this.failed = true;
      this.fail(error?.message ?? error);
    }
  }

  viewerFrame() {
    const wasRefused = Boolean(this.report?.refused);
    const start = performance.now();
    this.report = this.viewer.frame(this.cameraForViewer());
    this.coreMs = performance.now() - start;  // the viewer's frame alone, for the bench
    // A degenerate camera (eye on the target, say) is refused for that frame only: said while it lasts.
    if (this.report.refused) this.overlay.say(this.report.refused, true);
    else if (wasRefused) this.overlay.say('');
    if (this.report.opening) return;  // no model yet: nothing to draw
    if (!this.bounds) this.opened();
    const buffers = this.viewer.buffers();
    if (!buffers?.positions) return;  // the viewer failed: onError has said why
    this.onBuffers?.(buffers);
    const capacity = this.geometry.vertexCapacity;
    this.geometry.update(buffers);
    if (this.geometry.vertexCapacity !== capacity) this.reallocations++;
    if (this.viewer.wantsFaceIds()) this.faceIdPass();
  }

  // A recorded frame's buffers (frame_recorder.js) instead of the viewer's: no network, no core work.
  replayFrame() {
    const buffers = this.replay.next();
    if (buffers) this.geometry.update(buffers);
  }

  opened() {
    performance.mark('pmstream:opened');  // the base mesh in the viewer
    this.bounds = this.viewer.bounds();
    this.controls.setSpeed(Math.hypot(...this.bounds.max.map((v, i) => v - this.bounds.min[i])) / 2);
    if (!this.state.eye && !this.scripted) this.controls.frame(this.bounds);
    // The sun high over the model's up axis, a little to the side.
    const up = this.controls.orbitUp;
    this.view.sun.position.set(...up.map((v, i) => v || [0.4, 0.3, 0.3][i]));
    this.overlay.say('');
  }

  faceIdPass() {
    const g = this.geometry;
    fitDepthRange(this.view.camera, this.bounds);
    const ids = this.faceIds.run(this.view.camera, g.positions(), g.indices(), g.triangleCount);
    if (ids) this.viewer.setFaceIds(ids.rgba, ids.width, ids.height);
  }

  writeLink(time) {
    this.lastUrl = time;
    if (!this.bounds) return;
    const c = this.controls.state();
    Object.assign(this.state, { eye: c.eye, target: c.target, up: c.up, fovy: c.fovy });
    const link = formatState({ ...this.state, server: this.state.server });
    if (link === this.pendingLink && link !== location.hash) history.replaceState(null, '', link);
    this.pendingLink = link;
  }
}

const app = new App();
installHook(app);
app.start().catch((error) => app.fail(error?.message ?? String(error)));
