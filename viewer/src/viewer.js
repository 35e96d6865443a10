// The 3D view: renderer, camera and orbit controls, lights like the PNG renderer's, the meshes'
// layout, and the frames, drawn only when something changed.
import {
  AmbientLight, Color, DirectionalLight, DoubleSide, LineBasicMaterial, LinearSRGBColorSpace,
  MeshLambertMaterial, PerspectiveCamera, Scene, Vector3, WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { formatNumber } from './panel.js';

const LAYOUTS = ['overlay', 'side'];
const SHADINGS = ['flat', 'smooth'];

export class Viewer {
  constructor(scene, panel) {
    this.panel = panel;
    this.fields = new Map(scene.fields.map((f) => [f.name, fieldInfo(f, scene.colormaps || {})]));
    this.visible = scene.meshes.map((m) => !!m.visible);
    this.state = { field: this.fields.has(scene.initial_field) ? scene.initial_field : null,
      layout: LAYOUTS.includes(scene.layout) ? scene.layout : 'overlay', smooth: false, wireframe: false };
    this.direction = vector(scene.view && scene.view.direction, [1, -1.4, 0.9]).normalize();
    this.up = vector(scene.view && scene.view.up, [0, 0, 1]).normalize();
    if (Math.abs(this.up.dot(this.direction)) > 0.999) this.up.set(this.direction.z, this.direction.x, this.direction.y);
    this.surfaces = [];
    this.waiting = [];

    try {
      this.renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    } catch (error) {
      throw new Error(`WebGL is not available in this browser (${error.message})`);
    }
    // The colours go to the screen as they are, as in the PNG pictures (no sRGB encoding on top).
    this.renderer.outputColorSpace = LinearSRGBColorSpace;
    this.renderer.domElement.className = 'cl-canvas';
    document.body.prepend(this.renderer.domElement);

    this.material = new MeshLambertMaterial({ vertexColors: true, side: DoubleSide, flatShading: true,
      // Behind the wireframe's lines drawn at the same depth.
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
    this.lineMaterial = new LineBasicMaterial({ color: new Color().setRGB(0.1, 0.1, 0.1), transparent: true,
      opacity: 0.45 });
    this.world = new Scene();
    this.world.background = new Color(1, 1, 1);
    this.camera = new PerspectiveCamera(30, 1, 1, 2);
    this.camera.up.copy(this.up);
    this.addLights();
    this.resize();
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.listen();
  }

  // The PNG renderer's shade 0.2 + 0.5 max(0, n.key) + 0.3 n.toward_viewer: an ambient, a key light
  // from the upper left in front and a fill from the viewer, all following the camera. Three.js
  // divides a Lambert surface's light by pi.
  addLights() {
    const key = new DirectionalLight(0xffffff, 0.5 * Math.PI), fill = new DirectionalLight(0xffffff, 0.3 * Math.PI);
    key.position.set(-0.3, 1.2, 1);
    fill.position.set(0, 0, 1);
    for (const light of [key, fill]) {
      this.camera.add(light);
      this.camera.add(light.target);  // at the camera: the light shines along the camera's -z
    }
    this.world.add(new AmbientLight(0xffffff, 0.2 * Math.PI), this.camera);
  }

  listen() {
    const canvas = this.renderer.domElement;
    this.controls.addEventListener('change', () => { this.frame(); this.hoverLater(); });
    this.controls.addEventListener('start', () => { this.dragging = true; this.panel.readout(''); });
    this.controls.addEventListener('end', () => { this.dragging = false; });
    window.addEventListener('resize', () => { this.resize(); this.frame(); });
    window.addEventListener('keydown', (event) => {
      const typing = /^(SELECT|TEXTAREA)$/.test(event.target.tagName);  // where r means something
      if ((event.key === 'r' || event.key === 'R') && !typing && !event.ctrlKey && !event.metaKey && !event.altKey)
        this.resetView();
    });
    canvas.addEventListener('pointermove', (event) => {
      this.pointer = event.buttons ? null : [event.offsetX, event.offsetY];
      this.hoverLater();
    });
    canvas.addEventListener('pointerleave', () => { this.pointer = null; this.hoverLater(); });
  }

  // The readout once the pointer rested a moment: at most one pick per frame, none while dragging.
  hoverLater() {
    clearTimeout(this.hoverTimer);
    if (!this.pointer || this.dragging) {
      this.panel.readout('');
      return;
    }
    this.hoverTimer = setTimeout(() => requestAnimationFrame(() => {
      if (!this.pointer || this.dragging) return;
      this.panel.readout(this.describe(this.pick(...this.pointer)));
    }), 60);
  }

  describe(hit) {
    if (!hit) return '';
    const p = hit.position.map((x) => formatNumber(x, 5)).join(', ');
    const lines = [`${hit.mesh}   face ${hit.face}   vertex ${hit.vertex}`, `at (${p})`];
    if (this.state.field !== null)
      lines.push(`${this.state.field} = ${hit.value === null ? 'undefined' : formatNumber(hit.value, 5)}`);
    return lines.join('\n');
  }

  // The canvas fills the window; when the window is wide enough, the view's centre is the centre of
  // the area right of the panel (a view offset), so that the panel does not hide the meshes.
  resize() {
    const width = window.innerWidth, height = Math.max(1, window.innerHeight);
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setSize(width, height);
    const panel = this.panel.right() + 8;
    const left = width > 3 * panel ? panel : 0;
    this.camera.aspect = (width + left) / height;
    this.freeAspect = (width - left) / height;  // of the area the meshes are fitted in
    if (left) this.camera.setViewOffset(width + left, height, 0, 0, width, height);
    else this.camera.clearViewOffset();
    this.camera.updateProjectionMatrix();
  }

  /** Takes the meshes (surface.js) and shows the first frame; resolves once it is drawn. */
  start(surfaces) {
    this.surfaces = surfaces;
    for (const surface of surfaces) this.world.add(surface.group);
    this.resetView();
    return this.update();
  }

  // The state into the meshes, the material and the panel; then a frame.
  update() {
    const field = this.state.field === null ? null : this.fields.get(this.state.field);
    if (this.material.flatShading === this.state.smooth) {
      this.material.flatShading = !this.state.smooth;
      this.material.needsUpdate = true;
    }
    this.surfaces.forEach((surface, i) => {
      surface.group.visible = this.visible[i];
      if (this.visible[i]) surface.show(field, this.state.smooth, this.state.wireframe);
    });
    this.panel.sync(this.state, this.visible);
    this.panel.legend(field || null);
    return this.frame();
  }

  /** A promise resolved once the next frame is drawn (one frame for every change until then). */
  frame() {
    const drawn = new Promise((resolve) => this.waiting.push(resolve));
    if (!this.framePending) {
      this.framePending = true;
      requestAnimationFrame(() => this.draw());
    }
    return drawn;
  }

  draw() {
    this.framePending = false;
    this.fitDepthRange();
    this.renderer.render(this.world, this.camera);
    for (const resolve of this.waiting.splice(0)) resolve();
  }

  // Near and far planes around the visible meshes, wherever the controls took the camera: the depth
  // buffer's precision where the surfaces are.
  fitDepthRange() {
    const sphere = this.visibleSphere();
    if (!sphere) return;
    const distance = this.camera.position.distanceTo(sphere.center);
    this.camera.near = Math.max(distance - 1.1 * sphere.radius, 1e-3 * sphere.radius, 1e-6 * distance);
    this.camera.far = distance + 1.1 * sphere.radius;
    this.camera.updateProjectionMatrix();
  }

  /** The bounding sphere {center, radius} of the visible meshes' boxes (of all when none is shown). */
  visibleSphere() {
    let shown = this.surfaces.filter((s, i) => this.visible[i]);
    if (shown.length === 0) shown = this.surfaces;
    const lo = new Vector3(Infinity, Infinity, Infinity), hi = new Vector3(-Infinity, -Infinity, -Infinity);
    for (const s of shown) {
      if (!(s.bounds.lo[0] <= s.bounds.hi[0])) continue;  // no vertex
      lo.min(new Vector3(...s.bounds.lo).add(s.group.position));
      hi.max(new Vector3(...s.bounds.hi).add(s.group.position));
    }
    if (!(lo.x <= hi.x)) return null;
    return { center: lo.clone().add(hi).multiplyScalar(0.5), radius: Math.max(hi.distanceTo(lo) / 2, 1e-9) };
  }

  /** The initial view: along -direction, up upwards, the visible meshes fitted. */
  resetView() {
    this.camera.up.copy(this.up);
    this.camera.position.copy(this.direction);
    this.controls.target.set(0, 0, 0);
    this.place();
    this.fit();
    return this.frame();
  }

  // The camera moved along its current direction, aimed at the visible meshes' centre, as near as
  // it can while every visible vertex stays in the picture with a margin (as the PNG pictures).
  fit() {
    const sphere = this.visibleSphere();
    if (!sphere) return;
    const toward = this.camera.position.clone().sub(this.controls.target).normalize();
    const right = new Vector3().crossVectors(this.camera.up, toward).normalize();
    const up = new Vector3().crossVectors(toward, right);
    const tanV = 0.92 * Math.tan((this.camera.fov * Math.PI) / 360), tanH = tanV * this.freeAspect;
    let distance = 0;
    this.surfaces.forEach((s, i) => {
      if (this.visible[i]) distance = Math.max(distance,
        s.viewDistance(sphere.center.clone().sub(s.group.position), right, up, toward, tanH, tanV));
    });
    if (!(distance > 0)) distance = sphere.radius / tanV;  // nothing visible: all the meshes' sphere
    this.controls.target.copy(sphere.center);
    this.camera.position.copy(sphere.center).addScaledVector(toward, distance);
    this.camera.lookAt(sphere.center);
    this.controls.update();
  }

  // Side by side: the visible meshes in scene order along the screen's right axis, one slot the
  // width of the widest plus a gap apart, centred where they were. Overlaid: where they are.
  place() {
    for (const s of this.surfaces) s.group.position.set(0, 0, 0);
    if (this.state.layout !== 'side') return;
    const forward = this.controls.target.clone().sub(this.camera.position);
    const right = forward.cross(this.camera.up).normalize();
    const shown = this.surfaces.filter((s, i) => this.visible[i] && s.bounds.lo[0] <= s.bounds.hi[0]);
    const spans = shown.map((s) => span(s.bounds, right));
    const step = 1.1 * Math.max(...spans.map(([lo, hi]) => hi - lo));
    const middle = spans.reduce((sum, [lo, hi]) => sum + (lo + hi) / 2, 0) / shown.length;
    shown.forEach((s, k) => {
      const [lo, hi] = spans[k];
      s.group.position.copy(right).multiplyScalar((k - (shown.length - 1) / 2) * step + middle - (lo + hi) / 2);
    });
  }

  /** Builds, while the page is idle, what the first readout over each visible mesh would wait for. */
  prepare() {
    const next = this.surfaces.find((s, i) => this.visible[i] && !s.picker);
    if (!next) return;
    // Not only when idle: a slow GPU may leave no idle period for long.
    const later = window.requestIdleCallback ? (f) => requestIdleCallback(f, { timeout: 500 }) : (f) => setTimeout(f, 200);
    later(() => {
      next.preparePicking();
      this.prepare();
    });
  }

  setField(name) {
    if (name !== null && !this.fields.has(name)) throw new Error(`no field "${name}"`);
    this.state.field = name;
    return this.update();
  }

  setVisible(index, on) {
    if (!Number.isInteger(index) || index < 0 || index >= this.surfaces.length) throw new Error(`no mesh ${index}`);
    this.visible[index] = !!on;
    this.prepare();
    if (this.state.layout === 'side') {
      this.place();
      this.fit();
    }
    return this.update();
  }

  setLayout(layout) {
    if (!LAYOUTS.includes(layout)) throw new Error(`layout "${layout}": expected overlay or side`);
    this.state.layout = layout;
    this.place();
    this.fit();
    return this.update();
  }

  setShading(shading) {
    if (!SHADINGS.includes(shading)) throw new Error(`shading "${shading}": expected flat or smooth`);
    this.state.smooth = shading === 'smooth';
    return this.update();
  }

  setWireframe(on) {
    this.state.wireframe = !!on;
    return this.update();
  }

  /** What is at the canvas' CSS pixel (x, y): {mesh, face, vertex, position, value} or null. */
  pick(x, y) {
    const canvas = this.renderer.domElement;
    this.camera.updateMatrixWorld();
    const ndc = new Vector3((2 * x) / canvas.clientWidth - 1, 1 - (2 * y) / canvas.clientHeight, 0.5);
    const direction = ndc.unproject(this.camera).sub(this.camera.position).normalize().toArray();
    const field = this.state.field === null ? null : this.fields.get(this.state.field);
    let best = null, nearest = Infinity;
    this.surfaces.forEach((surface, i) => {
      const origin = this.camera.position.clone().sub(surface.group.position).toArray();
      const hit = this.visible[i] ? surface.pick(origin, direction, field) : null;
      if (hit && hit.t < nearest) {
        nearest = hit.t;
        best = { mesh: surface.name, face: hit.face, vertex: hit.vertex, position: hit.position, value: hit.value };
      }
    });
    return best;
  }
}

// The extent [lo, hi] of a box {lo, hi} along a unit axis.
function span(box, axis) {
  const a = axis.toArray();
  const middle = a.reduce((sum, c, i) => sum + (c * (box.lo[i] + box.hi[i])) / 2, 0);
  const half = a.reduce((sum, c, i) => sum + (Math.abs(c) * (box.hi[i] - box.lo[i])) / 2, 0);
  return [middle - half, middle + half];
}

function vector(xyz, fallback) {
  const ok = Array.isArray(xyz) && xyz.length === 3 && xyz.every(Number.isFinite) && xyz.some((c) => c !== 0);
  return new Vector3(...(ok ? xyz : fallback));
}

// A scene field with its colour stops flattened ({name, min, max, colormap, stops}).
function fieldInfo(field, colormaps) {
  const stops = colormaps[field.colormap];
  if (!Array.isArray(stops) || stops.length < 2 || !stops.every((s) => Array.isArray(s) && s.length === 3))
    throw new Error(`field "${field.name}": unknown colour map ${JSON.stringify(field.colormap)}`);
  const finite = Number.isFinite(field.min) && Number.isFinite(field.max);
  return { name: field.name, colormap: field.colormap, min: finite ? field.min : 0, max: finite ? field.max : 1,
    stops: Float64Array.from(stops.flat()) };
}
