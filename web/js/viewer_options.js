// The page's state as openViewer's options (web/js/pmstream.js).

// The LOD slider's 0 is the screen-size rule; above it a triangle budget, logarithmic up to the model's faces.
export function lodBudget(position, faces) {
  if (position <= 0 || !faces) return 0;
  return Math.max(1, Math.round(Math.pow(faces, position / 1000)));
}

// The core's share of a displayed frame: applying what arrived, then adapting the mesh (the walk and its
// splits and collapses). What does not fit carries to the next frames, so a burst (a region leaving the
// view collapses hundreds of vertices at once) spreads out instead of dropping a frame; together with the
// buffer updates and the page's JS they leave most of a 60 Hz frame to drawing.
export const APPLY_BUDGET_MS = 1;
export const ADAPT_BUDGET_MS = 1.5;

// The idle fetch's budget: the panel and the link give megabytes.
export function idleBytes(megabytes) {
  return Math.round(Math.max(0, megabytes) * 1024 * 1024);
}

export function viewerOptions(state, server, faces, callbacks) {
  return {
    server,
    mode: state.mode,
    model: state.model,
    tolerance: state.tolerance,
    morphFrames: 8,  // geomorphs on: the core blends splits and collapses, the page uploads the positions
    applyBudgetMs: APPLY_BUDGET_MS,
    adaptBudgetMs: ADAPT_BUDGET_MS,
    dag: { traversal: state.traversal, budget: state.budget, maxOps: state.maxOps },
    receiver: { fetch: state.fetch, prefetch: state.prefetch, background: idleBytes(state.idleMb) },
    multilevel: { budget: lodBudget(state.lod, faces) },
    ...callbacks,
  };
}

// The options an open viewer takes in place (viewer.set): the mesh is kept.
const TUNED = new Set(['tolerance', 'traversal', 'budget', 'maxOps', 'prefetch', 'idleMb', 'lod']);

// What a change of the key does: 'view' settings change the picture only, 'tune' ones go to the open viewer
// (viewer.set), the rest (model, mode, the receiver's fetch style) reopen it.
export function changeKind(key) {
  if (key === 'camera' || key === 'wireframe') return 'view';
  return TUNED.has(key) ? 'tune' : 'reopen';
}

// viewer.set's options for a change of `key` ('tune' kind) in `state`.
export function viewerTuning(key, state, faces) {
  if (key === 'tolerance') return { tolerance: state.tolerance };
  if (key === 'prefetch') return { receiver: { prefetch: state.prefetch } };
  if (key === 'idleMb') return { receiver: { background: idleBytes(state.idleMb) } };
  if (key === 'lod') return { multilevel: { budget: lodBudget(state.lod, faces) } };
  return { dag: { traversal: state.traversal, budget: state.budget, maxOps: state.maxOps } };
}

// A multilevel-only model (a `.pml`, catalogue kind "multilevel") has no progressive hierarchy to stream.
export function modesFor(model, modes) {
  return model?.kind === 'multilevel' ? ['multilevel'] : modes;
}
