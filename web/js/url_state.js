// The page's state in the URL's hash, so that a view can be shared as a link:
//   #model=bunny&mode=sender&tau=1&eye=x,y,z&target=x,y,z&up=0,1,0&fovy=60&camera=orbit
// plus the mode's own options (traversal, budget, maxops; fetch, prefetch, idle; lod) and wireframe.
// Anything missing or malformed falls back to the default, so a hand-edited link still opens.

export const MODES = ['sender', 'sender-plain', 'vi', 'dag', 'receiver', 'multilevel'];
// The DAG traversals by the core's names (`pmstream stream --traversal`); a budget > 0 picks the budget
// variant of the one named, as --budget does.
export const DAG_TRAVERSALS = ['priority', 'linear', 'constant'];

export const DEFAULTS = Object.freeze({
  server: '', model: '', mode: 'sender', tolerance: 1, camera: 'orbit', wireframe: false,
  traversal: 'priority', budget: 0, maxOps: 0, fetch: 'lists', prefetch: false, idleMb: 0, lod: 0,
  eye: null, target: null, up: [0, 1, 0], fovy: 60,
});

function number(text, fallback, min = -Infinity) {
  const value = Number(text);
  return text !== null && text !== '' && Number.isFinite(value) && value >= min ? value : fallback;
}

function vector(text) {
  if (!text) return null;
  const parts = text.split(',').map(Number);
  return parts.length === 3 && parts.every(Number.isFinite) ? parts : null;
}

function oneOf(text, choices, fallback) {
  return choices.includes(text) ? text : fallback;
}

export function parseState(hash) {
  const q = new URLSearchParams(hash.replace(/^#/, ''));
  return {
    server: q.get('server') || DEFAULTS.server,
    model: q.get('model') || DEFAULTS.model,
    mode: oneOf(q.get('mode'), MODES, DEFAULTS.mode),
    tolerance: number(q.get('tau'), DEFAULTS.tolerance, 0),
    camera: oneOf(q.get('camera'), ['orbit', 'fly'], DEFAULTS.camera),
    wireframe: q.get('wire') === '1',
    traversal: oneOf(q.get('traversal'), DAG_TRAVERSALS, DEFAULTS.traversal),
    budget: Math.floor(number(q.get('budget'), DEFAULTS.budget, 0)),
    maxOps: Math.floor(number(q.get('maxops'), DEFAULTS.maxOps, 0)),
    fetch: oneOf(q.get('fetch'), ['lists', 'blocks'], DEFAULTS.fetch),
    prefetch: q.get('prefetch') === '1',
    idleMb: number(q.get('idle'), DEFAULTS.idleMb, 0),
    lod: Math.floor(number(q.get('lod'), DEFAULTS.lod, 0)),
    eye: vector(q.get('eye')),
    target: vector(q.get('target')),
    up: vector(q.get('up')) || DEFAULTS.up,
    fovy: Math.min(179, number(q.get('fovy'), DEFAULTS.fovy, 1)),
  };
}

// Only what differs from the defaults, in a fixed order, with the camera rounded to what a link needs.
export function formatState(state) {
  const q = new URLSearchParams();
  const round = (v) => v.map((x) => Number(x.toPrecision(6))).join(',');
  if (state.server) q.set('server', state.server);
  if (state.model) q.set('model', state.model);
  q.set('mode', state.mode);
  q.set('tau', String(state.tolerance));
  if (state.mode === 'dag') {
    q.set('traversal', state.traversal);
    if (state.budget) q.set('budget', String(state.budget));
    if (state.maxOps) q.set('maxops', String(state.maxOps));
  }
  if (state.mode === 'receiver') {
    q.set('fetch', state.fetch);
    if (state.prefetch) q.set('prefetch', '1');
    if (state.idleMb) q.set('idle', String(state.idleMb));
  }
  if (state.mode === 'multilevel' && state.lod) q.set('lod', String(state.lod));
  if (state.camera !== DEFAULTS.camera) q.set('camera', state.camera);
  if (state.wireframe) q.set('wire', '1');
  if (state.eye && state.target) {
    q.set('eye', round(state.eye));
    q.set('target', round(state.target));
    q.set('up', round(state.up));
    q.set('fovy', String(state.fovy));
  }
  return '#' + q.toString().replaceAll('%2C', ',');
}
