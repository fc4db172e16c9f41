// Orbit and fly cameras over three's controls (served under vendor/addons/): mouse, touch and keys.
// The camera's state is what the viewer and the URL need: eye, target, up, vertical field of view.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { FlyControls } from 'three/addons/controls/FlyControls.js';

export class CameraControls {
  constructor(camera, element) {
    this.camera = camera;
    this.element = element;
    // The native default view (common/camera.h) until the model's box is known: the viewer refuses a
    // camera whose eye is its target, and fails for good on one.
    camera.position.set(0, 0, 3);
    this.style = 'orbit';
    this.distance = 1;  // the fly camera's target sits this far ahead, so switching back orbits the same point
    this.orbit = null;
    this.orbitUp = [0, 1, 0];
    this.makeOrbit();
    this.fly = null;
    this.speed = 1;
  }

  // OrbitControls takes its axis from camera.up when made: a new up (a z-up model's link) needs a new one.
  makeOrbit() {
    const target = this.orbit?.target.clone();
    this.orbit?.dispose();
    this.orbit = new OrbitControls(this.camera, this.element);
    this.orbit.listenToKeyEvents(window);
    if (target) this.orbit.target.copy(target);
  }

  setStyle(style) {
    if (style === this.style) return;
    this.style = style;
    if (style === 'fly') {
      this.distance = this.camera.position.distanceTo(this.orbit.target);
      this.orbit.enabled = false;
      this.fly = new FlyControls(this.camera, this.element);
      this.fly.dragToLook = true;
      this.fly.rollSpeed = 0.6;
      this.fly.movementSpeed = this.speed;
    } else {
      this.fly?.dispose();
      this.fly = null;
      const ahead = new THREE.Vector3();
      this.camera.getWorldDirection(ahead);
      this.orbit.target.copy(this.camera.position).addScaledVector(ahead, this.distance);
      this.camera.up.set(...this.orbitUp);
      this.orbit.enabled = true;
      this.orbit.update();
    }
  }

  // A view of the whole model: the box's centre, from far enough that the box fits the field of view,
  // up along +y or, for a flat model, its short axis (as `pmstream path` chooses).
  frame(bounds) {
    const min = new THREE.Vector3(...bounds.min), max = new THREE.Vector3(...bounds.max);
    const centre = min.clone().add(max).multiplyScalar(0.5);
    const radius = Math.max(max.distanceTo(min) / 2, 1e-6);
    const distance = radius / Math.sin(THREE.MathUtils.degToRad(this.camera.fov) / 2);
    const size = max.clone().sub(min).toArray();
    const short = size.indexOf(Math.min(...size));
    const upAxis = size[short] < 0.5 * Math.min(...size.filter((_, i) => i !== short)) ? short : 1;
    const [side, front] = [0, 1, 2].filter((i) => i !== upAxis);
    const eye = centre.toArray(), up = [0, 0, 0];
    up[upAxis] = 1;
    eye[upAxis] += 0.45 * distance;
    eye[side] += 0.3 * distance;
    eye[front] += 0.85 * distance;
    this.setSpeed(radius);
    this.set({ eye, target: centre.toArray(), up, fovy: this.camera.fov });
  }

  setSpeed(radius) {
    this.speed = radius * 0.5;
    this.orbit.minDistance = radius * 1e-3;
    this.orbit.maxDistance = radius * 50;
    if (this.fly) this.fly.movementSpeed = this.speed;
  }

  set({ eye, target, up, fovy }) {
    this.camera.position.set(...eye);
    this.camera.up.set(...up);
    if (up.some((v, i) => v !== this.orbitUp[i])) {
      this.orbitUp = [...up];
      this.makeOrbit();
      this.orbit.enabled = !this.fly;
    }
    this.camera.fov = fovy;
    this.camera.updateProjectionMatrix();
    this.orbit.target.set(...target);
    this.distance = this.camera.position.distanceTo(this.orbit.target);
    if (this.fly) this.camera.lookAt(this.orbit.target);
    else this.orbit.update();
  }

  update(seconds) {
    if (this.fly) this.fly.update(seconds);
    else this.orbit.update();
  }

  // eye, target, up and fovy in the viewer's terms (common/camera.h).
  state() {
    const c = this.camera;
    let target = this.orbit.target;
    if (this.fly) {
      const ahead = new THREE.Vector3();
      c.getWorldDirection(ahead);
      target = c.position.clone().addScaledVector(ahead, this.distance);
    }
    // Orbiting keeps the world's up (the link then reopens the same axis); flying rolls the camera itself.
    const up = this.fly ? new THREE.Vector3(0, 1, 0).applyQuaternion(c.quaternion) : c.up.clone();
    return { eye: c.position.toArray(), target: target.toArray(), up: up.toArray(), fovy: c.fov };
  }
}
