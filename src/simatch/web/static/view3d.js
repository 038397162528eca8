// The 3D view: the run (live, or a recording) in three.js, fed by the same frames as the 2D pages. It follows
// the live picture until it is asked to look back (pause, seek, speed: the server gives it a timeline of its
// own over what has been played) and goes back to it with "Live". The overlay shows the game as the referee
// console does: score, clock, stage, the current command and the referee's reason.
import { MODES } from "/static/cameras3d.js";
import { clock, commandText, gameClock, scoreboard, startPage } from "/static/simatch.js";
import { Stage, webglAvailable } from "/static/stage3d.js";
import { TimelineBar } from "/static/timeline.js";

const $ = (id) => document.getElementById(id);
const page = { hello: null, view: null, frame: null, webgl: webglAvailable(), lastEvent: null };
const bar = new TimelineBar(page, $("timeline"), ["Live", "back to the moment the live pages show"]);
$("nowebgl").hidden = page.webgl;

startPage(page, {
  onHello(h) {
    page.hello = h;
    $("scene").textContent = h.source === "recording" ? `${h.scene} · ${h.recording}` : h.scene;
    if (h.source === "recording") bar.label(["Now playing", "back to the moment the recording plays on the bus"]);
    if (page.view || !page.webgl) return;
    try {
      page.view = new Stage($("scene3d"), h);
    } catch (err) {  // a browser that offered a context and then could not make one
      page.webgl = false;
      $("nowebgl").hidden = false;
    }
  },
  render,
  onEvents(m) { if (m.items.length) page.lastEvent = m.items[m.items.length - 1]; },
});

function render(f) {
  const h = page.hello, g = f.game;
  if (f.timeline) bar.render(f.timeline);
  $("scoreboard").innerHTML = scoreboard(h, g);
  $("stage").textContent = g ? g.stage : "no referee";
  $("clock").textContent = clock(g ? gameClock(g, f.t) : f.t);
  $("command").textContent = g ? commandText(g) : Object.entries(f.commands || {}).map(([t, c]) => `${t} ${c.mode}`).join(" / ") || "–";
  $("phase").textContent = !g ? "" : g.paused ? "paused" : g.phase + (g.manual ? " · manual" : "");
  const looking = f.timeline && !f.timeline.live;
  $("runstatus").textContent = f.status === "ended" ? "run ended" : looking ? "looking back" : "";
  const last = f.events && f.events.length ? f.events[f.events.length - 1] : page.lastEvent;
  const said = last ? `${last.type}${last.team ? ` ${last.team}` : ""}${last.robot ? ` #${last.robot}` : ""}` : "";
  $("decision").textContent = [g && g.reason ? `why: ${g.reason}` : "", said ? `last: ${said}` : ""].filter(Boolean).join(" · ");
}

// --- cameras and keys ------------------------------------------------------------------------------------------
function setMode(mode) {
  const v = page.view;
  if (!v) return;
  if (mode === "follow" && !v.cameras.target) v.cameras.target = nearestToBall();
  v.setMode(mode);
  const t = v.cameras.target;
  $("camera").textContent = mode === "follow" && t ? `follow ${t}` : mode;
}

function nearestToBall() {
  const f = page.frame, robots = f ? f.robots.filter((r) => r.x !== undefined && r.x !== null) : [];
  if (!robots.length) return page.hello && page.hello.robots.length ? page.hello.robots[0].name : null;
  const b = f.ball || { x: 0, y: 0 };
  return robots.reduce((a, r) => (Math.hypot(r.x - b.x, r.y - b.y) < Math.hypot(a.x - b.x, a.y - b.y) ? r : a)).name;
}

function follow(step) {
  const v = page.view;
  if (!v) return;
  const names = page.hello.robots.map((r) => r.name);
  const k = names.indexOf(v.cameras.target);
  v.cameras.target = names[(k + step + names.length) % names.length];
  setMode("follow");
}

document.addEventListener("keydown", (ev) => {
  if (["INPUT", "SELECT", "TEXTAREA"].includes(document.activeElement.tagName) || ev.ctrlKey || ev.metaKey || ev.altKey) return;
  const mode = MODES[Number(ev.key) - 1];
  if (mode) setMode(mode);
  else if (ev.key === "[" || ev.key === "]") follow(ev.key === "]" ? 1 : -1);
  else if (ev.key === "l" || ev.key === "L") $("live").click();
  else if (ev.key === "h" || ev.key === "H") $("help").classList.toggle("hide");
  else if ((ev.key === "t" || ev.key === "T") && page.view) {
    page.view.bodies.showTrail = !page.view.bodies.showTrail;
    page.view.bodies.drawTrail();
    page.view.dirty = true;
  }
});

// A click (not a drag) on a robot follows it.
let down = null;
$("scene3d").addEventListener("pointerdown", (ev) => { down = [ev.offsetX, ev.offsetY]; });
$("scene3d").addEventListener("pointerup", (ev) => {
  if (!down || !page.view || Math.hypot(ev.offsetX - down[0], ev.offsetY - down[1]) > 4) return;
  const name = page.view.pick(ev.offsetX, ev.offsetY);
  if (name) { page.view.cameras.target = name; setMode("follow"); }
});
