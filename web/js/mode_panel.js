// The side panel: model, mode and each mode's own controls, camera style, wireframe. It holds no state of
// its own: it shows a state (url_state.js) and reports each change as a new one.
import { MODES } from './url_state.js';
import { modesFor, lodBudget } from './viewer_options.js';

export class ModePanel {
  constructor(root, onChange) {
    this.root = root;
    this.onChange = onChange;
    this.faces = 0;  // the model's, for the LOD slider's scale
    const $ = (id) => root.querySelector('#' + id);
    this.inputs = {
      model: $('model'), mode: $('mode'), tolerance: $('tolerance'), traversal: $('dag-traversal'),
      budget: $('dag-budget'), maxOps: $('dag-max-ops'), fetch: $('receiver-fetch'), prefetch: $('receiver-prefetch'),
      idleMb: $('receiver-idle'), lod: $('lod'), camera: $('camera-style'), wireframe: $('wireframe'),
    };
    this.lodValue = $('lod-value');
    for (const [key, input] of Object.entries(this.inputs)) {
      // A slider reports once it is let go: the open viewer takes the new value (main.js).
      input.addEventListener('change', () => this.onChange(key, this.read(key)));
    }
    this.inputs.lod.addEventListener('input', () => this.showLod());
  }

  setModels(models) {
    this.models = models;
    this.inputs.model.replaceChildren(...models.map((m) => {
      const option = document.createElement('option');
      option.value = m.name;
      option.textContent = `${m.name} (${Number(m.faces ?? 0).toLocaleString('en-US')} faces)`;
      return option;
    }));
  }

  show(state) {
    const i = this.inputs;
    i.model.value = state.model;
    i.mode.value = state.mode;
    i.tolerance.value = state.tolerance;
    i.traversal.value = state.traversal;
    i.budget.value = state.budget;
    i.maxOps.value = state.maxOps;
    i.fetch.value = state.fetch;
    i.prefetch.checked = state.prefetch;
    i.idleMb.value = state.idleMb;
    i.lod.value = state.lod;
    i.camera.value = state.camera;
    i.wireframe.checked = state.wireframe;
    const model = this.models?.find((m) => m.name === state.model);
    this.faces = model?.faces ?? 0;
    const modes = modesFor(model, MODES);
    for (const option of i.mode.options) option.disabled = !modes.includes(option.value);
    for (const set of this.root.querySelectorAll('fieldset[data-mode]')) set.hidden = set.dataset.mode !== state.mode;
    this.showLod();
  }

  showLod() {
    const budget = lodBudget(Number(this.inputs.lod.value), this.faces);
    this.lodValue.textContent = budget ? `${budget.toLocaleString('en-US')} triangles` : 'screen-size rule';
  }

  read(key) {
    const input = this.inputs[key];
    if (input.type === 'checkbox') return input.checked;
    if (input.type === 'number' || input.type === 'range') return Math.max(0, Number(input.value) || 0);
    return input.value;
  }
}
