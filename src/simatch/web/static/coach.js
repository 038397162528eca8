// The coach machine of one team (paper section V-A): command area, display area, status area.
import {
  EventLog, FieldView, attackArrow, clock, gameClock, fmt, opponentColor, setPieceButtons, startPage, teamColor, toast,
  withAlpha,
} from "/static/simatch.js";

const $ = (id) => document.getElementById(id);
const page = { hello: null, view: null, frame: null, test: { mode: "move", point: null } };
const log = new EventLog($("events"), 200);

startPage(page, {
  onHello(h) {
    page.hello = h;
    document.title = `simatch coach · ${h.team}`;
    $("team").textContent = h.team;
    $("team").style.background = teamColor(h, h.team);
    $("scene").textContent = h.scene;
    const ids = h.teams.find((t) => t.name === h.team).ids;
    for (const sel of [$("trobot"), $("treceiver")]) sel.replaceChildren(...ids.map((i) => new Option(`#${i}`, i)));
    if (ids.length > 1) $("treceiver").value = ids[1];
    $("obsof").replaceChildren(new Option("all", "all"), new Option("none", "none"), ...ids.map((i) => new Option(`#${i}`, i)));
    if (!page.view) {
      page.view = new FieldView($("field"), h, { obstacles: "all" });
      page.view.canvas.addEventListener("click", (ev) => choosePoint(page.view.eventToWorld(ev)));
    } else {
      page.view.hello = h;
    }
    // soccer's set pieces and the test modes only where the game has them (not in an encirclement, a flight test)
    for (const el of document.querySelectorAll(".soccer")) el.hidden = h.set_pieces === false;
    page.commands = Boolean(h.capabilities && h.capabilities.commands);
    document.querySelectorAll(".command button, .command input, .command select").forEach((el) => { el.disabled = !page.commands; });
    $("cmdnote").textContent = page.commands ? "" : !h.capabilities ? "a recording: this page watches, nothing can be commanded"
      : h.capabilities.referee ? "the referee gives the commands in this run: this page watches"
      : "the judge gives the commands in this run: this page watches";
    legend(h);
    runStatus(h.status);
  },
  render,
  onEvents: (m) => log.update(m),
});

const send = page.send;

// What the colours on the field mean: this team's robots as they perceive themselves, the opponents as they
// perceive them, the ball (seen by the robot nearest to it), pass lines.
function legend(h) {
  const key = (swatch, text) => {
    const k = document.createElement("span");
    k.className = "key";
    const s = document.createElement("span");
    s.className = "swatch" + (swatch.line ? " line" : "");
    Object.assign(s.style, swatch.style);
    k.append(s, text);
    return k;
  };
  const ours = teamColor(h, h.team), theirs = opponentColor(h);
  const others = h.teams.filter((t) => t.name !== h.team).map((t) => t.name).join(", ") || "other robots";
  $("legend").replaceChildren(
    key({ style: { background: ours, borderColor: "#0b0f12" } }, `${h.team} (ours)`),
    key({ style: { background: withAlpha(theirs, 0.35), borderColor: theirs } }, `${others} as ${h.team} sees them`),
    key({ style: { background: "#ff9800", borderColor: "#3e2723" } }, "ball"),
    key({ line: true, style: { borderColor: "#ffeb3b" } }, "pass"),
  );
}
function command(cmd) { return send({ type: "command", cmd }); }

// --- command area ----------------------------------------------------------------------------------
$("start").onclick = () => command("STARTROBOT");
$("stop").onclick = () => command("STOPROBOT");
setPieceButtons($("setpieces"));
document.querySelectorAll("[data-cmd]").forEach((b) => { b.onclick = () => command(b.dataset.cmd); });
document.addEventListener("keydown", (ev) => {
  // Space stops the team, always (as the original coach), unless typing in a field
  if (ev.code === "Space" && page.commands && !["INPUT", "SELECT", "TEXTAREA"].includes(document.activeElement.tagName)) {
    ev.preventDefault();
    command("STOPROBOT");
  }
});
$("limits").onclick = () => send({ type: "limits", max_vel: Number($("maxvel").value), max_w: Number($("maxw").value) });

