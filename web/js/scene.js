// The three.js side of the picture: renderer, a sky, a light, the model's material and the camera's
// depth range. Knows nothing of the viewer or its modes.
import * as THREE from 'three';

// A vertical gradient behind everything: a 1-pixel-wide texture is all a sky needs.
function skyTexture() {
  const canvas = document.createElement('canvas');
  canvas.width = 1;
  canvas.height = 256;
  const g = canvas.getContext('2d');
  const gradient = g.createLinearGradient(0, 0, 0, 256);
  gradient.addColorStop(0, '#3f77b8');
  gradient.addColorStop(0.6, '#9cc3e6');
  gradient.addColorStop(1, '#dfe9f0');
  g.fillStyle = gradient;
  g.fillRect(0, 0, 1, 256);
  const texture = new THREE.CanvasTexture(canvas);
  texture.colorSpace = THREE.SRGBColorSpace;
  return texture;
}

// Two-sided lighting by the normal, as the native renderer's headlight (|cos|): a fragment whose
// interpolated normal faces away from the eye is lit with it turned round, whatever the triangle's winding.
// three's DoubleSide turns it by the winding instead, which draws as dark lines the fold-overs a
// view-dependent mesh may hold: vsplits made in another order than the build's collapses can fold a thin
// triangle over its neighbour (the build checks flips along its own sequence only), wound backwards while
// its vertex normals, averaged over their fans, still face the eye.
const WINDING_FLIP = 'normal *= faceDirection;';
const NORMAL_FLIP = 'normal = faceforward( normal, - vViewPosition, normal );';

function litByNormal(shader) {
  const chunk = THREE.ShaderChunk.normal_fragment_begin;
  if (!chunk.includes(WINDING_FLIP)) console.error('three.js changed normal_fragment_begin: two-sided lighting is by winding');
  shader.fragmentShader = shader.fragmentShader.replace('#include <normal_fragment_begin>', chunk.replace(WINDING_FLIP, NORMAL_FLIP));
}

export function createScene(container) {
  // preserveDrawingBuffer: the tests' screenshots read the canvas after the frame was presented.
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  container.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  scene.background = skyTexture();
  scene.add(new THREE.HemisphereLight(0xdfeeff, 0x4a3f33, 1.4));
  const sun = new THREE.DirectionalLight(0xfff4e0, 2.0);
  sun.position.set(0.4, 1, 0.3);
  scene.add(sun);

  const camera = new THREE.PerspectiveCamera(60, 1, 0.01, 100);
  // Per-vertex colours are the model's, or white where it has none; the material's grey shades white.
  const material = new THREE.MeshStandardMaterial({
    color: 0xd8d8d8, vertexColors: true, roughness: 0.85, metalness: 0, side: THREE.DoubleSide,
  });
  material.onBeforeCompile = litByNormal;

  function resize() {
    const width = container.clientWidth || 1, height = container.clientHeight || 1;
    renderer.setSize(width, height, false);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
  }
  resize();
  window.addEventListener('resize', resize);

  return { renderer, scene, camera, material, sun, resize };
}

// Near and far enclose the model's box seen from the camera, near at least far * 1e-4, as the native
// view does (common/camera.h), so the picture clips where the refinement's frustum does.
export function fitDepthRange(camera, bounds) {
  if (!bounds) return;
  const forward = new THREE.Vector3();
  camera.getWorldDirection(forward);
  let far = 0, near = Infinity;
  for (let i = 0; i < 8; ++i) {
    const corner = new THREE.Vector3(
      (i & 1 ? bounds.max : bounds.min)[0], (i & 2 ? bounds.max : bounds.min)[1], (i & 4 ? bounds.max : bounds.min)[2]);
    const depth = corner.sub(camera.position).dot(forward);
    far = Math.max(far, depth);
    near = Math.min(near, depth);
  }
  far = Math.max(far * 1.01, 1e-6);
  near = Math.max(near * 0.99, far * 1e-4);
  if (camera.near !== near || camera.far !== far) {
    camera.near = near;
    camera.far = far;
    camera.updateProjectionMatrix();
  }
}
