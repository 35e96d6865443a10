// Converts the npm `bunny` module ({positions: [[x,y,z]...], cells: [[i,j,k]...], 0-based}) to OBJ.
// Usage: node fetch_bunny.js PATH/TO/node_modules/bunny OUT.obj
'use strict';
const fs = require('fs');
const path = require('path');
if (process.argv.length !== 4) {
  console.error('usage: node fetch_bunny.js MODULE_DIR OUT.obj');
  process.exit(2);
}
const bunny = require(path.resolve(process.argv[2]));
const { positions, cells } = bunny;
if (!Array.isArray(positions) || !Array.isArray(cells) || positions.length === 0 || cells.length === 0) {
  console.error('fetch_bunny: module has no positions/cells arrays');
  process.exit(1);
}
const lines = [`# Stanford bunny from npm package bunny@1.0.1: ${positions.length} vertices, ${cells.length} faces`];
for (const p of positions) {
  if (p.length !== 3 || !p.every(Number.isFinite)) { console.error('fetch_bunny: bad position', p); process.exit(1); }
  lines.push(`v ${p[0]} ${p[1]} ${p[2]}`);
}
for (const c of cells) {
  if (c.length < 3 || !c.every((i) => Number.isInteger(i) && i >= 0 && i < positions.length)) {
    console.error('fetch_bunny: bad cell', c); process.exit(1);
  }
  lines.push('f ' + c.map((i) => i + 1).join(' '));
}
const tmp = process.argv[3] + '.tmp';
fs.writeFileSync(tmp, lines.join('\n') + '\n');
fs.renameSync(tmp, process.argv[3]);
console.log(`fetch_bunny: wrote ${process.argv[3]} (${positions.length} vertices, ${cells.length} faces)`);
