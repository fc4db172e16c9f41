// The receiver mode's face-id pass (cheng-ooi 2008 §4.2: the screen importance of a face is the pixels it
// covers). Every few frames the current triangles are drawn non-indexed into a small off-screen target,
// each triangle in one flat colour = its face slot + 1 as a 24-bit number (R the low byte, B the high byte,
// as client/face_id_importance.h reads it; 0 is the background), and the pixels read back are handed to
// the viewer, which counts them per face.
import * as THREE from 'three';

const EVERY_FRAMES = 4;  // the ranking changes with the view, not every frame
const DOWNSCALE = 4;     // a quarter of the canvas each way: enough pixels to rank faces, little to read back

const vertexShader = `
in vec3 position;
in vec3 faceId;
uniform mat4 modelViewMatrix;
uniform mat4 projectionMatrix;
flat out vec3 vFaceId;
void main() {
  vFaceId = faceId;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;

const fragmentShader = `
precision highp float;
flat in vec3 vFaceId;
out vec4 color;
void main() { color = vec4(vFaceId, 1.0); }`;

export class FaceIdPass {
  constructor(renderer) {
    this.renderer = renderer;
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x000000);
    this.geometry = new THREE.BufferGeometry();
    this.material = new THREE.RawShaderMaterial({
      vertexShader, fragmentShader, glslVersion: THREE.GLSL3, side: THREE.DoubleSide,
    });
    this.mesh = new THREE.Mesh(this.geometry, this.material);
    this.mesh.frustumCulled = false;
    this.scene.add(this.mesh);
    this.target = null;
    this.pixels = null;
    this.capacity = 0;
    this.frames = 0;
  }

  // Draws and reads back when due; returns {rgba, width, height} or null.
  run(camera, positions, indices, triangleCount) {
    if (this.frames++ % EVERY_FRAMES !== 0 || !positions || !indices) return null;
    this.fill(positions, indices, triangleCount);
    const size = this.renderer.getSize(new THREE.Vector2());
    const width = Math.max(1, Math.floor(size.x / DOWNSCALE)), height = Math.max(1, Math.floor(size.y / DOWNSCALE));
    if (!this.target || this.target.width !== width || this.target.height !== height) {
      this.target?.dispose();
      this.target = new THREE.WebGLRenderTarget(width, height, {
        minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, depthBuffer: true,
      });
      this.pixels = new Uint8Array(width * height * 4);
    }
    const previous = this.renderer.getRenderTarget();
    this.renderer.setRenderTarget(this.target);
    this.renderer.render(this.scene, camera);
    this.renderer.readRenderTargetPixels(this.target, 0, 0, width, height, this.pixels);
    this.renderer.setRenderTarget(previous);
    return { rgba: this.pixels, width, height };
  }

  // Triangle t's three corners, each carrying t + 1; a free slot (0, 0, 0) collapses to a point.
  fill(positions, indices, triangleCount) {
    if (triangleCount > this.capacity) this.grow(triangleCount);
    const corners = this.geometry.getAttribute('position');
    const out = corners.array;
    for (let t = 0; t < triangleCount; ++t) {
      for (let k = 0; k < 3; ++k) {
        const v = indices[3 * t + k] * 3, o = 9 * t + 3 * k;
        out[o] = positions[v];
        out[o + 1] = positions[v + 1];
        out[o + 2] = positions[v + 2];
      }
    }
    corners.clearUpdateRanges();
    corners.addUpdateRange(0, triangleCount * 9);
    corners.needsUpdate = true;
    this.geometry.setDrawRange(0, triangleCount * 3);
  }

  grow(triangles) {
    this.capacity = Math.ceil(triangles * 1.5);
    const ids = new Uint8Array(this.capacity * 9);
    for (let t = 0; t < this.capacity; ++t) {
      const id = t + 1;
      for (let k = 0; k < 3; ++k) {
        ids[9 * t + 3 * k] = id & 255;
        ids[9 * t + 3 * k + 1] = (id >> 8) & 255;
        ids[9 * t + 3 * k + 2] = (id >> 16) & 255;
      }
    }
    this.geometry.dispose();
    this.geometry = new THREE.BufferGeometry();
    this.geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(this.capacity * 9), 3)
      .setUsage(THREE.DynamicDrawUsage));
    this.geometry.setAttribute('faceId', new THREE.BufferAttribute(ids, 3, true));
    this.mesh.geometry = this.geometry;
  }

  dispose() {
    this.target?.dispose();
    this.geometry.dispose();
    this.material.dispose();
  }
}
