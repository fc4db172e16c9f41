// The page's link format (web/js/url_state.js) without a browser: a state survives the round trip, and a
// malformed or hand-edited link falls back to defaults rather than failing.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { parseState, formatState, DEFAULTS, MODES } from '../../web/js/url_state.js';
import { lodBudget } from '../../web/js/viewer_options.js';

test('every mode\'s state survives formatState then parseState', () => {
  for (const mode of MODES) {
    const state = { ...DEFAULTS, model: 'bunny', mode, tolerance: 0.5, traversal: 'change', budget: 5000, maxOps: 300,
                    fetch: 'blocks', prefetch: true, lod: 420, camera: 'fly', wireframe: true,
                    eye: [1.5, -2.25, 3], target: [0, 0.125, 0], up: [0, 0, 1], fovy: 45 };
    const back = parseState(formatState(state));
    assert.equal(back.mode, mode);
    assert.equal(back.tolerance, 0.5);
    assert.deepEqual([back.eye, back.target, back.up, back.fovy], [state.eye, state.target, state.up, 45]);
    assert.deepEqual([back.camera, back.wireframe], ['fly', true]);
    if (mode === 'dag') assert.deepEqual([back.traversal, back.budget, back.maxOps], ['change', 5000, 300]);
    if (mode === 'receiver') assert.deepEqual([back.fetch, back.prefetch], ['blocks', true]);
    if (mode === 'multilevel') assert.equal(back.lod, 420);
  }
});

test('a malformed link opens with defaults', () => {
  const s = parseState('#mode=warp&tau=-3&eye=1,2&target=a,b,c&fovy=0&lod=x&fetch=all');
  assert.deepEqual([s.mode, s.tolerance, s.eye, s.target, s.fovy >= 1, s.lod, s.fetch],
                   [DEFAULTS.mode, DEFAULTS.tolerance, null, null, true, 0, 'lists']);
});

test('the LOD slider: 0 is the screen-size rule, then budgets rise to the model\'s faces', () => {
  assert.equal(lodBudget(0, 100000), 0);
  let last = 0;
  for (let p = 1; p <= 1000; p += 37) {
    const b = lodBudget(p, 100000);
    assert.ok(b >= last && b >= 1, `${p}: ${b}`);
    last = b;
  }
  assert.equal(lodBudget(1000, 100000), 100000);
});
