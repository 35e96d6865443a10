// One mesh of the page in three.js. Its polygons are fanned into triangles of an indexed geometry
// sharing the vertices; what costs more memory is built only when first asked for: a non-indexed
// copy for face fields (one colour per face), vertex normals for smooth shading, the polygon edges
// for the wireframe, the picking structure.
import { BufferAttribute, BufferGeometry, Group, LineSegments, Mesh } from 'three';
import { readArray } from './data.js';
import { TrianglePicker, bounds } from './pick.js';

const GREY = Math.round(0.78 * 255);  // a surface without field, as in the PNG pictures

export class Surface {
  constructor(desc, buffer, material, lineMaterial) {
    this.name = String(desc.name);
    const what = `mesh "${this.name}"`;
    const nv = (this.vertexCount = desc.vertices), nf = (this.faceCount = desc.faces);
    if (!(nv >= 0 && nf >= 0)) throw new Error(`${what}: bad vertex or face count`);  // exact: readArray
    this.positions = readArray(buffer, desc.positions, 'float32', 3 * nv, `${what}: positions`);
    this.faceSize = desc.face_size || 0;
    if (this.faceSize !== 0 && !(this.faceSize >= 3 && this.faceSize <= 255))
      throw new Error(`${what}: face_size ${this.faceSize}`);
    this.faceSizes = this.faceSize ? null : readArray(buffer, desc.face_sizes, 'uint8', nf, `${what}: face_sizes`);
    const starts = this.faceSizes ? faceStarts(this.faceSizes, what) : null;
    this.corners = readArray(buffer, desc.corners, 'uint32', starts ? starts[nf] : nf * this.faceSize,
      `${what}: corners`);
    this.starts = starts;
    for (let i = 0; i < this.corners.length; ++i)
      if (this.corners[i] >= nv) throw new Error(`${what}: a face refers to vertex ${this.corners[i]} of ${nv}`);
    this.vertexFields = readFields(buffer, desc.vertex_fields, nv, `${what}: vertex field`);
    this.faceFields = readFields(buffer, desc.face_fields, nf, `${what}: face field`);
    this.bounds = bounds(this.positions);
    ({ index: this.index, triangleFace: this.triangleFace } = this.fan());

    this.geometry = new BufferGeometry();
    this.geometry.setAttribute('position', new BufferAttribute(this.positions, 3));
    this.colours = new Uint8Array(3 * nv).fill(GREY);
    this.geometry.setAttribute('color', new BufferAttribute(this.colours, 3, true));
    this.geometry.setIndex(new BufferAttribute(this.index, 1));
    this.group = new Group();
    this.mesh = this.addToGroup(new Mesh(this.geometry, material));
    this.lineMaterial = lineMaterial;
    this.shownField = null;
  }

  // Culling would make three.js compute bounding spheres with a loop over Vector3s: not needed.
  addToGroup(object) {
    object.frustumCulled = false;
    this.group.add(object);
    return object;
  }

  /** The first corner of face f in `corners`. */
  faceStart(f) {
    return this.starts ? this.starts[f] : f * this.faceSize;
  }

  // Triangles fanned from each face's first corner, and the face of each triangle.
  fan() {
    const { corners, faceCount } = this;
    const triangles = corners.length - 2 * faceCount;
    const index = new Uint32Array(3 * triangles), triangleFace = new Uint32Array(triangles);
    for (let f = 0, t = 0; f < faceCount; ++f) {
      const first = this.faceStart(f), end = this.faceStart(f + 1);
      for (let c = first + 1; c + 1 < end; ++c, ++t) {
        index[3 * t] = corners[first];
        index[3 * t + 1] = corners[c];
        index[3 * t + 2] = corners[c + 1];
        triangleFace[t] = f;
      }
    }
    return { index, triangleFace };
  }

