// The page's state as openViewer's options (web/js/pmstream.js).
import { lodBudget } from './mode_panel.js';

export function viewerOptions(state, server, faces, callbacks) {
  return {
    server,
    mode: state.mode,
    model: state.model,
    tolerance: state.tolerance,
    morphFrames: 8,  // geomorphs on: the core blends splits and collapses, the page uploads the positions
    dag: { traversal: state.traversal, budget: state.budget, maxOps: state.maxOps },
    receiver: { fetch: state.fetch, prefetch: state.prefetch },
    multilevel: { budget: lodBudget(state.lod, faces) },
    ...callbacks,
  };
}

// What a change of the key does: 'view' settings change the picture only; the rest reopen the viewer.
export function changeKind(key) {
  return key === 'camera' || key === 'wireframe' ? 'view' : 'reopen';
}
