// Meshes compared as sets, whatever their numbering: the native viewer's (a binary PLY from
// `pmstream stream --save-mesh`) and the page's (window.pmstream.mesh()). A vertex is its position's
// bits; a face is its three corners' positions, rotated to start at the least and so kept oriented.
import { readFileSync } from 'node:fs';

const SIZES = { char: 1, uchar: 1, int8: 1, uint8: 1, short: 2, ushort: 2, int16: 2, uint16: 2,
                int: 4, uint: 4, int32: 4, uint32: 4, float: 4, float32: 4, double: 8, float64: 8 };

export function readPly(file) {
  const bytes = readFileSync(file);
  const end = bytes.indexOf('end_header\n');
  const header = bytes.subarray(0, end).toString('latin1').split('\n');
  if (!header.includes('format binary_little_endian 1.0')) throw new Error(`${file}: not a binary little-endian PLY`);
  const elements = [];
  for (const line of header) {
    const w = line.trim().split(/\s+/);
    if (w[0] === 'element') elements.push({ name: w[1], count: Number(w[2]), properties: [] });
    if (w[0] === 'property') elements.at(-1).properties.push(w[1] === 'list' ? { list: true, count: w[2], type: w[3], name: w[4] } : { type: w[1], name: w[2] });
  }
  const view = new DataView(bytes.buffer, bytes.byteOffset + end + 'end_header\n'.length);
  let at = 0;
  const read = (type) => {
    const v = type.startsWith('float') ? (SIZES[type] === 4 ? view.getFloat32(at, true) : view.getFloat64(at, true))
      : SIZES[type] === 1 ? view.getUint8(at) : SIZES[type] === 2 ? view.getUint16(at, true) : view.getUint32(at, true);
    at += SIZES[type];
    return v;
  };
  const positions = [], faces = [];
  for (const e of elements) {
    for (let i = 0; i < e.count; ++i) {
      for (const p of e.properties) {
        if (p.list) {
          const n = read(p.count);
          for (let k = 0; k < n; ++k) faces.push(read(p.type));
        } else {
          const v = read(p.type);
          if (e.name === 'vertex' && 'xyz'.includes(p.name)) positions.push(v);
        }
      }
    }
  }
  return { positions: Float32Array.from(positions), faces: Uint32Array.from(faces) };
}

function vertexKey(positions, v) {
  return `${positions[3 * v]},${positions[3 * v + 1]},${positions[3 * v + 2]}`;
}

// The faces as sets of oriented position triples; the vertices any face uses.
export function meshSets({ positions, faces }) {
  const p = Float32Array.from(positions);
  const faceSet = new Set(), vertexSet = new Set();
  for (let f = 0; f + 2 < faces.length; f += 3) {
    const corners = [0, 1, 2].map((k) => vertexKey(p, faces[f + k]));
    if (corners[0] === corners[1] || corners[1] === corners[2] || corners[0] === corners[2]) continue;
    const least = corners.indexOf([...corners].sort()[0]);
    faceSet.add([0, 1, 2].map((k) => corners[(least + k) % 3]).join(' '));
    corners.forEach((c) => vertexSet.add(c));
  }
  return { faces: faceSet, vertices: vertexSet };
}

// Empty when equal; else what differs, a few examples each way.
export function compareMeshes(a, b) {
  const sa = meshSets(a), sb = meshSets(b);
  const only = (x, y) => [...x].filter((k) => !y.has(k));
  const faces = [only(sa.faces, sb.faces), only(sb.faces, sa.faces)];
  if (!faces[0].length && !faces[1].length) return '';
  return `faces ${sa.faces.size} vs ${sb.faces.size}; only in the first ${faces[0].length} (${faces[0].slice(0, 2).join(' | ')}), ` +
    `only in the second ${faces[1].length} (${faces[1].slice(0, 2).join(' | ')})`;
}
