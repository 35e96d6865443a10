// The script of the page `corrlap view` writes (viewer/README.md): reads the embedded scene and
// geometry, shows the meshes, and offers window.corrlapView to scripts and tests.
import { readData, readScene } from './data.js';
import { createPanel, showError } from './panel.js';
import { Surface } from './surface.js';
import { Viewer } from './viewer.js';

let viewer = null;
const api = { fields: [], meshes: [] };

// Runs synchronously up to its first await, so api.fields and api.meshes are set when it returns.
async function load() {
  const scene = readScene();
  api.fields.push(...scene.fields.map((f) => String(f.name)));
  api.meshes.push(...scene.meshes.map((m) => String(m.name)));
  const panel = createPanel(scene, {
    visible: (i, on) => viewer && viewer.setVisible(i, on),
    layout: (layout) => viewer && viewer.setLayout(layout),
    field: (name) => viewer && viewer.setField(name),
    shading: (shading) => viewer && viewer.setShading(shading),
    wireframe: (on) => viewer && viewer.setWireframe(on),
    reset: () => viewer && viewer.resetView(),
  });
  const faces = scene.meshes.reduce((sum, m) => sum + (m.faces || 0), 0);
  panel.status(`loading ${faces.toLocaleString('en-US')} faces…`);
  const candidate = new Viewer(scene, panel);  // before the data: no WebGL fails at once
  const buffer = await readData(scene);
  performance.mark('corrlap: data decoded');  // the load's steps, for the browser's profiler
  await nextPaint();  // the status shows while the meshes are built
  const surfaces = scene.meshes.map((m) => new Surface(m, buffer, candidate.material, candidate.lineMaterial));
  performance.mark('corrlap: meshes built');
  viewer = candidate;
  await viewer.start(surfaces);
  performance.mark('corrlap: first frame');
  panel.status('');
  document.body.dataset.ready = '1';
  viewer.prepare();
}

function nextPaint() {
  return new Promise((resolve) => requestAnimationFrame(() => setTimeout(resolve, 0)));
}

function fail(error) {
  const message = error && error.message ? error.message : String(error);
  document.body.dataset.error = message;
  showError(message);
  throw error instanceof Error ? error : new Error(message);
}

const ready = load().catch(fail);
ready.catch(() => {});  // shown in the page; scripts see the rejection through corrlapView.ready

// Each call waits for the page to be ready, and resolves once the frame showing the change is drawn.
const once = (method) => (...args) => ready.then(() => viewer[method](...args));
window.corrlapView = Object.assign(api, {
  ready,
  setField: once('setField'),
  setVisible: once('setVisible'),
  setLayout: once('setLayout'),
  setShading: once('setShading'),
  setWireframe: once('setWireframe'),
  resetView: once('resetView'),
  pick: (x, y) => (viewer ? viewer.pick(x, y) : null),
});
