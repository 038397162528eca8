// The 3D view's world: what does not move, built once from the field the server describes (FieldGeometry's
// describe(): the very lines the referee judges): the floor, the markings, named areas, the goals with posts,
// crossbar and net, the boards, the arena's obstacles at their heights and the ceiling.
// World frame: metres, z up, the origin at the field's centre.
import * as THREE from "three";

const WHITE = 0xf7f7f7;
const LINE_Z = 0.004;   // the markings lie just above the floor (no z-fighting with it)

// A flat band of `width` along each segment of `points` ([x, y] pairs), square-capped like the 2D page's lines,
// as triangles appended to `out` (a list of floats, 3 per vertex).
function band(points, width, out) {
  const h = width / 2;
  for (let i = 1; i < points.length; i++) {
    const [x0, y0] = points[i - 1], [x1, y1] = points[i];
    const len = Math.hypot(x1 - x0, y1 - y0);
    if (len < 1e-9) continue;
    const ux = (x1 - x0) / len, uy = (y1 - y0) / len, nx = -uy * h, ny = ux * h;
    const ax = x0 - ux * h, ay = y0 - uy * h, bx = x1 + ux * h, by = y1 + uy * h;
    out.push(ax + nx, ay + ny, LINE_Z, ax - nx, ay - ny, LINE_Z, bx - nx, by - ny, LINE_Z,
             ax + nx, ay + ny, LINE_Z, bx - nx, by - ny, LINE_Z, bx + nx, by + ny, LINE_Z);
  }
}

// An arc of the markings as points (a counter-clockwise world arc from `start` to `end`).
function arcPoints(p) {
  const n = Math.max(6, Math.ceil(Math.abs(p.end - p.start) / (2 * Math.PI) * 96));
  const pts = [];
  for (let k = 0; k <= n; k++) {
    const a = p.start + (p.end - p.start) * k / n;
    pts.push([p.center[0] + p.radius * Math.cos(a), p.center[1] + p.radius * Math.sin(a)]);
  }
  return pts;
}

