// simatch web UI: what every page shares — the connection (token, automatic reconnect, answers to
// requests) and the display area (the field to scale, robots, ball, obstacles, pass lines).
// World frame everywhere: metres, +x towards the goal at the right, +y up on the screen.

export const TEAM_COLORS = { cyan: "#19c6da", magenta: "#e0359c" };

export function token() {
  return new URLSearchParams(location.search).get("token") || "";
}

// ------------------------------------------------------------------------------------------------
// Connection: one WebSocket, reopened after a loss (0.5 s, then up to 5 s between tries).

export class Connection {
  constructor({ onHello, onFrame, onEvents, onStatus }) {
    this.handlers = { onHello, onFrame, onEvents, onStatus };
    this.pending = new Map();
    this.nextId = 1;
    this.delay = 500;
    this.fatal = null;
    this.framesReceived = 0;
    this.open();
  }

  open() {
    const scheme = location.protocol === "https:" ? "wss" : "ws";
    const ws = new WebSocket(`${scheme}://${location.host}/ws?token=${encodeURIComponent(token())}`);
    this.ws = ws;
    ws.onopen = () => { this.delay = 500; this.status("up"); };
    ws.onmessage = (ev) => this.receive(JSON.parse(ev.data));
    ws.onclose = () => {
      for (const [, p] of this.pending) p.reject(new Error("connection lost"));
      this.pending.clear();
      if (this.fatal) { this.status("refused", this.fatal); return; }
      this.status("down");
      setTimeout(() => this.open(), this.delay);
      this.delay = Math.min(5000, this.delay * 2);
    };
  }

  status(state, detail) {
    const el = document.getElementById("conn");
    if (el) {
      el.classList.toggle("up", state === "up");
      el.textContent = { up: "live", down: "reconnecting…", refused: "refused" }[state] || state;
    }
    if (state === "refused") refuse();
    if (this.handlers.onStatus) this.handlers.onStatus(state, detail);
  }

  receive(m) {
    if (m.type === "hello") this.handlers.onHello && this.handlers.onHello(m);
    else if (m.type === "frame") { this.framesReceived++; this.handlers.onFrame && this.handlers.onFrame(m); }
    else if (m.type === "events") this.handlers.onEvents && this.handlers.onEvents(m);
    else if (m.type === "ack" || m.type === "error") {
      const p = m.id !== undefined ? this.pending.get(m.id) : undefined;
      if (p) {
        this.pending.delete(m.id);
        m.type === "ack" ? p.resolve(m) : p.reject(new Error(m.error));
      } else if (m.type === "error") {
        if (m.fatal) this.fatal = m.error;
        toast(m.error);
      }
    }
  }

  // Send a request; the promise settles with the server's answer (errors are also shown in a toast).
  request(msg) {
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      if (!this.ws || this.ws.readyState !== WebSocket.OPEN) { reject(new Error("not connected")); return; }
      this.pending.set(id, { resolve, reject });
      this.ws.send(JSON.stringify({ ...msg, id }));
    }).catch((err) => { toast(err.message); throw err; });
  }
}

// A page the server refused (a wrong or missing token) can do nothing: every control says so.
function refuse() {
  document.body.classList.add("refused");
  document.querySelectorAll("button, input, select").forEach((el) => {
    el.disabled = true;
    el.title = "this page was refused: open an address printed on the console";
  });
}

let toastTimer = null;
export function toast(text, ok = false) {
  const el = document.getElementById("toast");
  if (!el) return;
  el.textContent = text;
  el.classList.toggle("ok", ok);
  el.classList.add("show");
  clearTimeout(toastTimer);
  toastTimer = setTimeout(() => el.classList.remove("show"), ok ? 1200 : 4000);
}

export function fmt(v, digits = 2) {
  return v === null || v === undefined || Number.isNaN(v) ? "–" : Number(v).toFixed(digits);
}

// m:ss.s — rounded to the tenth first, then split, so that 119.97 s reads 2:00.0 (never 1:60.0)
export function clock(t) {
  if (t === null || t === undefined || !Number.isFinite(t)) return "–";
  const tenths = Math.round(Math.abs(t) * 10);
  const m = Math.floor(tenths / 600), s = (tenths - 600 * m) / 10;
  return `${t < 0 && tenths ? "-" : ""}${m}:${s.toFixed(1).padStart(4, "0")}`;
}

