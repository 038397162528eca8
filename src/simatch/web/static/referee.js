// The referee console: both teams, score and clock, the event log with reasons, manual mode.
import { EventLog, FieldView, clock, fmt, setPieceButtons, startPage, teamColor } from "/static/simatch.js";

const $ = (id) => document.getElementById(id);
const page = { hello: null, view: null, frame: null, team: null };
const log = new EventLog($("events"), 500);

startPage(page, {
  onHello(h) {
    page.hello = h;
    $("scene").textContent = h.scene;
    page.team = page.team || h.teams[0].name;
    $("teamsel").replaceChildren(...h.teams.map((t) => {
      const b = document.createElement("button");
      b.textContent = t.name; b.dataset.team = t.name;
      b.style.borderColor = teamColor(h, t.name);
      b.onclick = () => selectTeam(t.name);
      return b;
    }));
    selectTeam(page.team);
    $("sendoff").replaceChildren(...h.teams.map((t) => {
      const div = document.createElement("div");
      div.className = "robots-off";
      for (const id of t.ids) {
        const b = document.createElement("button");
        b.textContent = `${t.name[0].toUpperCase()}${id}`;
        b.title = `send ${t.name}/${id} off, or bring it back`;
        b.dataset.robot = `${t.name}/${id}`;
        b.style.borderColor = teamColor(h, t.name);
        b.onclick = () => send({ type: "send_off", robot: b.dataset.robot, off: !b.classList.contains("off") });
        div.appendChild(b);
      }
      return div;
    }));
    const caps = h.capabilities || {};
    $("auto").disabled = !caps.auto_referee;
    $("auto").textContent = caps.auto_referee ? "on" : "none in this run";
    if (!page.view) {
      page.view = new FieldView($("field"), h);
      dragging(page.view);
    } else page.view.hello = h;
  },
  render,
  onEvents: (m) => log.update(m),
});

const send = page.send;

function selectTeam(team) {
  page.team = team;
  document.querySelectorAll("#teamsel button").forEach((b) => b.classList.toggle("on", b.dataset.team === team));
}

setPieceButtons($("setpieces"));
document.querySelectorAll("[data-cmd]").forEach((b) => {
  b.onclick = () => send({ type: "command", cmd: b.dataset.cmd, team: page.team });
});
$("pause").onclick = () => send({ type: "pause" });
$("start").onclick = () => send({ type: "command", cmd: "STARTROBOT", team: page.team });
$("auto").onclick = () => send({ type: "auto_referee", on: $("auto").textContent !== "on" });
document.addEventListener("keydown", (ev) => {
  if (ev.code === "Space" && !["INPUT", "SELECT", "TEXTAREA"].includes(document.activeElement.tagName)) {
    ev.preventDefault();
    send({ type: "pause" });
  }
});
$("opttrail").onchange = () => { page.view.options.trail = $("opttrail").checked; page.view.trail = []; };
$("optflip").onchange = () => { page.view.flip = $("optflip").checked; };

// Drag the ball to place it: the ball follows the pointer, and is placed where it is dropped.
function dragging(view) {
  const c = view.canvas;
  c.addEventListener("pointerdown", (ev) => {
    const b = page.frame && page.frame.ball;
    if (!b) return;
    const [x, y] = view.eventToWorld(ev);
    if (Math.hypot(x - b.x, y - b.y) > Math.max(0.4, 12 / view.scale)) return;
    view.dragBall = [x, y];
    c.setPointerCapture(ev.pointerId);
  });
  c.addEventListener("pointermove", (ev) => {
    const [x, y] = view.eventToWorld(ev);
    $("ballpos").textContent = `(${x.toFixed(2)}, ${y.toFixed(2)})`;
    if (view.dragBall) view.dragBall = [x, y];
  });
  c.addEventListener("pointerup", () => {
    if (!view.dragBall) return;
    const [x, y] = view.dragBall;
    send({ type: "place_ball", x, y }).finally(() => { setTimeout(() => { view.dragBall = null; }, 150); });
  });
}

function render(f) {
  const h = page.hello;
  const g = f.game;
  $("runstatus").textContent = f.status === "ended" ? "run ended" : "";
  $("banner").textContent = f.status === "ended" ? "the run has ended" : "";
  $("banner").classList.toggle("show", f.status === "ended");
  $("clock").textContent = clock(g ? g.clock : f.t);
  $("stage").textContent = g ? g.stage : "no referee";
  const teams = h.teams.map((t) => t.name);
  const score = (t) => (g && g.score[t] !== undefined ? g.score[t] : 0);
  $("scoreboard").innerHTML = teams.length === 2
    ? `<span style="color:${teamColor(h, teams[0])}">${teams[0]}</span><span class="score" id="score">${score(teams[0])} : ${score(teams[1])}</span><span style="color:${teamColor(h, teams[1])}">${teams[1]}</span>`
    : `<span class="score" id="score">${teams.map(score).join(" : ")}</span>`;
  const cmds = f.commands || {};
  $("command").textContent = g ? `${g.command_name}${g.command_team ? " " + g.command_team : ""}` : teams.map((t) => cmds[t] ? cmds[t].mode : "–").join(" / ");
  $("teams").tBodies[0].replaceChildren(...teams.map((t) => {
    const tr = document.createElement("tr");
    tr.innerHTML = `<td style="color:${teamColor(h, t)}">${t}</td><td>${cmds[t] ? cmds[t].mode : "–"}</td><td>${score(t)}</td><td>${g && g.fouls[t] !== undefined ? g.fouls[t] : "–"}</td>`;
    return tr;
  }));
  const off = new Set(f.sent_off || []);
  document.querySelectorAll("#sendoff button").forEach((b) => b.classList.toggle("off", off.has(b.dataset.robot)));
  const b = f.ball;
  if (b && !page.view.dragBall) $("ballpos").textContent = `ball (${fmt(b.x)}, ${fmt(b.y)}, ${fmt(b.z)})`;
}
