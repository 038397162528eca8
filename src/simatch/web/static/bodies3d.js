// The 3D view's moving bodies: each robot as its body (hello.robots[].body, the description the recordings'
// 3D scene uses too: simatch/robots/looks.py), drones with their rotors at their height over a shadow and a
// pole to the floor, the ball at its height with its trail. `Bodies.update(frame)` poses them all.
import * as THREE from "three";
import { teamColor } from "/static/simatch.js";
import { upright } from "/static/world3d.js";

const TRAIL = 1.5;        // [s] of the ball's path drawn behind it
const TRAIL_POINTS = 240;

// A number (or any short text) that always faces the camera, `size` metres tall.
export function label(text, size = 0.32, color = "#ffffff") {
  const canvas = document.createElement("canvas");
  canvas.width = 128; canvas.height = 64;
  const c = canvas.getContext("2d");
  c.font = "bold 48px system-ui, sans-serif";
  c.textAlign = "center"; c.textBaseline = "middle";
  c.lineWidth = 8; c.strokeStyle = "rgba(0,0,0,0.7)"; c.strokeText(text, 64, 34);
  c.fillStyle = color; c.fillText(text, 64, 34);
  const texture = new THREE.CanvasTexture(canvas);
  texture.colorSpace = THREE.SRGBColorSpace;
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: texture, depthTest: false, transparent: true }));
  sprite.scale.set(size * 2, size, 1);
  sprite.renderOrder = 10;
  return sprite;
}

// A ground robot: an upright cylinder with the dribbler's mouth cut flat into its front (+x), a dark stripe on
// its top from the centre to the mouth (its heading), its number above it.
function groundRobot(body, color, goalkeeper) {
  const r = body.radius, h = body.height, cut = Math.max(0.0, Math.min(body.mouth, 0.9 * r));
  const phi = Math.acos((r - cut) / r);
  const shape = new THREE.Shape();
  shape.absarc(0, 0, r, phi, 2 * Math.PI - phi, false);
  shape.closePath();  // the chord at x = r - cut: the mouth
  const geometry = new THREE.ExtrudeGeometry(shape, { depth: h, bevelEnabled: false, curveSegments: 40 });
  const material = new THREE.MeshLambertMaterial({ color });
  const group = new THREE.Group();
  group.add(new THREE.Mesh(geometry, material));
  const stripe = new THREE.Mesh(new THREE.BoxGeometry(r - cut, 0.05, 0.01), new THREE.MeshBasicMaterial({ color: 0x0b0f12 }));
  stripe.position.set((r - cut) / 2, 0, h + 0.006);
  group.add(stripe);
  if (goalkeeper) {
    const ring = new THREE.Mesh(new THREE.RingGeometry(r * 0.55, r * 0.68, 32), new THREE.MeshBasicMaterial({ color: 0xffffff }));
    ring.position.z = h + 0.004;
    group.add(ring);
  }
  return { group, material, top: h };
}

// A drone, drawn body.scale times its size (every viewer draws drones so: looks.py): a small frame, four arms
// on an X, a rotor disc at each arm's end, a white nose mark along its heading.
function drone(body, color) {
  const s = body.scale || 1, group = new THREE.Group();
  const material = new THREE.MeshLambertMaterial({ color });
  const dark = new THREE.MeshLambertMaterial({ color: 0x20252b });
  const hub = body.rotors.length ? Math.hypot(...body.rotors[0]) * s * 0.45 : body.radius * s * 0.3;
  const frame = new THREE.Mesh(new THREE.BoxGeometry(hub, hub, Math.max(0.02, body.height * s)), dark);
  group.add(frame);
  for (const [x, y] of body.rotors) {
    const len = Math.hypot(x, y) * s;
    const arm = new THREE.Mesh(new THREE.BoxGeometry(len, 0.012 * s, 0.01 * s), dark);
    arm.position.set(x * s / 2, y * s / 2, 0);
    arm.rotation.z = Math.atan2(y, x);
    group.add(arm);
    const rotor = upright(body.rotor_radius * s, 0.008 * s, material, 24);
    rotor.position.set(x * s, y * s, 0.01 * s);
    group.add(rotor);
  }
  const nose = new THREE.Mesh(new THREE.BoxGeometry(body.radius * s * 0.8, 0.015 * s, 0.012 * s),
                              new THREE.MeshBasicMaterial({ color: 0xffffff }));
  nose.position.set(body.radius * s * 0.4, 0, 0.012 * s);
  group.add(nose);
  return { group, material, top: 0.05 };
}

// A dark disc on the floor under something in the air.
function shadow(radius) {
  return new THREE.Mesh(new THREE.CircleGeometry(radius, 24),
    new THREE.MeshBasicMaterial({ color: 0x000000, transparent: true, opacity: 0.3, depthWrite: false }));
}

// Where a flyer is over the floor: its shadow and a thin pole from the floor up to it (its altitude, at a glance).
function groundMarks(radius) {
  const pole = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3(0, 0, 1)]),
    new THREE.LineDashedMaterial({ color: 0xe3f2fd, dashSize: 0.1, gapSize: 0.08 }));
  return { shadow: shadow(radius), pole };
}