function markings(f) {
  const tri = [];
  const group = new THREE.Group();
  const material = new THREE.MeshBasicMaterial({ color: WHITE, side: THREE.DoubleSide });
  for (const p of f.lines || []) {
    if (p.kind === "polyline") band(p.points, f.line_width, tri);
    else if (p.kind === "arc") band(arcPoints(p), f.line_width, tri);
    else if (p.kind === "dot") {
      const dot = new THREE.Mesh(new THREE.CircleGeometry(p.radius, 24), material);
      dot.position.set(p.center[0], p.center[1], LINE_Z);
      group.add(dot);
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.Float32BufferAttribute(tri, 3));
  group.add(new THREE.Mesh(geometry, material));
  return group;
}

function box(sx, sy, sz, material, x, y, z, yaw = 0) {
  const m = new THREE.Mesh(new THREE.BoxGeometry(sx, sy, sz), material);
  m.position.set(x, y, z);
  m.rotation.z = yaw;
  return m;
}

// A cylinder standing on the floor (three's cylinders stand along y: turned to z).
export function upright(radius, height, material, segments = 32) {
  const g = new THREE.CylinderGeometry(radius, radius, height, segments);
  g.rotateX(Math.PI / 2);
  return new THREE.Mesh(g, material);
}

// Lines of a net: a grid of `step` over the goal's back, sides and roof (from the goal line at x0 to x1).
function netLines(x0, x1, halfWidth, height, step) {
  const pts = [];
  const seg = (a, b) => pts.push(...a, ...b);
  for (let y = -halfWidth; y <= halfWidth + 1e-9; y += step) {
    seg([x1, y, 0], [x1, y, height]);                    // back, upright
    seg([x0, y, height], [x1, y, height]);              // roof, along the depth
  }
  for (let z = 0; z <= height + 1e-9; z += step) {
    seg([x1, -halfWidth, z], [x1, halfWidth, z]);        // back, across
    for (const s of [-1, 1]) seg([x0, s * halfWidth, z], [x1, s * halfWidth, z]);  // sides, along the depth
  }
  const n = Math.max(1, Math.round(Math.abs(x1 - x0) / step));
  for (let k = 0; k <= n; k++) {
    const x = x0 + (x1 - x0) * k / n;
    for (const s of [-1, 1]) seg([x, s * halfWidth, 0], [x, s * halfWidth, height]);  // sides, upright
    seg([x, -halfWidth, height], [x, halfWidth, height]);                              // roof, across
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", new THREE.Float32BufferAttribute(pts, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0xffffff, transparent: true, opacity: 0.55 }));
}

// The goals: two posts and a crossbar on each goal line, a net behind, tinted with the defending team's colour
// (`tint(side)` gives it: the teams change ends at half time, so the world calls `recolour`).
function goals(f) {
  const group = new THREE.Group();
  const L = f.length / 2, p = f.goal_post_size, gw = f.goal_width, gh = f.goal_height, gd = f.goal_depth;
  const post = new THREE.MeshLambertMaterial({ color: 0xffffff });
  const tints = {};
  for (const side of [-1, 1]) {
    const x = side * (L + p / 2);
    for (const sy of [-1, 1]) group.add(box(p, p, gh + p, post, x, sy * (gw / 2 + p / 2), (gh + p) / 2));
    group.add(box(p, gw + 2 * p, p, post, x, 0, gh + p / 2));
    const tint = new THREE.MeshBasicMaterial({ color: 0xcccccc, transparent: true, opacity: 0.18, depthWrite: false });
    tints[side] = tint;
    group.add(box(gd, gw, gh, tint, side * (L + p + gd / 2), 0, gh / 2));
    group.add(netLines(side * (L + p), side * (L + p + gd), gw / 2, gh, 0.15));
  }
  return { group, tints };
}

// The boards round the floor; tall ones (an arena's) are see-through, so that the side cameras see in.
function boards(f) {
  const group = new THREE.Group();
  const L = f.length / 2 + f.margin, W = f.width / 2 + f.margin, h = f.wall_height, t = 0.05;
  const tall = h > 1.0;
  const material = new THREE.MeshLambertMaterial({ color: 0x40414a, transparent: tall, opacity: tall ? 0.22 : 1.0,
                                                   depthWrite: !tall, side: THREE.DoubleSide });
  for (const s of [-1, 1]) {
    group.add(box(t, 2 * (W + t), h, material, s * (L + t / 2), 0, h / 2));
    group.add(box(2 * L, t, h, material, 0, s * (W + t / 2), h / 2));
  }
  if (tall) {  // the top edge, solid, so that the arena's bounds read
    const edge = new THREE.LineBasicMaterial({ color: 0x9aa0aa });
    const g = new THREE.BufferGeometry().setFromPoints(
      [[L, W], [-L, W], [-L, -W], [L, -W], [L, W]].map(([x, y]) => new THREE.Vector3(x, y, h)));
    group.add(new THREE.Line(g, edge));
  }
  return group;
}

function obstacles(f) {
  const group = new THREE.Group();
  const rock = new THREE.MeshLambertMaterial({ color: 0x5c616b });
  for (const o of f.obstacles || []) {
    if (o.shape === "cylinder") {
      const m = upright(o.radius, o.height, rock);
      m.position.set(o.x, o.y, o.height / 2);
      group.add(m);
    } else group.add(box(2 * o.half_x, 2 * o.half_y, o.height, rock, o.x, o.y, o.height / 2, o.yaw));
  }
  return group;
}

function areas(f) {
  const group = new THREE.Group();
  const fill = new THREE.MeshBasicMaterial({ color: 0xffb74d, transparent: true, opacity: 0.14, depthWrite: false });
  const edge = new THREE.LineDashedMaterial({ color: 0xffb74d, dashSize: 0.3, gapSize: 0.2 });
  for (const a of f.areas || []) {
    const w = a.x1 - a.x0, h = a.y1 - a.y0;
    const m = new THREE.Mesh(new THREE.PlaneGeometry(w, h), fill);
    m.position.set((a.x0 + a.x1) / 2, (a.y0 + a.y1) / 2, LINE_Z / 2);
    group.add(m);
    const g = new THREE.BufferGeometry().setFromPoints(
      [[a.x0, a.y0], [a.x1, a.y0], [a.x1, a.y1], [a.x0, a.y1], [a.x0, a.y0]].map(([x, y]) => new THREE.Vector3(x, y, 0.01)));
    const line = new THREE.Line(g, edge);
    line.computeLineDistances();
    group.add(line);
  }
  return group;
}

// The ceiling: seen from below only (a camera above looks through it), with its edges drawn from everywhere.
function ceiling(f) {
  const group = new THREE.Group();
  const L = f.length / 2 + f.margin, W = f.width / 2 + f.margin, z = f.ceiling;
  const panel = new THREE.Mesh(new THREE.PlaneGeometry(2 * L, 2 * W),
    new THREE.MeshBasicMaterial({ color: 0xb0bec5, transparent: true, opacity: 0.12, side: THREE.BackSide, depthWrite: false }));
  panel.position.z = z;
  group.add(panel);
  const g = new THREE.BufferGeometry().setFromPoints(
    [[L, W], [-L, W], [-L, -W], [L, -W], [L, W]].map(([x, y]) => new THREE.Vector3(x, y, z)));
  group.add(new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0xb0bec5 })));
  return group;
}

// The whole static world; `recolour(colourOfSide)` tints each goal's net with its defending team's colour.
export function buildWorld(scene, f) {
  const L = f.length / 2 + f.margin, W = f.width / 2 + f.margin;
  const floor = new THREE.Mesh(new THREE.PlaneGeometry(2 * L, 2 * W), new THREE.MeshLambertMaterial({ color: 0x1d5a2a }));
  scene.add(floor);
  const pitch = new THREE.Mesh(new THREE.PlaneGeometry(f.length, f.width), new THREE.MeshLambertMaterial({ color: 0x23703a }));
  pitch.position.z = LINE_Z / 4;
  scene.add(pitch);
  scene.add(markings(f));
  scene.add(areas(f));
  let tints = {};
  if (f.goals) {
    const g = goals(f);
    scene.add(g.group);
    tints = g.tints;
  }
  if (f.walls) scene.add(boards(f));
  scene.add(obstacles(f));
  if (f.ceiling) scene.add(ceiling(f));
  return {
    recolour(colourOfSide) {
      for (const side of [-1, 1]) if (tints[side]) tints[side].color.set(colourOfSide(side));
    },
  };
}
