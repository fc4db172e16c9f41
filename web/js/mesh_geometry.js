// The viewer's mesh as a three.js geometry, updated from the viewer's changed ranges (client/mesh_buffers.h):
// only those ranges are copied out of WASM memory and uploaded (BufferAttribute.addUpdateRange); the
// arrays are reallocated, and then uploaded whole, only when the mesh outgrows them.
import * as THREE from 'three';

const GROWTH = 1.5;  // spare room on reallocation, so a refining mesh reallocates a few times, not every frame

function attribute(ArrayType, itemSize, capacity, normalized = false) {
  const a = new THREE.BufferAttribute(new ArrayType(capacity * itemSize), itemSize, normalized);
  a.setUsage(THREE.DynamicDrawUsage);
  return a;
}

export class MeshGeometry {
  constructor(material) {
    this.mesh = new THREE.Mesh(new THREE.BufferGeometry(), material);
    this.mesh.frustumCulled = false;  // the slots' bounding sphere would need every position read back
    this.vertexCapacity = 0;
    this.triangleCapacity = 0;
    this.vertexCount = 0;
    this.triangleCount = 0;
    this.uploadedVertices = 0;  // the elements copied this frame, for the overlay and the tests
    this.uploadedTriangles = 0;
  }

  // b: viewer.buffers(), valid only until the next call into the viewer: everything is copied here.
  update(b) {
    const grown = b.vertexCount > this.vertexCapacity || b.triangleCount > this.triangleCapacity;
    if (grown) this.reallocate(b.vertexCount, b.triangleCount);
    const g = this.mesh.geometry;
    this.uploadedVertices = grown ? this.copyAllVertices(b) : this.copyVertexRanges(b, b.changedVertices);
    this.uploadedTriangles = grown ? this.copyAllTriangles(b) : this.copyTriangleRanges(b, b.changedTriangles);
    // New attributes go up whole on their first draw: ranges recorded now would be sent again later.
    if (grown) for (const a of [...Object.values(g.attributes), g.getIndex()]) a.clearUpdateRanges();
    this.vertexCount = b.vertexCount;
    this.triangleCount = b.triangleCount;
    g.setDrawRange(0, b.triangleCount * 3);
  }

  reallocate(vertices, triangles) {
    const old = this.mesh.geometry;
    this.vertexCapacity = Math.max(this.vertexCapacity, Math.ceil(vertices * GROWTH), 64);
    this.triangleCapacity = Math.max(this.triangleCapacity, Math.ceil(triangles * GROWTH), 64);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', attribute(Float32Array, 3, this.vertexCapacity));
    g.setAttribute('normal', attribute(Float32Array, 3, this.vertexCapacity));
    g.setAttribute('color', attribute(Uint8Array, 4, this.vertexCapacity, true));
    g.setIndex(attribute(Uint32Array, 1, this.triangleCapacity * 3));
    this.mesh.geometry = g;
    old.dispose();
  }

  copyAllVertices(b) {
    return this.copyVertexRanges(b, b.vertexCount ? [[0, b.vertexCount]] : []);
  }

  copyAllTriangles(b) {
    return this.copyTriangleRanges(b, b.triangleCount ? [[0, b.triangleCount]] : []);
  }

  copyVertexRanges(b, ranges) {
    const g = this.mesh.geometry;
    let copied = 0;
    for (const [name, source, size] of [['position', b.positions, 3], ['normal', b.normals, 3], ['color', b.colors, 4]]) {
      copied = copyRanges(g.getAttribute(name), source, size, ranges);
    }
    return copied;
  }

  copyTriangleRanges(b, ranges) {
    return copyRanges(this.mesh.geometry.getIndex(), b.indices, 3, ranges);
  }

  // The mesh as the page holds it (positions, triangles): what the face-id pass draws.
  positions() { return this.mesh.geometry.getAttribute('position')?.array; }
  indices() { return this.mesh.geometry.getIndex()?.array; }
}

// ranges are in elements (vertices or triangles), `size` array entries each.
function copyRanges(target, source, size, ranges) {
  let copied = 0;
  for (const [first, count] of ranges) {
    if (count === 0) continue;
    const start = first * size, length = count * size;
    target.array.set(source.subarray(start, start + length), start);
    target.addUpdateRange(start, length);
    copied += count;
  }
  if (copied) target.needsUpdate = true;
  return copied;
}