  /**
   * Shows the surface coloured by `field` ({name, min, max, stops}; grey when null or not a field of
   * this mesh), with vertex normals when `smooth`, its polygon edges when `wireframe`.
   */
  show(field, smooth, wireframe) {
    const kind = !field ? null : this.vertexFields.has(field.name) ? 'vertex' : this.faceFields.has(field.name) ? 'face' : null;
    const key = kind ? field.name : null;
    if (key !== this.shownField) {
      if (kind === 'face') this.paintFaces(field);
      else if (kind === 'vertex') paint(this.vertexFields.get(field.name), field, this.colours);
      else this.colours.fill(GREY);
      if (kind !== 'face') this.geometry.getAttribute('color').needsUpdate = true;
      this.shownField = key;
    }
    this.mesh.visible = kind !== 'face';
    if (this.faceMesh) this.faceMesh.visible = kind === 'face';
    if (smooth) this.ensureNormals();
    if (wireframe && !this.lines) this.buildLines();
    if (this.lines) this.lines.visible = wireframe;
  }

  // Face colours on the non-indexed copy: every triangle corner gets its face's colour.
  paintFaces(field) {
    if (!this.faceMesh) {
      const geometry = new BufferGeometry();
      geometry.setAttribute('position', new BufferAttribute(gather(this.positions, this.index, 3), 3));
      geometry.setAttribute('color', new BufferAttribute(new Uint8Array(3 * this.index.length), 3, true));
      if (this.normals) geometry.setAttribute('normal', new BufferAttribute(gather(this.normals, this.index, 3), 3));
      this.faceMesh = this.addToGroup(new Mesh(geometry, this.mesh.material));
    }
    const faceColours = paint(this.faceFields.get(field.name), field, new Uint8Array(3 * this.faceCount));
    const attribute = this.faceMesh.geometry.getAttribute('color'), out = attribute.array;
    const { triangleFace } = this;
    for (let t = 0, o = 0; t < triangleFace.length; ++t) {
      const c = 3 * triangleFace[t];
      for (let corner = 0; corner < 3; ++corner, o += 3) {
        out[o] = faceColours[c];
        out[o + 1] = faceColours[c + 1];
        out[o + 2] = faceColours[c + 2];
      }
    }
    attribute.needsUpdate = true;
  }

  ensureNormals() {
    if (!this.normals) {
      this.normals = vertexNormals(this.positions, this.index);
      this.geometry.setAttribute('normal', new BufferAttribute(this.normals, 3));
    }
    const faceGeometry = this.faceMesh && this.faceMesh.geometry;
    if (faceGeometry && !faceGeometry.getAttribute('normal'))
      faceGeometry.setAttribute('normal', new BufferAttribute(gather(this.normals, this.index, 3), 3));
  }

  // The polygon edges (not the fans' diagonals), on the vertex buffer of the surface. An edge
  // between two faces is drawn twice: finding the pairs would cost more than drawing them.
  buildLines() {
    const { corners, faceCount } = this;
    const index = new Uint32Array(2 * corners.length);
    for (let f = 0, o = 0; f < faceCount; ++f) {
      const first = this.faceStart(f), end = this.faceStart(f + 1);
      for (let c = first; c < end; ++c, o += 2) {
        index[o] = corners[c];
        index[o + 1] = corners[c + 1 < end ? c + 1 : first];
      }
    }
    const geometry = new BufferGeometry();
    geometry.setAttribute('position', this.geometry.getAttribute('position'));
    geometry.setIndex(new BufferAttribute(index, 1));
    this.lines = this.addToGroup(new LineSegments(geometry, this.lineMaterial));
  }

  preparePicking() {
    if (!this.picker) this.picker = new TrianglePicker(this.positions, this.index);
  }

  /**
   * The distance from `center` along `toward` (unit, with `right` and `up` a camera's frame) at
   * which every vertex is within tanH, tanV of the view axis.
   */
  viewDistance(center, right, up, toward, tanH, tanV) {
    const p = this.positions;
    let distance = 0;
    for (let i = 0; i < p.length; i += 3) {
      const x = p[i] - center.x, y = p[i + 1] - center.y, z = p[i + 2] - center.z;
      const depth = x * toward.x + y * toward.y + z * toward.z;
      const h = Math.abs(x * right.x + y * right.y + z * right.z) / tanH;
      const v = Math.abs(x * up.x + y * up.y + z * up.z) / tanV;
      distance = Math.max(distance, depth + (h > v ? h : v));
    }
    return distance;
  }

