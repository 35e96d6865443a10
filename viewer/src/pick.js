// Ray casts against millions of triangles without freezing the page. The triangles are ordered
// along a Morton curve of their centroids (a radix sort, no per-triangle objects) and cut into runs
// of LEAF neighbours; a ray tests the runs' boxes (tens of thousands, a millisecond) and then only
// the triangles of the boxes it crosses.

const LEAF = 32;

export class TrianglePicker {
  /** `positions`: 3 floats per vertex; `index`: 3 vertex ids per triangle. */
  constructor(positions, index) {
    this.positions = positions;
    this.index = index;
    const { lo, hi } = bounds(positions);
    this.order = mortonOrder(positions, index, lo, hi);
    // Boxes a little larger than their triangles: a flat run of a staircase (a box of no thickness)
    // is not missed through rounding in the slab test.
    const pad = 1e-5 * Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    this.boxes = leafBoxes(positions, index, this.order, pad);
  }

  /** The nearest triangle crossed by the ray origin + t direction, t > 0: {t, triangle} or null. */
  intersect(origin, direction) {
    const [ox, oy, oz] = origin, [dx, dy, dz] = direction;
    const inverse = [1 / dx, 1 / dy, 1 / dz];
    const { boxes, order, index, positions: p } = this;
    let best = Infinity, hit = -1;
    for (let leaf = 0, b = 0; b < boxes.length; ++leaf, b += 6) {
      // Slab test of the box, clipped to the nearest hit so far.
      let near = 0, far = best;
      for (let a = 0; a < 3; ++a) {
        const t0 = (boxes[b + a] - origin[a]) * inverse[a], t1 = (boxes[b + 3 + a] - origin[a]) * inverse[a];
        if (t0 < t1) {
          if (t0 > near) near = t0;
          if (t1 < far) far = t1;
        } else {
          if (t1 > near) near = t1;
          if (t0 < far) far = t0;
        }
      }
      if (near > far) continue;
      const end = Math.min(order.length, (leaf + 1) * LEAF);
      for (let k = leaf * LEAF; k < end; ++k) {
        const tri = order[k];
        const t = rayTriangle(p, 3 * index[3 * tri], 3 * index[3 * tri + 1], 3 * index[3 * tri + 2],
          ox, oy, oz, dx, dy, dz);
        if (t < best) { best = t; hit = tri; }
      }
    }
    return hit < 0 ? null : { t: best, triangle: hit };
  }
}

// Möller-Trumbore, both sides: the ray parameter of the hit, or Infinity.
function rayTriangle(p, a, b, c, ox, oy, oz, dx, dy, dz) {
  const e1x = p[b] - p[a], e1y = p[b + 1] - p[a + 1], e1z = p[b + 2] - p[a + 2];
  const e2x = p[c] - p[a], e2y = p[c + 1] - p[a + 1], e2z = p[c + 2] - p[a + 2];
  const px = dy * e2z - dz * e2y, py = dz * e2x - dx * e2z, pz = dx * e2y - dy * e2x;
  const det = e1x * px + e1y * py + e1z * pz;
  if (det === 0) return Infinity;
  const inv = 1 / det;
  const sx = ox - p[a], sy = oy - p[a + 1], sz = oz - p[a + 2];
  const u = (sx * px + sy * py + sz * pz) * inv;
  if (u < 0 || u > 1) return Infinity;
  const qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
  const v = (dx * qx + dy * qy + dz * qz) * inv;
  if (v < 0 || u + v > 1) return Infinity;
  const t = (e2x * qx + e2y * qy + e2z * qz) * inv;
  return t > 0 ? t : Infinity;
}

/** The bounding box {lo, hi} of 3-float points. */
export function bounds(p) {
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < p.length; i += 3)
    for (let a = 0; a < 3; ++a) {
      if (p[i + a] < lo[a]) lo[a] = p[i + a];
      if (p[i + a] > hi[a]) hi[a] = p[i + a];
    }
  return { lo, hi };
}

// The triangles sorted by the 30-bit Morton code of their centroid in the bounding box.
function mortonOrder(p, index, lo, hi) {
  const n = index.length / 3;
  const scale = lo.map((l, a) => 1023 / 3 / Math.max(hi[a] - l, 1e-30));  // the centroid's sum / 3
  const keys = new Uint32Array(n);
  for (let t = 0; t < n; ++t) {
    let code = 0;
    for (let a = 0; a < 3; ++a) {
      const sum = p[3 * index[3 * t] + a] + p[3 * index[3 * t + 1] + a] + p[3 * index[3 * t + 2] + a];
      code |= spreadBits(Math.min(1023, Math.max(0, Math.floor((sum - 3 * lo[a]) * scale[a])))) << a;
    }
    keys[t] = code;
  }
  return radixOrder(keys);
}

// The 10 low bits of x spread to every third bit.
function spreadBits(x) {
  x = (x | (x << 16)) & 0x030000ff;
  x = (x | (x << 8)) & 0x0300f00f;
  x = (x | (x << 4)) & 0x030c30c3;
  return (x | (x << 2)) & 0x09249249;
}

// Indices sorting `keys` (< 2^32): two stable counting passes over 16 bits.
function radixOrder(keys) {
  const n = keys.length;
  let order = new Uint32Array(n), next = new Uint32Array(n);
  for (let i = 0; i < n; ++i) order[i] = i;
  for (const shift of [0, 16]) {
    const start = new Uint32Array(65537);
    for (let i = 0; i < n; ++i) ++start[((keys[i] >>> shift) & 0xffff) + 1];
    for (let d = 1; d <= 65536; ++d) start[d] += start[d - 1];
    for (let i = 0; i < n; ++i) {
      const t = order[i];
      next[start[(keys[t] >>> shift) & 0xffff]++] = t;
    }
    [order, next] = [next, order];
  }
  return order;
}

// Bounding boxes (min xyz, max xyz) of the runs of LEAF triangles in `order`, `pad` larger.
function leafBoxes(p, index, order, pad) {
  const boxes = new Float64Array(6 * Math.ceil(order.length / LEAF));
  for (let leaf = 0, b = 0; b < boxes.length; ++leaf, b += 6) {
    let x0 = Infinity, y0 = Infinity, z0 = Infinity, x1 = -Infinity, y1 = -Infinity, z1 = -Infinity;
    const end = Math.min(order.length, (leaf + 1) * LEAF);
    for (let k = leaf * LEAF; k < end; ++k)
      for (let c = 3 * order[k], last = c + 3; c < last; ++c) {
        const v = 3 * index[c], x = p[v], y = p[v + 1], z = p[v + 2];
        if (x < x0) x0 = x;
        if (x > x1) x1 = x;
        if (y < y0) y0 = y;
        if (y > y1) y1 = y;
        if (z < z0) z0 = z;
        if (z > z1) z1 = z;
      }
    boxes.set([x0 - pad, y0 - pad, z0 - pad, x1 + pad, y1 + pad, z1 + pad], b);
  }
  return boxes;
}
