// The 3D view's stage: the WebGL renderer, the scene (the world and the bodies), the cameras, and the drawing
// loop: a picture is drawn when something changed (a new frame, a camera that moves, a resize), never more than
// once per animation frame.
import * as THREE from "three";
import { Bodies } from "/static/bodies3d.js";
import { Cameras } from "/static/cameras3d.js";
import { attackSign, teamColor } from "/static/simatch.js";
import { buildWorld } from "/static/world3d.js";

// Whether this browser can draw WebGL at all (a probe canvas: the page says so instead of failing).
export function webglAvailable() {
  try {
    const probe = document.createElement("canvas");
    return Boolean(probe.getContext("webgl2") || probe.getContext("webgl"));
  } catch (err) {
    return false;
  }
}

export class Stage {
  constructor(canvas, hello) {
    this.canvas = canvas;
    this.hello = hello;
    this.frame = null;
    this.contextLost = 0;
    canvas.addEventListener("webglcontextlost", (ev) => { ev.preventDefault(); this.contextLost++; });
    canvas.addEventListener("webglcontextrestored", () => { this.dirty = true; });
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, powerPreference: "high-performance" });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x0f1418);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x33402f, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.4);
    sun.position.set(-6, -9, 20);
    this.scene.add(sun);
    this.world = buildWorld(this.scene, hello.field);
    this.bodies = new Bodies(this.scene, hello);
    this.cameras = new Cameras(canvas, hello.field, hello.set_pieces !== false);  // a ball game: soccer's set pieces
    this.cameras.controls.addEventListener("change", () => { this.dirty = true; });
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
    this.recolour(null);
    this.drawn = 0;
    let last = performance.now();
    const loop = (now) => {
      const dt = Math.min(0.25, (now - last) / 1000);
      last = now;
      this.draw(dt);
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  resize() {
    const r = this.canvas.getBoundingClientRect();
    this.w = Math.max(1, r.width); this.h = Math.max(1, r.height);
    this.renderer.setSize(this.w, this.h, false);
    this.cameras.resize(this.w, this.h);
    this.dirty = true;
  }

  // The nets take the colour of the team that defends them now (the teams change ends at half time).
  recolour(game) {
    const h = this.hello;
    this.world.recolour((side) => {
      const team = h.teams.find((t) => attackSign(h, game, t.name) === -side) || h.teams[0];
      return team ? teamColor(h, team.name) : "#cccccc";
    });
  }

  setFrame(frame) {
    const ends = JSON.stringify(frame.game && frame.game.attacks);
    if (ends !== this.ends) { this.ends = ends; this.recolour(frame.game); }
    this.frame = frame;
    this.bodies.update(frame);
    this.dirty = true;
  }

  setMode(mode) { this.cameras.setMode(mode, this.frame); this.dirty = true; }

  draw(dt) {
    const moving = this.cameras.mode === "broadcast" || this.cameras.mode === "follow";
    if (!this.dirty && !moving) return;
    this.cameras.update(this.frame, dt);
    const followed = this.cameras.mode === "follow" ? this.cameras.target : null;
    for (const [name, item] of this.bodies.robots) item.tag.visible = item.group.visible && name !== followed;  // not in the lens
    this.renderer.render(this.scene, this.cameras.camera);
    this.dirty = false;
    this.drawn++;
  }

  // Where world point (x, y, z) is on the canvas now [CSS px] (for tools and tests: the camera's own projection).
  project(x, y, z = 0) { return this.cameras.project(x, y, z); }

  // The robot under canvas point (px, py), or null: what a click on the picture chooses to follow.
  pick(px, py) {
    const ray = new THREE.Raycaster();
    ray.setFromCamera(new THREE.Vector2(px / this.w * 2 - 1, 1 - py / this.h * 2), this.cameras.camera);
    const items = [...this.bodies.robots.values()].filter((i) => i.group.visible);
    const hits = ray.intersectObjects(items.map((i) => i.group), true);
    if (!hits.length) return null;
    const hit = items.find((i) => { let o = hits[0].object; while (o) { if (o === i.group) return true; o = o.parent; } return false; });
    return hit ? hit.meta.name : null;
  }
}