export class Bodies {
  constructor(scene, hello) {
    this.scene = scene;
    this.hello = hello;
    this.robots = new Map();
    for (const meta of hello.robots) this.robots.set(meta.name, this.makeRobot(meta));
    const R = hello.ball_radius;
    this.ball = new THREE.Mesh(new THREE.SphereGeometry(R, 24, 16), new THREE.MeshLambertMaterial({ color: 0xff9800 }));
    this.ball.visible = false;
    scene.add(this.ball);
    this.ballShadow = shadow(R);
    scene.add(this.ballShadow);
    this.holder = new THREE.Mesh(new THREE.RingGeometry(1, 1.12, 40), new THREE.MeshBasicMaterial({ color: 0xffeb3b, side: THREE.DoubleSide }));
    this.holder.visible = false;
    scene.add(this.holder);
    this.trail = [];
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(new Float32Array(3 * TRAIL_POINTS), 3));
    this.trailLine = new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0xffa726, transparent: true, opacity: 0.8 }));
    this.trailLine.frustumCulled = false;
    scene.add(this.trailLine);
    this.showTrail = true;
  }

  makeRobot(meta) {
    const body = meta.body || { kind: "ground", radius: meta.radius || 0.25, height: 0.8, mouth: 0.07 };
    const color = new THREE.Color(teamColor(this.hello, meta.team));
    const made = body.kind === "drone" ? drone(body, color) : groundRobot(body, color, meta.goalkeeper);
    const tag = label(String(meta.id), body.kind === "drone" ? 0.22 : 0.32);
    const item = { meta, body, color, ...made, tag, marks: null };
    this.scene.add(made.group);
    this.scene.add(tag);
    if (body.kind === "drone") {
      item.marks = groundMarks(body.radius * (body.scale || 1));
      this.scene.add(item.marks.shadow, item.marks.pole);
    }
    return item;
  }

  update(frame) {
    const off = new Set(frame.sent_off || []);
    for (const r of frame.robots) {
      const item = this.robots.get(r.name);
      if (!item) continue;
      const here = r.x !== undefined && r.x !== null;
      item.group.visible = item.tag.visible = here;
      if (!here) continue;
      const z = item.body.kind === "drone" ? (r.z || 0) : 0;
      item.group.position.set(r.x, r.y, z);
      item.group.rotation.z = r.yaw;
      item.tag.position.set(r.x, r.y, z + item.top + 0.3);
      item.material.color.set(off.has(r.name) ? 0x777777 : item.color);
      if (item.marks) {
        item.marks.shadow.position.set(r.x, r.y, 0.006);
        item.marks.pole.position.set(r.x, r.y, 0);
        item.marks.pole.scale.set(1, 1, Math.max(1e-3, z));
        item.marks.pole.computeLineDistances();
      }
    }
    this.updateBall(frame);
  }

  updateBall(frame) {
    const b = frame.ball;
    this.ball.visible = Boolean(b);
    this.ballShadow.visible = false;
    this.holder.visible = false;
    if (!b) { this.trail = []; this.drawTrail(); return; }
    this.ball.position.set(b.x, b.y, b.z);
    this.ballShadow.position.set(b.x, b.y, 0.005);
    this.ballShadow.visible = b.z > 2.2 * this.hello.ball_radius;
    this.markHolder(frame, b);
    const last = this.trail[this.trail.length - 1];
    // a new trail after a jump in time (seek, reconnect) or in space (the ball was placed)
    if (last && (frame.t < last.t || frame.t - last.t > 0.5 || Math.hypot(b.x - last.x, b.y - last.y) > 1.0)) this.trail = [];
    if (!last || frame.t > last.t) this.trail.push({ t: frame.t, x: b.x, y: b.y, z: b.z });
    while (this.trail.length && (frame.t - this.trail[0].t > TRAIL || this.trail.length > TRAIL_POINTS)) this.trail.shift();
    this.drawTrail();
  }

  // The robot holding the ball (the ball in its mouth, on the floor): a yellow ring round it.
  markHolder(frame, b) {
    const R = this.hello.ball_radius;
    if (b.z > 2.5 * R) return;
    for (const r of frame.robots) {
      const item = this.robots.get(r.name);
      if (!item || item.body.kind !== "ground" || r.x === undefined || r.x === null) continue;
      const reach = item.body.radius - item.body.mouth + R;
      const mx = r.x + reach * Math.cos(r.yaw), my = r.y + reach * Math.sin(r.yaw);
      if (Math.hypot(b.x - mx, b.y - my) < 0.6 * R) {
        const s = item.body.radius + 0.06;
        this.holder.scale.set(s, s, 1);
        this.holder.position.set(r.x, r.y, 0.01);
        this.holder.visible = true;
        return;
      }
    }
  }

  drawTrail() {
    const pos = this.trailLine.geometry.attributes.position;
    const pts = this.showTrail ? this.trail : [];
    pts.forEach((p, i) => pos.setXYZ(i, p.x, p.y, p.z));
    pos.needsUpdate = true;
    this.trailLine.geometry.setDrawRange(0, pts.length > 1 ? pts.length : 0);
  }
}
