// The page's link format (web/js/url_state.js) without a browser: a state survives the round trip, and a
// malformed or hand-edited link falls back to defaults rather than failing.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { parseState, formatState, DEFAULTS, MODES, DAG_TRAVERSALS } from '../../web/js/url_state.js';
import { lodBudget, changeKind, viewerTuning } from '../../web/js/viewer_options.js';

test('every mode\'s state survives formatState then parseState', () => {
  for (const mode of MODES) {
    const state = { ...DEFAULTS, model: 'bunny', mode, tolerance: 0.5, traversal: 'constant', budget: 5000, maxOps: 300,
                    fetch: 'blocks', prefetch: true, idleMb: 16, lod: 420, camera: 'fly', wireframe: true,
                    eye: [1.5, -2.25, 3], target: [0, 0.125, 0], up: [0, 0, 1], fovy: 45 };
    const back = parseState(formatState(state));
    assert.equal(back.mode, mode);
    assert.equal(back.tolerance, 0.5);
    assert.deepEqual([back.eye, back.target, back.up, back.fovy], [state.eye, state.target, state.up, 45]);
    assert.deepEqual([back.camera, back.wireframe], ['fly', true]);
    if (mode === 'dag') assert.deepEqual([back.traversal, back.budget, back.maxOps], ['constant', 5000, 300]);
    if (mode === 'receiver') assert.deepEqual([back.fetch, back.prefetch, back.idleMb], ['blocks', true, 16]);
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

test('the DAG traversals are the core\'s names, in the link and in the panel', () => {
  assert.deepEqual(DAG_TRAVERSALS, ['priority', 'linear', 'constant']);
  assert.equal(DEFAULTS.traversal, 'priority');
  for (const name of DAG_TRAVERSALS) assert.equal(parseState(`#mode=dag&traversal=${name}`).traversal, name);
  for (const other of ['free', 'budget', 'change']) assert.equal(parseState(`#mode=dag&traversal=${other}`).traversal, 'priority');
  const html = fs.readFileSync(new URL('../../web/index.html', import.meta.url), 'utf8');
  const select = html.slice(html.indexOf('id="dag-traversal"'), html.indexOf('</select>', html.indexOf('id="dag-traversal"')));
  assert.deepEqual([...select.matchAll(/<option value="([^"]+)"/g)].map((m) => m[1]), DAG_TRAVERSALS);
});

test('options the open viewer takes go to viewer.set; model, mode and fetch reopen', () => {
  for (const key of ['tolerance', 'traversal', 'budget', 'maxOps', 'prefetch', 'idleMb', 'lod']) assert.equal(changeKind(key), 'tune', key);
  for (const key of ['model', 'mode', 'fetch']) assert.equal(changeKind(key), 'reopen', key);
  const state = { ...DEFAULTS, tolerance: 3, traversal: 'linear', budget: 900, maxOps: 50, prefetch: true, lod: 1000 };
  assert.deepEqual(viewerTuning('tolerance', state, 5000), { tolerance: 3 });
  assert.deepEqual(viewerTuning('budget', state, 5000), { dag: { traversal: 'linear', budget: 900, maxOps: 50 } });
  assert.deepEqual(viewerTuning('prefetch', state, 5000), { receiver: { prefetch: true } });
  assert.deepEqual(viewerTuning('idleMb', { ...state, idleMb: 2 }, 5000), { receiver: { background: 2 * 1024 * 1024 } });
  assert.deepEqual(viewerTuning('lod', state, 5000), { multilevel: { budget: 5000 } });
});
