// The overlay: what the viewer holds and what it cost, per displayed frame, and a progress bar while data
// arrives. Reads only the frame report (web/js/pmstream.js) and the page's own frame rate.

const SHOW_EVERY_MS = 250;

function bytes(n) {
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KiB`;
  return `${(n / 1024 / 1024).toFixed(2)} MiB`;
}

function count(n) {
  return Number(n ?? 0).toLocaleString('en-US');
}

// Frames per second over the last second of frames.
export class FrameRate {
  constructor() { this.times = []; }
  tick(now) {
    this.times.push(now);
    while (this.times.length > 2 && now - this.times[0] > 1000) this.times.shift();
  }
  value() {
    const n = this.times.length;
    return n < 2 ? 0 : ((n - 1) * 1000) / (this.times[n - 1] - this.times[0]);
  }
}

export class Overlay {
  constructor(root) {
    this.stats = root.querySelector('#stats');
    this.progress = root.querySelector('#progress');
    this.bar = root.querySelector('#progress-bar');
    this.status = root.querySelector('#status');
    this.root = root;
    this.latencyMs = 0;
    this.busy = null;
    this.shownAt = -Infinity;
  }

  // modelTotal: what the model has of the unit received (its splits, or levels), for the "of N" and the bar.
  // Written a few times a second, and when the busy state flips: each write restyles the page, a cost the
  // frame should not pay for figures nobody reads at 60 Hz.
  show(report, fps, modelTotal, now = performance.now()) {
    if (report.latencyMs > 0) this.latencyMs = report.latencyMs;  // a frame reports it when an answer came
    const busy = Boolean(report.opening || !report.satisfied || report.inFlight > 0);
    if (busy === this.busy && now - this.shownAt < SHOW_EVERY_MS) return;
    this.busy = busy;
    this.shownAt = now;
    const unit = report.receivedUnit || 'vsplits';
    const total = unit === 'levels' ? report.levels?.count : modelTotal;
    const received = report.receivedTotal ?? 0;
    const lines = [
      `faces      ${count(report.faces)}`,
      `vertices   ${count(report.vertices)}`,
      `${unit.padEnd(10)} ${count(received)}${total ? ` of ${count(total)}` : ''}`,
      `down       ${bytes(report.downBytes ?? 0)}`,
      `up         ${bytes(report.upBytes ?? 0)}`,
      `latency    ${this.latencyMs ? `${this.latencyMs.toFixed(1)} ms` : '–'}`,
      `fps        ${fps.toFixed(1)}`,
    ];
    if (report.levels) lines.push(`levels     ${report.levels.shown} shown, ${report.levels.loaded} in`);
    this.stats.textContent = lines.join('\n');
    // The same figures as numbers, for a script reading the page (the browser tests do).
    Object.assign(this.stats.dataset, {
      faces: report.faces ?? 0, vertices: report.vertices ?? 0, received,
      down: report.downBytes ?? 0, up: report.upBytes ?? 0,
    });
    // Data is arriving while the view is unsatisfied or anything is in flight; the bar is how much of the
    // model is in, and moves (css) while busy.
    this.progress.classList.toggle('busy', busy);
    this.bar.style.width = `${Math.round(Math.min(1, total ? received / total : 0) * 100)}%`;
    this.root.dataset.busy = busy ? '1' : '0';
  }

  // A new viewer: nothing measured yet.
  reset() {
    this.latencyMs = 0;
    this.busy = null;
  }

  say(text, error = false) {
    this.status.textContent = text;
    this.status.classList.toggle('error', error);
  }
}
