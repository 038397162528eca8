// The 3D view's cameras, each tab its own: "top" (straight down, framed exactly as the 2D pages frame the
// field: the same metres per pixel and margins), "broadcast" (a side stand that pans with the ball), "follow"
// (behind a chosen robot or drone, along its heading) and "orbit" (free: drag to turn, wheel to zoom, right-drag
// to pan). `project(x, y, z)` says where a world point is on the canvas (CSS pixels) with the current camera.
import * as THREE from "three";
import { OrbitControls } from "three/addons/OrbitControls.js";

export const MODES = ["top", "broadcast", "follow", "orbit"];
const FIELD_PAD = 24;   // [CSS px] round the floor, as the 2D pages leave
const EASE = 4.0;       // [1/s] how fast the moving cameras catch up with what they follow

// What the broadcast camera pans with: in a ball game the ball, else (a pursuit, an encirclement) the middle of
// the robots.
function focus(frame, ballGame) {
  const b = frame && frame.ball;
  if (b && ballGame) return [b.x, b.y];
  const robots = frame ? frame.robots.filter((r) => r.x !== undefined && r.x !== null) : [];
  if (!robots.length) return b ? [b.x, b.y] : [0, 0];
  return [robots.reduce((s, r) => s + r.x, 0) / robots.length, robots.reduce((s, r) => s + r.y, 0) / robots.length];
}

export class Cameras {
  constructor(canvas, field, ballGame = true) {
    this.canvas = canvas;
    this.field = field;
    this.ballGame = ballGame;
    this.mode = "top";
    this.target = null;                    // the robot the follow camera is behind (its name)
    this.top = new THREE.OrthographicCamera(-1, 1, 1, -1, 0.1, 200);
    this.top.position.set(0, 0, 100);
    this.top.up.set(0, 1, 0);
    this.top.lookAt(0, 0, 0);
    this.eye = new THREE.PerspectiveCamera(45, 1, 0.05, 500);
    this.eye.up.set(0, 0, 1);
    this.look = new THREE.Vector3();
    this.controls = new OrbitControls(this.eye, canvas);
    this.controls.enabled = false;
    this.controls.enableDamping = false;
    this.w = 1; this.h = 1;
  }

  get camera() { return this.mode === "top" ? this.top : this.eye; }

  resize(w, h) {
    const f = this.field;
    this.w = w; this.h = h;
    // the 2D pages' scale: the floor and its margin fill the canvas less a border of FIELD_PAD pixels
    this.scale = Math.max(1e-6, Math.min((w - 2 * FIELD_PAD) / (f.length + 2 * f.margin), (h - 2 * FIELD_PAD) / (f.width + 2 * f.margin)));
    const hw = w / 2 / this.scale, hh = h / 2 / this.scale;
    Object.assign(this.top, { left: -hw, right: hw, top: hh, bottom: -hh });
    this.top.updateProjectionMatrix();
    this.eye.aspect = w / Math.max(1, h);
    this.eye.updateProjectionMatrix();
  }

  setMode(mode, frame) {
    if (!MODES.includes(mode)) return;
    if (mode === "orbit" && this.mode !== "orbit") {
      if (this.mode === "top") this.stand(frame, true);   // start from an overview, not from straight down
      this.controls.target.copy(this.look);
    }
    this.mode = mode;
    this.controls.enabled = mode === "orbit";
    this.snap = true;   // the moving cameras jump to their place once, then ease
  }

  // The broadcast camera's place: on a stand beside the field (the -y side), high enough to see over the boards
  // and the obstacles, panning with the ball (a game without one: with the robots' middle).
  stand(frame, jump = false) {
    const f = this.field, W = f.width / 2 + f.margin;
    const [fx, fy] = focus(frame, this.ballGame);
    const span = Math.max(f.length, f.width);
    const place = new THREE.Vector3(0.7 * fx, -(W + 0.25 * span), Math.max(0.3 * span, (f.ceiling || 0) + 1.5));
    const look = new THREE.Vector3(0.9 * fx, 0.4 * fy, 0);
    this.move(place, look, jump);
  }

  // The follow camera's place: behind the robot along its heading, above it, looking a little ahead of it.
  behind(frame, jump = false) {
    const r = frame && frame.robots.find((x) => x.name === this.target && x.x !== undefined && x.x !== null);
    if (!r) { this.stand(frame, jump); return; }
    const z = r.z || 0, c = Math.cos(r.yaw), s = Math.sin(r.yaw);
    const back = z > 0.3 ? 1.6 : 2.6, up = z > 0.3 ? 0.7 : 1.5;
    this.move(new THREE.Vector3(r.x - back * c, r.y - back * s, z + up), new THREE.Vector3(r.x + 2 * c, r.y + 2 * s, z * 0.8), jump);
  }

  move(place, look, jump) {
    const k = jump || this.snap ? 1 : Math.min(1, EASE * this.dt);
    this.eye.position.lerp(place, k);
    this.look.lerp(look, k);
    this.eye.lookAt(this.look);
    this.snap = false;
  }

  // Called every drawn frame with the newest picture and the wall time since the last call.
  update(frame, dt) {
    this.dt = dt;
    if (this.mode === "broadcast") this.stand(frame);
    else if (this.mode === "follow") this.behind(frame);
    else if (this.mode === "orbit") this.controls.update();
    this.camera.updateMatrixWorld();
  }

  project(x, y, z = 0) {
    const v = new THREE.Vector3(x, y, z).project(this.camera);
    return [(v.x + 1) / 2 * this.w, (1 - v.y) / 2 * this.h];
  }
}
