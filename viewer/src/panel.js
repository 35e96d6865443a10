// The page's controls: a compact panel at the top left (meshes, layout, field and its legend,
// shading, wireframe, reset), the readout of the value under the cursor, and the error message.
// Everything is created here, names from the scene set as text (never as HTML).

const CSS = `
html, body { margin: 0; height: 100%; overflow: hidden; background: #fff; }
body { font: 13px/1.35 system-ui, sans-serif; color: #222; }
.cl-canvas { display: block; position: fixed; inset: 0; }
.cl-panel { position: fixed; top: 8px; left: 8px; width: 250px; max-height: calc(100% - 16px);
  overflow: auto; box-sizing: border-box; padding: 8px 10px; background: rgba(255,255,255,0.92);
  border: 1px solid #ccc; border-radius: 6px; box-shadow: 0 1px 4px rgba(0,0,0,0.12); }
.cl-title { font-weight: 600; margin-bottom: 6px; overflow-wrap: anywhere; }
.cl-row { display: flex; align-items: center; gap: 6px; margin: 4px 0; }
.cl-row > span:first-child { width: 58px; color: #555; flex: none; }
.cl-row select { flex: 1; min-width: 0; font: inherit; }
.cl-mesh { display: block; margin: 2px 0; padding-left: 22px; text-indent: -22px; }
.cl-mesh input { margin: 0 6px 0 2px; vertical-align: -2px; }
.cl-mesh small { color: #777; white-space: nowrap; margin-left: 6px; text-indent: 0; display: inline-block; }
.cl-mesh b { font-weight: 500; overflow-wrap: anywhere; }
.cl-legend { margin: 6px 0 4px; }
.cl-bar { height: 12px; border: 1px solid #999; }
.cl-ticks { position: relative; height: 15px; font-size: 11px; color: #444; }
.cl-ticks span { position: absolute; top: 1px; transform: translateX(-50%); white-space: nowrap; }
.cl-ticks span:first-child { transform: none; }
.cl-ticks span:last-child { transform: translateX(-100%); }
.cl-name { text-align: center; font-size: 12px; color: #333; }
.cl-status { color: #555; margin-top: 4px; }
.cl-status:empty, .cl-readout:empty { display: none; }
.cl-readout { position: fixed; bottom: 8px; left: 8px; padding: 5px 8px; white-space: pre;
  font: 12px/1.35 ui-monospace, monospace; background: rgba(255,255,255,0.92); border: 1px solid #ccc;
  border-radius: 4px; pointer-events: none; }
.cl-error { position: fixed; top: 50%; left: 50%; transform: translate(-50%, -50%); max-width: 70%;
  padding: 16px 20px; background: #fff4f4; border: 1px solid #d66; border-radius: 6px; color: #900; }
`;

function injectStyle() {
  if (!document.getElementById('cl-style')) document.head.append(element('style', { id: 'cl-style', textContent: CSS }));
}

function element(tag, props = {}, children = []) {
  const node = document.createElement(tag);
  Object.assign(node, props);
  for (const child of children) node.append(child);
  return node;
}

function row(label, control) {
  return element('label', { className: 'cl-row' }, [element('span', { textContent: label }), control]);
}

function select(options, onChange) {
  const node = element('select', {}, options.map(([value, text]) => element('option', { value, textContent: text })));
  node.addEventListener('change', () => onChange(node.value));
  return node;
}

/** A number short enough for a legend or a readout. */
export function formatNumber(x, digits = 3) {
  if (x === 0) return '0';
  const a = Math.abs(x);
  return a >= 1e5 || a < 1e-3 ? x.toExponential(digits - 1) : String(Number(x.toPrecision(digits)));
}

/**
 * The panel for `scene`; `actions` ({visible(i, on), layout(v), field(name|null), shading(v),
 * wireframe(on), reset()}) are called on the user's changes. Returns what the viewer updates.
 */
