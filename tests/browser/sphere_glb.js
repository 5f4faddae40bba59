// A unit icosphere as a mesh, and a minimal glTF 2.0 binary (GLB) writer for it: POSITION, optionally
// NORMAL (the exact sphere normal at each vertex), uint32 indices, one grey PBR material. Used to
// calibrate render_glb.js (the same sphere with and without vertex normals) and as the input given to
// `normalflow compress` / `convert` (as an .obj) so that every figure compares the same geometry.
'use strict';
const fs = require('fs');

function icosphere(level) {
  const t = (1 + Math.sqrt(5)) / 2;
  let v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
           [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]];
  let f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
           [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11],
           [6, 2, 10], [8, 6, 7], [9, 8, 1]];
  const unit = (p) => { const l = Math.hypot(p[0], p[1], p[2]); return [p[0] / l, p[1] / l, p[2] / l]; };
  v = v.map(unit);
  for (let s = 0; s < level; s++) {
    const mid = new Map();
    const m = (a, b) => {
      const key = a < b ? a + ',' + b : b + ',' + a;
      if (!mid.has(key)) {
        mid.set(key, v.length);
        v.push(unit([(v[a][0] + v[b][0]) / 2, (v[a][1] + v[b][1]) / 2, (v[a][2] + v[b][2]) / 2]));
      }
      return mid.get(key);
    };
    const g = [];
    for (const [a, b, c] of f) {
      const ab = m(a, b), bc = m(b, c), ca = m(c, a);
      g.push([a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]);
    }
    f = g;
  }
  return { vertices: v, triangles: f };
}

// With normals: `vn` lines (the unit sphere's normal is the position) and `f a//a` corners.
function writeObj(file, mesh, { normals } = { normals: false }) {
  const lines = mesh.vertices.map((p) => `v ${p[0]} ${p[1]} ${p[2]}`);
  if (normals) for (const p of mesh.vertices) lines.push(`vn ${p[0]} ${p[1]} ${p[2]}`);
  const corner = (i) => (normals ? `${i + 1}//${i + 1}` : `${i + 1}`);
  for (const [a, b, c] of mesh.triangles) lines.push(`f ${corner(a)} ${corner(b)} ${corner(c)}`);
  fs.writeFileSync(file, lines.join('\n') + '\n');
}

function writeGlb(file, mesh, { normals }) {
  const n = mesh.vertices.length;
  const pos = new Float32Array(n * 3);
  mesh.vertices.forEach((p, i) => pos.set(p, 3 * i));
  const nor = normals ? new Float32Array(pos) : null;  // unit sphere: the normal is the position
  const idx = new Uint32Array(mesh.triangles.flat());
  const parts = [Buffer.from(pos.buffer)];
  if (nor) parts.push(Buffer.from(nor.buffer));
  parts.push(Buffer.from(idx.buffer));
  const bin = Buffer.concat(parts);  // every part is a multiple of 4 bytes
  const min = [0, 1, 2].map((k) => Math.min(...mesh.vertices.map((p) => p[k])));
  const max = [0, 1, 2].map((k) => Math.max(...mesh.vertices.map((p) => p[k])));
  const bufferViews = [{ buffer: 0, byteOffset: 0, byteLength: pos.byteLength, target: 34962 }];
  const accessors = [{ bufferView: 0, componentType: 5126, count: n, type: 'VEC3', min, max }];
  const attributes = { POSITION: 0 };
  let offset = pos.byteLength;
  if (nor) {
    bufferViews.push({ buffer: 0, byteOffset: offset, byteLength: nor.byteLength, target: 34962 });
    accessors.push({ bufferView: 1, componentType: 5126, count: n, type: 'VEC3' });
    attributes.NORMAL = 1;
    offset += nor.byteLength;
  }
  bufferViews.push({ buffer: 0, byteOffset: offset, byteLength: idx.byteLength, target: 34963 });
  accessors.push({ bufferView: bufferViews.length - 1, componentType: 5125, count: idx.length, type: 'SCALAR' });
  const gltf = {
    asset: { version: '2.0', generator: 'normalflow tests/browser/sphere_glb.js' },
    scene: 0, scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }],
    meshes: [{ primitives: [{ attributes, indices: accessors.length - 1, material: 0, mode: 4 }] }],
    materials: [{ pbrMetallicRoughness: { baseColorFactor: [0.7, 0.7, 0.7, 1], metallicFactor: 0, roughnessFactor: 0.6 } }],
    buffers: [{ byteLength: bin.length }], bufferViews, accessors,
  };
  let json = Buffer.from(JSON.stringify(gltf));
  json = Buffer.concat([json, Buffer.alloc((4 - (json.length % 4)) % 4, 0x20)]);
  const header = Buffer.alloc(12), jh = Buffer.alloc(8), bh = Buffer.alloc(8);
  header.writeUInt32LE(0x46546c67, 0); header.writeUInt32LE(2, 4);
  header.writeUInt32LE(12 + 8 + json.length + 8 + bin.length, 8);
  jh.writeUInt32LE(json.length, 0); jh.writeUInt32LE(0x4e4f534a, 4);
  bh.writeUInt32LE(bin.length, 0); bh.writeUInt32LE(0x004e4942, 4);
  fs.writeFileSync(file, Buffer.concat([header, jh, json, bh, bin]));
}

module.exports = { icosphere, writeObj, writeGlb };