// The match clock at frame time t: the referee publishes its game state on every change and once a second;
// its clock runs on in between (in stoppages too), except while the operator's pause holds it.
export function gameClock(g, t) {
  return g.paused ? g.clock : g.clock + Math.max(0, t - g.t);
}

// The referee's command in neutral words: "FREEKICK magenta", "STOPROBOT, next KICKOFF cyan" (GameState gives
// commands from the first team's point of view and names the team whose set piece it is).
const neutral = (name) => name.replace(/^(OUR|OPP)_/, "");
export function commandText(g) {
  if (g.next_command) return `${g.command_name}, next ${neutral(g.next_command_name)} ${g.command_team}`;
  return g.command_team ? `${neutral(g.command_name)} ${g.command_team}` : g.command_name;
}

// The score as the pages' headers show it: "cyan 1 : 0 magenta" in the teams' colours (more teams: the scores).
export function scoreboard(hello, game) {
  const teams = hello.teams.map((t) => t.name);
  const score = (t) => (game && game.score[t] !== undefined ? game.score[t] : 0);
  return teams.length === 2
    ? `<span style="color:${teamColor(hello, teams[0])}">${teams[0]}</span><span class="score" id="score">${score(teams[0])} : ${score(teams[1])}</span><span style="color:${teamColor(hello, teams[1])}">${teams[1]}</span>`
    : `<span class="score" id="score">${teams.map(score).join(" : ")}</span>`;
}

// The way a team attacks now: +1 towards +x, -1 towards -x. The game state says it (the teams change ends at
// half time); before the first game state, or without a referee, the scene's team frame.
export function attackSign(hello, game, team) {
  const side = game && game.attacks ? game.attacks[team] : undefined;
  if (side) return side === "-x" ? -1 : 1;
  const t = hello.teams.find((x) => x.name === team);
  return t ? t.sign : 1;
}

// An arrow for the way a team attacks on the screen (the field may be turned).
export function attackArrow(hello, game, team, flip = false) {
  return attackSign(hello, game, team) * (flip ? -1 : 1) > 0 ? "→" : "←";
}

export function teamColor(hello, team) {
  const t = hello.teams.find((x) => x.name === team);
  const c = t ? t.color : team;
  return TEAM_COLORS[c] || c;
}

// The colour of the robots a team's perception reports as obstacles: the other team's (grey where there are
// several other teams, or none).
export function opponentColor(hello) {
  const others = hello.teams.filter((t) => t.name !== hello.team);
  return others.length === 1 ? teamColor(hello, others[0].name) : "#b0bec5";
}

// "#rrggbb" (or a name the page knows) with an alpha, for translucent fills
export function withAlpha(color, alpha) {
  const m = /^#([0-9a-f]{2})([0-9a-f]{2})([0-9a-f]{2})$/i.exec(color);
  return m ? `rgba(${parseInt(m[1], 16)},${parseInt(m[2], 16)},${parseInt(m[3], 16)},${alpha})` : color;
}

// ------------------------------------------------------------------------------------------------
// Event log: newest first, with the reason of every decision.

export class EventLog {
  constructor(list, max = 300) { this.list = list; this.max = max; this.items = []; }

  update(m) {
    if (m.reset) this.items = [];
    this.items.push(...m.items);
    if (this.items.length > this.max) this.items = this.items.slice(-this.max);
    this.render(this.items);
  }

  render(items) {
    const rows = items.slice().reverse().map((e) => {
      const who = [e.team, e.robot ? `#${e.robot}` : ""].filter(Boolean).join(" ");
      let why = e.detail || (e.info ? Object.entries(e.info).map(([k, v]) => `${k}: ${typeof v === "object" ? JSON.stringify(v) : v}`).join(", ") : "");
      if (e.limit) why += `${why ? " — " : ""}${fmt(e.value)} (limit ${fmt(e.limit)})`;
      const li = document.createElement("li");
      li.className = e.type;
      li.innerHTML = `<span class="t">${fmt(e.t, 1)}</span><span class="type"></span> <span class="who"></span><span class="why"></span>`;
      li.querySelector(".type").textContent = e.type;
      li.querySelector(".who").textContent = who;
      li.querySelector(".why").textContent = why;
      return li;
    });
    this.list.replaceChildren(...rows);
  }
}