export function createPanel(scene, actions) {
  injectStyle();
  const count = (n) => Number(n).toLocaleString('en-US');
  const meshBoxes = scene.meshes.map((mesh, i) => {
    const box = element('input', { type: 'checkbox', checked: !!mesh.visible });
    box.addEventListener('change', () => actions.visible(i, box.checked));
    return box;
  });
  const meshes = scene.meshes.map((mesh, i) => element('label', { className: 'cl-mesh' }, [meshBoxes[i],
    element('b', { textContent: String(mesh.name) }),
    element('small', { textContent: `${count(mesh.vertices)} V, ${count(mesh.faces)} F` })]));
  const layout = select([['overlay', 'overlaid'], ['side', 'side by side']], actions.layout);
  const field = select([['-1', 'none'], ...scene.fields.map((f, i) => [String(i), String(f.name)])],
    (v) => actions.field(v === '-1' ? null : scene.fields[Number(v)].name));
  const shading = select([['flat', 'flat'], ['smooth', 'smooth']], actions.shading);
  const wireframe = element('input', { type: 'checkbox' });
  wireframe.addEventListener('change', () => actions.wireframe(wireframe.checked));
  const reset = element('button', { textContent: 'reset view', title: 'key r' });
  reset.addEventListener('click', actions.reset);
  const bar = element('div', { className: 'cl-bar' }), ticks = element('div', { className: 'cl-ticks' });
  const fieldName = element('div', { className: 'cl-name' });
  const legend = element('div', { className: 'cl-legend', style: 'display: none' }, [bar, ticks, fieldName]);
  const status = element('div', { className: 'cl-status' });
  const readout = element('div', { className: 'cl-readout' });
  const panel = element('div', { className: 'cl-panel' }, [
    element('div', { className: 'cl-title', textContent: String(scene.title || 'corrlap view') }),
    ...meshes,
    scene.meshes.length > 1 ? row('layout', layout) : '',
    row('field', field), legend, row('shading', shading),
    row('wireframe', wireframe), reset, status]);
  document.body.append(panel, readout);

  return {
    /** Shows the viewer's state ({field, layout, smooth, wireframe}, visible[i]) in the controls. */
    sync(state, visible) {
      visible.forEach((on, i) => { meshBoxes[i].checked = on; });
      layout.value = state.layout;
      field.value = String(scene.fields.findIndex((f) => f.name === state.field));
      shading.value = state.smooth ? 'smooth' : 'flat';
      wireframe.checked = state.wireframe;
    },
    /** The colour bar of `info` ({name, min, max, stops, colormap}), hidden when null. */
    legend(info) {
      legend.style.display = info ? '' : 'none';
      if (!info) return;
      const rgb = (k) => `rgb(${[0, 1, 2].map((c) => Math.round(255 * info.stops[3 * k + c])).join(',')})`;
      const n = info.stops.length / 3;
      bar.style.background = `linear-gradient(to right, ${Array.from({ length: n },
        (_, k) => `${rgb(k)} ${(100 * k) / (n - 1)}%`).join(', ')})`;
      const marks = [[info.min, 0]];
      if (info.colormap === 'diverging' && info.min < 0 && info.max > 0)
        marks.push([0, (-info.min / (info.max - info.min)) * 100]);
      marks.push([info.max, 100]);
      ticks.replaceChildren(...marks.map(([v, at]) =>
        element('span', { textContent: formatNumber(v), style: `left: ${at}%` })));
      fieldName.textContent = info.name;
    },
    status(text) { status.textContent = text; },
    /** The panel's right edge in CSS pixels. */
    right() { return panel.getBoundingClientRect().right; },
    readout(text) { readout.textContent = text; },
  };
}

/** A clear message in the page when it cannot show the meshes. */
export function showError(message) {
  injectStyle();
  for (const node of document.querySelectorAll('.cl-panel, .cl-readout, .cl-canvas')) node.remove();
  document.body.append(element('div', { className: 'cl-error', textContent: `The view cannot be shown: ${message}` }));
}