  /**
   * The face crossed first by the ray (in mesh coordinates) and what the page says of it:
   * {t, face, vertex (the face's corner nearest to the hit), position, value (of `field`, or null)}.
   */
  pick(origin, direction, field) {
    this.preparePicking();
    const hit = this.picker.intersect(origin, direction);
    if (!hit) return null;
    const position = [0, 1, 2].map((a) => origin[a] + hit.t * direction[a]);
    const face = this.triangleFace[hit.triangle];
    let vertex = -1, nearest = Infinity;
    for (let c = this.faceStart(face); c < this.faceStart(face + 1); ++c) {
      const v = this.corners[c], p = this.positions;
      const d = (p[3 * v] - position[0]) ** 2 + (p[3 * v + 1] - position[1]) ** 2 + (p[3 * v + 2] - position[2]) ** 2;
      if (d < nearest) { nearest = d; vertex = v; }
    }
    let value = null;
    if (field && this.vertexFields.has(field.name)) value = this.vertexFields.get(field.name)[vertex];
    else if (field && this.faceFields.has(field.name)) value = this.faceFields.get(field.name)[face];
    if (Number.isNaN(value)) value = null;  // undefined there
    return { t: hit.t, face, vertex, position, value };
  }
}

// Prefix sums of the face sizes: where each face starts in `corners`, and the corner count last.
function faceStarts(sizes, what) {
  const starts = new Uint32Array(sizes.length + 1);
  for (let f = 0; f < sizes.length; ++f) {
    if (sizes[f] < 3) throw new Error(`${what}: face ${f} has ${sizes[f]} corners`);
    starts[f + 1] = starts[f] + sizes[f];
  }
  return starts;
}

function readFields(buffer, descs, count, what) {
  const fields = new Map();
  for (const [name, desc] of Object.entries(descs || {}))
    fields.set(name, readArray(buffer, desc, 'float32', count, `${what} "${name}"`));
  return fields;
}

/**
 * `values` coloured into `out` (3 bytes each) by the field's colour map: stops evenly spaced in t,
 * interpolated linearly in RGB, t = (value - min) / (max - min) clamped to [0, 1], NaN mid grey.
 */
export function paint(values, field, out) {
  const { min, stops } = field;
  const last = stops.length / 3 - 1, scale = field.max > min ? 1 / (field.max - min) : 0;
  for (let i = 0, o = 0; i < values.length; ++i, o += 3) {
    const value = values[i];
    if (Number.isNaN(value)) {
      out[o] = out[o + 1] = out[o + 2] = 128;
      continue;
    }
    const x = Math.min(1, Math.max(0, (value - min) * scale)) * last;
    const s = Math.min(Math.floor(x), last - 1), f = x - s;
    for (let c = 0; c < 3; ++c)
      out[o + c] = Math.round(255 * ((1 - f) * stops[3 * s + c] + f * stops[3 * s + 3 + c]));
  }
  return out;
}

// The items (of `size` elements) of `source` at each index: the vertex data of a non-indexed copy.
function gather(source, index, size) {
  const out = new source.constructor(index.length * size);
  for (let i = 0, o = 0; i < index.length; ++i)
    for (let k = 0, s = size * index[i]; k < size; ++k) out[o++] = source[s + k];
  return out;
}

// Normals weighted by the triangles' areas (so a polygon's fan counts as the polygon).
function vertexNormals(p, index) {
  const normals = new Float32Array(p.length);
  for (let i = 0; i < index.length; i += 3) {
    const a = 3 * index[i], b = 3 * index[i + 1], c = 3 * index[i + 2];
    const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
    const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
    const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    normals[a] += nx; normals[a + 1] += ny; normals[a + 2] += nz;
    normals[b] += nx; normals[b + 1] += ny; normals[b + 2] += nz;
    normals[c] += nx; normals[c + 1] += ny; normals[c + 2] += nz;
  }
  for (let v = 0; v < normals.length; v += 3) {
    const length = Math.hypot(normals[v], normals[v + 1], normals[v + 2]) || 1;
    normals[v] /= length;
    normals[v + 1] /= length;
    normals[v + 2] /= length;
  }
  return normals;
}