// ------------------------------------------------------------------------------------------------
// The display area: the field to scale (FieldGeometry.describe()), drawn on a canvas: markings, goals,
// zones, static obstacles (with their heights), robots, drones (seen from above, with their heights).

const FIELD_PAD = 24;  // [CSS px] round the floor: two lines of labels above a robot at its very edge

export class FieldView {
  constructor(canvas, hello, options = {}) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.hello = hello;
    this.field = hello.field;
    this.flip = false;
    this.frame = null;
    this.trail = [];
    this.options = { trail: true, passes: true, targets: true, obstacles: "all", ...options };
    this.marker = null;        // a chosen point (e.g. a test target)
    this.dragBall = null;      // where the ball is being dragged to
    this.meta = Object.fromEntries(hello.robots.map((r) => [r.name, r]));
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
    const loop = () => { this.draw(); requestAnimationFrame(loop); };
    requestAnimationFrame(loop);
  }

  resize() {
    const dpr = window.devicePixelRatio || 1;
    const r = this.canvas.getBoundingClientRect();
    this.w = r.width; this.h = r.height;
    this.canvas.width = Math.max(1, Math.round(r.width * dpr));
    this.canvas.height = Math.max(1, Math.round(r.height * dpr));
    this.ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    // a border of screen pixels round the floor: a robot at the edge keeps its id and role on the canvas
    const f = this.field, pad = FIELD_PAD;
    this.scale = Math.max(1e-6, Math.min((this.w - 2 * pad) / (f.length + 2 * f.margin), (this.h - 2 * pad) / (f.width + 2 * f.margin)));
    this.dirty = true;
  }

  // world (m) -> canvas CSS pixels, and back
  toScreen(x, y) {
    const s = this.flip ? -1 : 1;
    return [this.w / 2 + s * x * this.scale, this.h / 2 - s * y * this.scale];
  }

  toWorld(px, py) {
    const s = this.flip ? -1 : 1;
    return [s * (px - this.w / 2) / this.scale, -s * (py - this.h / 2) / this.scale];
  }

  eventToWorld(ev) {
    const r = this.canvas.getBoundingClientRect();
    return this.toWorld(ev.clientX - r.left, ev.clientY - r.top);
  }

  setFrame(frame) {
    const b = frame.ball;
    if (b && this.options.trail) {
      const last = this.trail[this.trail.length - 1];
      // a new trail after a jump in time (seek, reconnect) or in space (the ball was placed)
      if (last && (frame.t < last.t || frame.t - last.t > 0.5 || Math.hypot(b.x - last.x, b.y - last.y) > 1.0)) this.trail = [];
      this.trail.push({ t: frame.t, x: b.x, y: b.y });
      while (this.trail.length && frame.t - this.trail[0].t > 1.5) this.trail.shift();
    }
    this.frame = frame;
  }

  draw() {
    const c = this.ctx, f = this.field, k = this.scale;
    if (!k) return;
    c.clearRect(0, 0, this.w, this.h);
    // floor and field
    const [fx0, fy0] = this.toScreen(-f.length / 2 - f.margin, f.width / 2 + f.margin);
    c.fillStyle = "#1d5a2a";
    c.fillRect(Math.min(fx0, this.w - fx0), Math.min(fy0, this.h - fy0), k * (f.length + 2 * f.margin), k * (f.width + 2 * f.margin));
    const [ix0, iy0] = this.toScreen(-f.length / 2, f.width / 2);
    c.fillStyle = "#23703a";
    c.fillRect(Math.min(ix0, this.w - ix0), Math.min(iy0, this.h - iy0), k * f.length, k * f.width);
    c.strokeStyle = "rgba(255,255,255,0.92)";
    c.fillStyle = "rgba(255,255,255,0.92)";
    c.lineWidth = Math.max(1, f.line_width * k);
    c.lineJoin = "miter"; c.lineCap = "square";
    for (const p of f.lines) this.primitive(p);
    for (const a of f.areas || []) this.area(a);
    for (const o of f.obstacles || []) this.obstacle(o);
    if (f.ceiling) this.note(`ceiling ${f.ceiling.toFixed(1)} m`);
    if (f.goals) this.goals();
    if (!this.frame) return;
    this.drawFrame(this.frame);
    if (this.marker) this.cross(this.marker[0], this.marker[1], "#ffeb3b");
  }

  primitive(p) {
    const c = this.ctx;
    if (p.kind === "polyline") {
      c.beginPath();
      p.points.forEach(([x, y], i) => { const [sx, sy] = this.toScreen(x, y); i ? c.lineTo(sx, sy) : c.moveTo(sx, sy); });
      c.stroke();
    } else if (p.kind === "arc") {
      const [sx, sy] = this.toScreen(p.center[0], p.center[1]);
      c.beginPath();
      // screen y points down: a counter-clockwise world arc is clockwise on screen (and turned by pi when flipped)
      const off = this.flip ? Math.PI : 0;
      c.arc(sx, sy, p.radius * this.scale, -(p.end + off), -(p.start + off));
      c.stroke();
    } else if (p.kind === "dot") {
      const [sx, sy] = this.toScreen(p.center[0], p.center[1]);
      c.beginPath();
      c.arc(sx, sy, Math.max(1.5, p.radius * this.scale), 0, 2 * Math.PI);
      c.fill();
    }
  }

  area(a) {
    const c = this.ctx;
    const [x0, y0] = this.toScreen(a.x0, a.y1), [x1, y1] = this.toScreen(a.x1, a.y0);
    c.save();
    c.setLineDash([6, 4]);
    c.strokeStyle = "#ffb74d";
    c.lineWidth = 2;
    c.strokeRect(Math.min(x0, x1), Math.min(y0, y1), Math.abs(x1 - x0), Math.abs(y1 - y0));
    c.fillStyle = "#ffb74d";
    c.font = "12px system-ui";
    c.fillText(a.name, Math.min(x0, x1) + 4, Math.min(y0, y1) + 14);
    c.restore();
  }

  // a static obstacle seen from above: a box turned by its yaw, or a cylinder; its height written on it
  obstacle(o) {
    const c = this.ctx;
    c.save();
    c.fillStyle = "rgba(58,62,70,0.95)"; c.strokeStyle = "#c5cad3"; c.lineWidth = 1.5;
    c.beginPath();
    if (o.shape === "cylinder") {
      const [sx, sy] = this.toScreen(o.x, o.y);
      c.arc(sx, sy, o.radius * this.scale, 0, 2 * Math.PI);
    } else {
      const cs = Math.cos(o.yaw), sn = Math.sin(o.yaw);
      [[1, 1], [-1, 1], [-1, -1], [1, -1]].forEach(([a, b], i) => {
        const px = a * o.half_x, py = b * o.half_y;
        const [sx, sy] = this.toScreen(o.x + cs * px - sn * py, o.y + sn * px + cs * py);
        i ? c.lineTo(sx, sy) : c.moveTo(sx, sy);
      });
      c.closePath();
    }
    c.fill(); c.stroke();
    const [tx, ty] = this.toScreen(o.x, o.y);
    c.fillStyle = "rgba(255,255,255,0.8)"; c.font = "10px system-ui"; c.textAlign = "center"; c.textBaseline = "middle";
    c.fillText(`${o.height.toFixed(1)} m`, tx, ty);
    c.restore();
  }

  note(text) {
    const c = this.ctx;
    c.save(); c.fillStyle = "rgba(255,255,255,0.7)"; c.font = "11px system-ui"; c.textBaseline = "top";
    c.fillText(text, 6, 6); c.restore();
  }

  goals() {
    const c = this.ctx, f = this.field, L = f.length / 2, gw = f.goal_width / 2, d = f.goal_depth;
    for (const side of [-1, 1]) {
      // the team that defends this goal now: the one that attacks the other way (they change ends at half time)
      const game = this.frame && this.frame.game;
      const team = this.hello.teams.find((t) => attackSign(this.hello, game, t.name) === -side) || this.hello.teams[0];
      const [x0, y0] = this.toScreen(side * L, gw), [x1, y1] = this.toScreen(side * (L + d), -gw);
      c.fillStyle = "rgba(255,255,255,0.25)";
      c.fillRect(Math.min(x0, x1), Math.min(y0, y1), Math.abs(x1 - x0), Math.abs(y1 - y0));
      c.lineWidth = Math.max(2, f.goal_post_size * this.scale);
      c.strokeStyle = teamColor(this.hello, team.name);
      c.strokeRect(Math.min(x0, x1), Math.min(y0, y1), Math.abs(x1 - x0), Math.abs(y1 - y0));
    }
  }

  cross(x, y, color) {
    const c = this.ctx, [sx, sy] = this.toScreen(x, y), r = 6;
    c.strokeStyle = color; c.lineWidth = 2;
    c.beginPath(); c.moveTo(sx - r, sy - r); c.lineTo(sx + r, sy + r); c.moveTo(sx - r, sy + r); c.lineTo(sx + r, sy - r); c.stroke();
  }

  drawFrame(fr) {
    const c = this.ctx;
    this.labels = [];  // where this frame's text went (screen rectangles), so that none covers the ball
    const b = this.dragBall ? { x: this.dragBall[0], y: this.dragBall[1] } : fr.ball;
    if (b) {
      const [bx, by] = this.toScreen(b.x, b.y);
      this.ballSpot = { x: bx, y: by, r: Math.max(3.5, this.hello.ball_radius * this.scale) + 4 };
    } else this.ballSpot = null;
    // obstacles seen by the chosen robot(s) (coach pages): the opponents as this team perceives them, drawn
    // translucent in their team's colour
    if (fr.obstacles && this.options.obstacles !== "none") {
      const color = opponentColor(this.hello);
      c.strokeStyle = color; c.lineWidth = 1.5; c.fillStyle = withAlpha(color, 0.35);
      for (const [rid, list] of Object.entries(fr.obstacles)) {
        if (this.options.obstacles !== "all" && String(this.options.obstacles) !== rid) continue;
        for (const [x, y, r] of list) {
          const [sx, sy] = this.toScreen(x, y);
          c.beginPath(); c.arc(sx, sy, Math.max(3, r * this.scale), 0, 2 * Math.PI); c.fill(); c.stroke();
        }
      }
    }
    // where each robot is heading
    if (this.options.targets) {
      c.save(); c.setLineDash([3, 4]); c.strokeStyle = "rgba(255,255,255,0.35)"; c.lineWidth = 1;
      for (const r of fr.robots) {
        if (!r.target || r.x === undefined) continue;
        const [a, b] = this.toScreen(r.x, r.y), [tx, ty] = this.toScreen(r.target[0], r.target[1]);
        c.beginPath(); c.moveTo(a, b); c.lineTo(tx, ty); c.stroke();
      }
      c.restore();
    }
    // pass lines (passer -> catch point)
    if (fr.passes && this.options.passes) {
      c.save(); c.strokeStyle = "#ffeb3b"; c.lineWidth = 2; c.setLineDash(fr.passes.some((p) => p.kicked) ? [] : [8, 5]);
      for (const p of fr.passes) {
        if (p.from[0] === null) continue;
        const [a, b] = this.toScreen(p.from[0], p.from[1]), [tx, ty] = this.toScreen(p.to[0], p.to[1]);
        c.beginPath(); c.moveTo(a, b); c.lineTo(tx, ty); c.stroke();
        c.beginPath(); c.arc(tx, ty, 4, 0, 2 * Math.PI); c.fillStyle = "#ffeb3b"; c.fill();
      }
      c.restore();
    }
    const off = new Set(fr.sent_off || []);
    for (const r of fr.robots) if (r.x !== undefined && r.x !== null) this.robot(r, off.has(r.name) || r.sent_off);
    this.ball(fr.ball);
  }

  // a drone seen from above: four rotor discs on an X turned by its heading, a nose mark, and its height;
  // drawn larger the higher it flies (and never smaller than a few pixels), with its shadow on the floor
  drone(r, meta, sentOff) {
    const c = this.ctx, team = r.team || meta.team, z = r.z || 0;
    const [sx, sy] = this.toScreen(r.x, r.y);
    const yaw = this.flip ? r.yaw + Math.PI : r.yaw;
    const arm = Math.max(7, meta.radius * this.scale) * (1 + Math.min(z, 6) * 0.08);
    const rotor = arm * 0.42, color = sentOff ? "#777" : teamColor(this.hello, team);
    c.save();
    c.fillStyle = "rgba(0,0,0,0.28)";
    c.beginPath(); c.ellipse(sx + 2 + z * 1.5, sy + 2 + z * 1.5, arm * 0.9, arm * 0.6, 0, 0, 2 * Math.PI); c.fill();
    c.strokeStyle = "#0b0f12"; c.lineWidth = 2;
    for (const a of [Math.PI / 4, 3 * Math.PI / 4, -3 * Math.PI / 4, -Math.PI / 4]) {
      const rx = sx + arm * Math.cos(yaw + a), ry = sy - arm * Math.sin(yaw + a);
      c.beginPath(); c.moveTo(sx, sy); c.lineTo(rx, ry); c.stroke();
      c.beginPath(); c.arc(rx, ry, rotor, 0, 2 * Math.PI); c.fillStyle = color; c.fill(); c.stroke();
    }
    c.beginPath(); c.moveTo(sx, sy); c.lineTo(sx + arm * 0.9 * Math.cos(yaw), sy - arm * 0.9 * Math.sin(yaw));
    c.strokeStyle = "#fff"; c.lineWidth = 2; c.stroke();
    c.font = "bold 12px system-ui"; c.fillStyle = "#fff"; c.textBaseline = "bottom";
    c.fillText(`${r.id}`, sx + arm + 2, sy - arm * 0.6);
    c.font = "11px system-ui"; c.textBaseline = "top"; c.fillStyle = "#e3f2fd";
    c.fillText(`${z.toFixed(1)} m`, sx + arm + 2, sy - arm * 0.6 + 1);
    c.restore();
  }

  robot(r, sentOff) {
    const c = this.ctx, meta = this.meta[r.name] || { radius: 0.25, team: r.team || this.hello.team };
    if (meta.aerial) { this.drone(r, meta, sentOff); return; }
    const team = r.team || meta.team;
    const [sx, sy] = this.toScreen(r.x, r.y), rad = Math.max(4, meta.radius * this.scale);
    const yaw = (this.flip ? r.yaw + Math.PI : r.yaw);
    c.beginPath(); c.arc(sx, sy, rad, 0, 2 * Math.PI);
    c.fillStyle = sentOff ? "#777" : teamColor(this.hello, team);
    c.fill();
    c.lineWidth = meta.goalkeeper ? 3 : 1.5; c.strokeStyle = meta.goalkeeper ? "#fff" : "#0b0f12"; c.stroke();
    // heading: from the centre to the kicker
    c.beginPath(); c.moveTo(sx, sy); c.lineTo(sx + rad * Math.cos(yaw), sy - rad * Math.sin(yaw));
    c.lineWidth = 3; c.strokeStyle = "#0b0f12"; c.stroke();
    // id and role beside the robot, wherever they do not cover the ball
    const id = String(r.id), label = sentOff ? "OFF" : (r.role || "");
    this.label(id, "bold 13px system-ui", "#fff",
               [[sx + rad * 0.8, sy - rad * 0.8 - 13], [sx - rad * 0.8 - 9, sy - rad * 0.8 - 13],
                [sx + rad * 0.8, sy + rad * 0.8], [sx - rad * 0.8 - 9, sy + rad * 0.8]]);
    if (label) {
      c.font = "11px system-ui";
      const w = c.measureText(label).width;
      this.label(label, "11px system-ui", "rgba(255,255,255,0.9)",
                 [[sx - w / 2, sy + rad + 2], [sx - w / 2, sy - rad - 27], [sx + rad + 4, sy - 6], [sx - rad - 4 - w, sy - 6]]);
    }
    if (r.holding || r.dribble) { c.beginPath(); c.arc(sx, sy, rad + 3, 0, 2 * Math.PI); c.strokeStyle = "#ffeb3b"; c.lineWidth = 1.5; c.stroke(); }
    if (r.stuck) this.label("stuck", "11px system-ui", "#fb8c00", [[sx - 12, sy - rad - 14], [sx - 12, sy + rad + 14]]);
  }

  // Text at the first of `spots` (top-left corners) whose box keeps clear of the ball, with a dark halo so
  // that it reads on the field.
  label(text, font, color, spots) {
    const c = this.ctx;
    c.font = font;
    const w = c.measureText(text).width, h = parseInt(font.match(/(\d+)px/)[1], 10) + 1;
    const clear = ([x, y]) => {
      const s = this.ballSpot;
      if (!s) return true;
      const nx = Math.max(x, Math.min(s.x, x + w)), ny = Math.max(y, Math.min(s.y, y + h));
      return Math.hypot(s.x - nx, s.y - ny) > s.r;
    };
    const [x, y] = spots.find(clear) || spots[0];
    c.textBaseline = "top";
    c.lineJoin = "round"; c.lineWidth = 3; c.strokeStyle = "rgba(0,0,0,0.55)";
    c.strokeText(text, x, y);
    c.fillStyle = color; c.fillText(text, x, y);
    this.labels.push({ text, x, y, w, h });
  }

  ball(b) {
    const c = this.ctx, R = this.hello.ball_radius;
    if (this.options.trail && this.trail.length > 1) {
      for (let i = 1; i < this.trail.length; i++) {
        const p = this.trail[i - 1], q = this.trail[i];
        const [a, bb] = this.toScreen(p.x, p.y), [x2, y2] = this.toScreen(q.x, q.y);
        c.strokeStyle = `rgba(255,152,0,${(0.7 * i / this.trail.length).toFixed(3)})`; c.lineWidth = 2;
        c.beginPath(); c.moveTo(a, bb); c.lineTo(x2, y2); c.stroke();
      }
    }
    const drawAt = this.dragBall || (b ? [b.x, b.y] : null);
    if (!drawAt) return;
    const [sx, sy] = this.toScreen(drawAt[0], drawAt[1]);
    const base = Math.max(3.5, R * this.scale);
    const h = !this.dragBall && b ? Math.max(0, b.z - R) : 0;
    if (h > 0.03) {
      // in the air: a shadow where it would land straight down, the ball lifted and larger, its height
      const lift = h * this.scale * 0.6, grow = 1 + h * 0.6;
      c.fillStyle = "rgba(0,0,0,0.45)";
      c.beginPath(); c.ellipse(sx, sy, base, base * 0.6, 0, 0, 2 * Math.PI); c.fill();
      c.setLineDash([2, 3]); c.strokeStyle = "rgba(255,255,255,0.6)"; c.lineWidth = 1;
      c.beginPath(); c.moveTo(sx, sy); c.lineTo(sx, sy - lift); c.stroke(); c.setLineDash([]);
      c.beginPath(); c.arc(sx, sy - lift, base * grow, 0, 2 * Math.PI);
      c.fillStyle = "#ff9800"; c.fill(); c.strokeStyle = "#3e2723"; c.lineWidth = 1.5; c.stroke();
      c.font = "bold 11px system-ui"; c.fillStyle = "#fff"; c.textBaseline = "bottom";
      c.fillText(`${b.z.toFixed(2)} m`, sx + base * grow + 3, sy - lift);
    } else {
      c.beginPath(); c.arc(sx, sy, base, 0, 2 * Math.PI);
      c.fillStyle = this.dragBall ? "rgba(255,152,0,0.6)" : "#ff9800"; c.fill();
      c.strokeStyle = "#3e2723"; c.lineWidth = 1.5; c.stroke();
    }
  }
}

