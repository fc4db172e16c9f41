// The bench's record and replay of the page's buffers (web/js/frame_recorder.js), in node with no browser:
// a made-up viewer whose slot-numbered buffers grow and change in ranges frame by frame, as
// client/mesh_buffers.h's do; replayed from the first recorded frame on, every frame hands over exactly the
// buffers the viewer had then, and the same changed ranges.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { FrameRecorder, FramePlayer } from '../../web/js/frame_recorder.js';

// A deterministic generator, so a failure repeats.
function random(seed) {
  let s = seed >>> 0;
  return (n) => {
    s = (Math.imul(s, 1664525) + 1013904223) >>> 0;
    return s % n;
  };
}

class FakeViewer {
  constructor(next) {
    this.next = next;
    this.positions = new Float32Array(0); this.normals = new Float32Array(0);
    this.colors = new Uint8Array(0); this.indices = new Uint32Array(0);
    this.vertexCount = 0; this.triangleCount = 0;
  }

  grow(name, size) {
    const old = this[name];
    if (old.length >= size) return;
    this[name] = new old.constructor(size);
    this[name].set(old);
  }

  // Some slots added at the end and a few ranges rewritten: the frame's buffers, viewer.buffers() style.
  frame() {
    const changedVertices = [], changedTriangles = [];
    const change = (count, ranges, arrays) => {
      for (let r = this.next(3); r > 0 && count > 0; --r) {
        const first = this.next(count), length = 1 + this.next(Math.min(8, count - first));
        for (const [name, size] of arrays) {
          for (let i = first * size; i < (first + length) * size; ++i) this[name][i] = this.next(1000);
        }
        ranges.push([first, length]);
      }
    };
    const vertices = this.vertexCount + this.next(20), triangles = this.triangleCount + this.next(40);
    for (const [name, size] of [['positions', 3], ['normals', 3], ['colors', 4]]) this.grow(name, vertices * size);
    this.grow('indices', triangles * 3);
    if (vertices > this.vertexCount) changedVertices.push([this.vertexCount, vertices - this.vertexCount]);
    if (triangles > this.triangleCount) changedTriangles.push([this.triangleCount, triangles - this.triangleCount]);
    for (const [name, size, from, to] of [['positions', 3, this.vertexCount, vertices], ['normals', 3, this.vertexCount, vertices],
      ['colors', 4, this.vertexCount, vertices], ['indices', 3, this.triangleCount, triangles]]) {
      for (let i = from * size; i < to * size; ++i) this[name][i] = this.next(1000);
    }
    this.vertexCount = vertices;
    this.triangleCount = triangles;
    change(vertices, changedVertices, [['positions', 3], ['normals', 3], ['colors', 4]]);
    change(triangles, changedTriangles, [['indices', 3]]);
    return {
      positions: this.positions.subarray(0, 3 * vertices), normals: this.normals.subarray(0, 3 * vertices),
      colors: this.colors.subarray(0, 4 * vertices), indices: this.indices.subarray(0, 3 * triangles),
      vertexCount: vertices, triangleCount: triangles, changedVertices, changedTriangles,
    };
  }
}

test('a replay hands over the buffers and changed ranges the viewer had, frame by frame', () => {
  const viewer = new FakeViewer(random(44));
  for (let i = 0; i < 10; ++i) viewer.frame();  // recording starts mid-flight, on a mesh already there
  const recorder = new FrameRecorder();
  const seen = [];
  for (let i = 0; i < 200; ++i) {
    const b = viewer.frame();
    recorder.record(b);
    seen.push({ ...b, positions: b.positions.slice(), normals: b.normals.slice(), colors: b.colors.slice(),
                indices: b.indices.slice() });
  }
  const player = new FramePlayer(recorder.frames);
  seen.forEach((expected, i) => {
    const b = player.next();
    for (const key of ['vertexCount', 'triangleCount', 'positions', 'normals', 'colors', 'indices']) {
      assert.deepEqual(b[key], expected[key], `frame ${i}: ${key}`);
    }
    // The first frame is whole (the replay starts from no mesh); the others carry the viewer's ranges.
    const whole = (count) => (count ? [[0, count]] : []);
    assert.deepEqual(b.changedVertices, i ? expected.changedVertices : whole(expected.vertexCount), `frame ${i}`);
    assert.deepEqual(b.changedTriangles, i ? expected.changedTriangles : whole(expected.triangleCount), `frame ${i}`);
  });
  assert.equal(player.next(), null);
  assert.ok(player.done);
});