function setMode(mode) {
  page.test.mode = mode;
  document.querySelectorAll("#tmodes button").forEach((b) => b.classList.toggle("on", b.dataset.mode === mode));
  document.querySelectorAll("[data-for]").forEach((el) => { el.style.display = el.dataset.for.split(" ").includes(mode) ? "" : "none"; });
  $("thint").textContent = mode === "catch" ? "the robot catches the ball" : mode === "pass" ? "click the field: where the receiver takes the ball" : mode === "shoot" ? "click the field: where to shoot" : "click the field: where to go";
}
document.querySelectorAll("#tmodes button").forEach((b) => { b.onclick = () => setMode(b.dataset.mode); });
setMode("move");

function choosePoint([x, y]) {
  page.test.point = [x, y];
  page.view.marker = [x, y];
  $("tpoint").textContent = `(${x.toFixed(2)}, ${y.toFixed(2)})`;
}
$("tsend").onclick = () => {
  const m = page.test.mode, p = page.test.point;
  if (m !== "catch" && !p) { toast("choose a point: click the field"); return; }
  const msg = { type: "test", mode: m, robot: Number($("trobot").value), kick: Number($("tkick").value),
                heading: Number($("theading").value) * Math.PI / 180, dribble: $("tdribble").checked, avoid: $("tavoid").checked,
                receiver: Number($("treceiver").value) };
  if (p) { msg.x = p[0]; msg.y = p[1]; }
  send(msg);
};
$("tstop").onclick = () => send({ type: "test", mode: "stop" });

// --- display options ------------------------------------------------------------------------------------
$("obsof").onchange = () => { page.view.options.obstacles = $("obsof").value; };
$("optpass").onchange = () => { page.view.options.passes = $("optpass").checked; };
$("opttrail").onchange = () => { page.view.options.trail = $("opttrail").checked; page.view.trail = []; };
$("opttarget").onchange = () => { page.view.options.targets = $("opttarget").checked; };
$("optflip").onchange = () => { page.view.flip = $("optflip").checked; };

// --- status area ------------------------------------------------------------------------------------------
function runStatus(status) {
  $("runstatus").textContent = status === "ended" ? "run ended" : status === "waiting" ? "waiting to start" : "";
  const banner = $("banner");
  banner.textContent = status === "ended" ? "the run has ended" : "";
  banner.classList.toggle("show", status === "ended");
}

function render(f) {
  $("time").textContent = clock(f.t);
  runStatus(f.status);
  if (f.command) {
    $("mode").textContent = f.command.mode;
    $("mtype").textContent = f.command.type !== f.command.mode ? `(after ${f.command.type})` : "";
  }
  const g = f.game;
  // the way this team attacks on the screen now (the teams change ends at half time)
  const arrow = attackArrow(page.hello, g, page.hello.team, Boolean(page.view && page.view.flip));
  $("gamebox").innerHTML = (g ? `score <b>${g.teams.map((t) => g.score[t]).join(" : ")}</b> · ${g.stage} <b>${clock(gameClock(g, f.t))}</b> · ` : "")
    + `attacks <b id="attacks">${arrow}</b>`;
  const rows = f.robots.map((r) => {
    const tr = document.createElement("tr");
    tr.dataset.robot = r.id;
    const flags = [];
    if (r.holding || r.dribble) flags.push('<span class="flag dribble">dribbling</span>');
    if (r.stuck) flags.push('<span class="flag stuck">stuck</span>');
    if (r.sent_off) flags.push('<span class="flag off">sent off</span>');
    if (r.seen && !r.valid && !r.sent_off) flags.push('<span class="flag off">off field</span>');
    const heading = r.yaw === undefined ? null : r.yaw * 180 / Math.PI;
    tr.innerHTML = `<td>#${r.id}</td><td class="l">${r.role || "–"}</td><td class="l">${r.action || "–"}</td>` +
      `<td>${fmt(r.x)}</td><td>${fmt(r.y)}</td><td>${fmt(heading, 0)}</td><td>${fmt(r.speed)}</td><td>${fmt(r.w)}</td>` +
      `<td>${r.wheels ? r.wheels.map((u) => fmt(u, 1)).join(" ") : "–"}</td><td class="l">${flags.join(" ")}</td>`;
    return tr;
  });
  $("robots").tBodies[0].replaceChildren(...rows);
}