// ------------------------------------------------------------------------------------------------
// What every page does with its connection: keep the newest frame, draw it, render the rest; `page.send`
// sends a request and shows its answer. The page object is `window.simatch` (for tests and tools).

export function startPage(page, { onHello, render, onEvents }) {
  page.conn = new Connection({
    onHello(h) {
      const link = document.getElementById("link3d");
      if (link && h.links) link.href = h.links["3d view"];
      onHello(h);
    },
    onFrame(f) {
      page.frame = f;
      if (page.view) page.view.setFrame(f);
      render(f);
    },
    onEvents,
  });
  page.send = (msg) => page.conn.request(msg).then(() => toast("done", true)).catch(() => {});
  window.simatch = page;
  return page.conn;
}

export const SET_PIECES = [["KICKOFF", "Kick-off"], ["THROWIN", "Throw-in"], ["PENALTY", "Penalty"],
                           ["GOALKICK", "Goal kick"], ["CORNERKICK", "Corner"], ["FREEKICK", "Free kick"]];

// A button for each set piece, ours and theirs (data-cmd holds the command's name).
export function setPieceButtons(container) {
  for (const [key, label] of SET_PIECES) {
    for (const [side, text] of [["OUR", label], ["OPP", `${label} (opp)`]]) {
      const b = document.createElement("button");
      b.textContent = text;
      b.dataset.cmd = `${side}_${key}`;
      container.appendChild(b);
    }
  }
}
