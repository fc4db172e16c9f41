// What the bench (bench/web/web_bench.mjs) records of a streamed flight and plays back: each frame's
// changed ranges of the viewer's buffers, copied out of WASM memory, and a player that rebuilds the
// buffers from them, so the page can draw the same per-frame meshes with no network and no core work.
const VERTEX_ARRAYS = [['positions', 3], ['normals', 3], ['colors', 4]];
const TRIANGLE_ARRAYS = [['indices', 3]];

// [{first, count, data: [slice per array]}] for the ranges of `ranges` over the arrays `names` of `b`.
function copyRanges(b, ranges, names) {
  return ranges.filter(([, count]) => count > 0).map(([first, count]) => ({
    first, count, data: names.map(([name, size]) => b[name].slice(first * size, (first + count) * size)),
  }));
}

export class FrameRecorder {
  constructor() {
    this.frames = [];
  }

  // b: viewer.buffers(), valid only now. The first frame is kept whole: a replay starts from no mesh.
  record(b) {
    const whole = this.frames.length === 0;
    this.frames.push({
      vertexCount: b.vertexCount, triangleCount: b.triangleCount,
      vertices: copyRanges(b, whole ? [[0, b.vertexCount]] : b.changedVertices, VERTEX_ARRAYS),
      triangles: copyRanges(b, whole ? [[0, b.triangleCount]] : b.changedTriangles, TRIANGLE_ARRAYS),
    });
  }
}

export class FramePlayer {
  constructor(frames) {
    this.frames = frames;
    this.at = 0;
    this.arrays = { positions: new Float32Array(0), normals: new Float32Array(0), colors: new Uint8Array(0),
                    indices: new Uint32Array(0) };
  }

  get done() { return this.at >= this.frames.length; }

  // The next frame's buffers, shaped as viewer.buffers() gives them; null after the last.
  next() {
    if (this.done) return null;
    const f = this.frames[this.at++];
    this.apply(f.vertices, VERTEX_ARRAYS, f.vertexCount);
    this.apply(f.triangles, TRIANGLE_ARRAYS, f.triangleCount);
    const a = this.arrays;
    return {
      positions: a.positions.subarray(0, 3 * f.vertexCount), normals: a.normals.subarray(0, 3 * f.vertexCount),
      colors: a.colors.subarray(0, 4 * f.vertexCount), indices: a.indices.subarray(0, 3 * f.triangleCount),
      vertexCount: f.vertexCount, triangleCount: f.triangleCount,
      changedVertices: f.vertices.map((r) => [r.first, r.count]),
      changedTriangles: f.triangles.map((r) => [r.first, r.count]),
    };
  }

  apply(ranges, names, count) {
    names.forEach(([name, size], k) => {
      if (this.arrays[name].length < count * size) {
        const grown = new this.arrays[name].constructor(Math.ceil(count * size * 1.5));
        grown.set(this.arrays[name]);
        this.arrays[name] = grown;
      }
      for (const r of ranges) this.arrays[name].set(r.data[k], r.first * size);
    });
  }
}
