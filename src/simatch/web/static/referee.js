// The referee console: both teams, score and clock, the event log with reasons, manual mode. In a run with
// an automatic referee every button is a request to the referee (its operator interface); without one,
// commands go to both teams' coaches. A recording is shown read-only.
import { EventLog, FieldView, attackArrow, clock, commandText, fmt, gameClock, scoreboard, setPieceButtons, startPage, teamColor } from "/static/simatch.js";

const $ = (id) => document.getElementById(id);
const page = { hello: null, view: null, frame: null, team: null, caps: null };
const log = new EventLog($("events"), 500);

startPage(page, {
  onHello(h) {
    page.hello = h;
    page.caps = h.capabilities;            // null: a recording, nothing can be commanded
    for (const el of document.querySelectorAll(".soccer")) el.hidden = h.set_pieces === false;  // no set pieces here
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
    robotRows(h);
    teamRows(h);
    capabilities(page.caps);
    if (!page.view) {
      page.view = new FieldView($("field"), h);
      dragging(page.view);
    } else page.view.hello = h;
  },
  render,
  onEvents: (m) => log.update(m),
});

const send = page.send;
const can = (what) => Boolean(page.caps && page.caps[what]);

function button(text, cls, title, onclick) {
  const b = document.createElement("button");
  b.textContent = text;
  if (cls) b.className = cls;
  b.title = title;
  b.onclick = onclick;
  return b;
}

// One row per robot: send off / bring back, yellow and red cards (built once; render() updates them).
function robotRows(h) {
  $("robots-table").tBodies[0].replaceChildren(...h.teams.flatMap((t) => t.ids.map((id) => {
    const name = `${t.name}/${id}`;
    const tr = document.createElement("tr");
    tr.dataset.robot = name;
    const who = document.createElement("td");
    who.textContent = name;
    who.style.color = teamColor(h, t.name);
    const cards = document.createElement("td");
    cards.className = "cards";
    const acts = document.createElement("td");
    acts.className = "acts";
    acts.append(
      button("Off", "sendoff", `send ${name} off the field, or bring it back`,
             () => send({ type: "send_off", robot: name, off: !tr.classList.contains("off") })),
      button("Y", "yellow", `yellow card for ${name}`, () => send({ type: "card", robot: name, card: "yellow" })),
      button("R", "red", `red card for ${name}`, () => send({ type: "card", robot: name, card: "red" })));
    tr.append(who, cards, acts);
    return tr;
  })));
}

function teamRows(h) {
  $("teams").tBodies[0].replaceChildren(...h.teams.map((t) => {
    const tr = document.createElement("tr");
    tr.dataset.team = t.name;
    tr.innerHTML = `<td style="color:${teamColor(h, t.name)}">${t.name}</td><td class="cmd">–</td><td class="score">0</td><td class="fouls">–</td><td class="cards">–</td><td></td>`;
    tr.lastChild.append(button("+1", "goal", `award a goal to ${t.name} (a correction the referee logs)`,
                               () => send({ type: "award_goal", team: t.name })));
    return tr;
  }));
}

// Grey out what this run cannot do: without a referee there is no resume, card, goal or automatic judging;
// a recording commands nothing.
function capabilities(caps) {
  const panel = document.querySelector("[aria-label='manual mode']");
  panel.querySelectorAll("button").forEach((b) => { if (!b.closest("#teamsel")) b.disabled = !caps; });
  if (!caps) {
    $("mode-note").textContent = "a recording: nothing can be commanded";
    $("auto").textContent = "–";
    return;
  }
  $("mode-note").textContent = caps.referee ? "the referee's operator: every request goes to the automatic referee"
    : caps.commands ? "no automatic referee: commands go to the coaches"
    : "the judge gives the commands in this run: the console places the ball and sends robots off";
  ["pause", "start"].forEach((id) => { $(id).disabled = !caps.commands; });
  document.querySelectorAll("[data-cmd]").forEach((b) => { b.disabled = !caps.commands; });
  $("resume").disabled = true;               // enabled while the referee's pause holds the game
  $("auto").disabled = !caps.auto_referee;
  $("auto").textContent = caps.auto_referee ? "on" : "none in this run";
  document.querySelectorAll("#robots-table button.yellow, #robots-table button.red").forEach((b) => { b.disabled = !caps.cards; });
  document.querySelectorAll("#teams button.goal").forEach((b) => { b.disabled = !caps.award_goal; });
}

function selectTeam(team) {
  page.team = team;
  document.querySelectorAll("#teamsel button").forEach((b) => b.classList.toggle("on", b.dataset.team === team));
}

setPieceButtons($("setpieces"));
document.querySelectorAll("[data-cmd]").forEach((b) => {
  b.onclick = () => send({ type: "command", cmd: b.dataset.cmd, team: page.team });
});
$("pause").onclick = () => send({ type: "pause" });
$("resume").onclick = () => send({ type: "resume" });
$("start").onclick = () => send({ type: "command", cmd: "STARTROBOT", team: page.team });
$("auto").onclick = () => send({ type: "auto_referee", on: !$("auto").classList.contains("on") });
document.addEventListener("keydown", (ev) => {
  // Space pauses, always (an emergency key: pressing it twice never resumes), unless typing in a field
  if (ev.code === "Space" && page.caps && !["INPUT", "SELECT", "TEXTAREA"].includes(document.activeElement.tagName)) {
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
    if (!b || !can("place_ball")) return;
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
  c.addEventListener("pointerup", (ev) => {
    if (!view.dragBall) return;
    const [x, y] = view.eventToWorld(ev);       // where it is dropped (the last move may not have been seen)
    view.dragBall = [x, y];
    send({ type: "place_ball", x, y }).finally(() => { setTimeout(() => { view.dragBall = null; }, 150); });
  });
}

function render(f) {
  const h = page.hello;
  const g = f.game;
  $("runstatus").textContent = f.status === "ended" ? "run ended" : "";
  $("banner").textContent = f.status === "ended" ? "the run has ended" : "";
  $("banner").classList.toggle("show", f.status === "ended");
  $("clock").textContent = clock(g ? gameClock(g, f.t) : f.t);
  $("stage").textContent = g ? g.stage : "no referee";
  const teams = h.teams.map((t) => t.name);
  const score = (t) => (g && g.score[t] !== undefined ? g.score[t] : 0);
  $("scoreboard").innerHTML = scoreboard(h, g);
  // which way each team attacks on the screen now (the teams change ends at half time)
  $("ends").textContent = teams.map((t) => `${t} ${attackArrow(h, g, t, page.view && page.view.flip)}`).join(" · ");
  const cmds = f.commands || {};
  $("command").textContent = g ? commandText(g) : teams.map((t) => cmds[t] ? cmds[t].mode : "–").join(" / ");
  // the referee's phase: paused by the operator, manual mode (automatic judging off), or the phase of play
  const phase = $("phase");
  phase.textContent = !g ? "" : g.paused ? "paused" : g.phase + (g.manual ? " · manual" : "");
  phase.className = "badge" + (g && g.paused ? " paused" : g && g.manual ? " manual" : "");
  $("reason").textContent = g && g.reason ? `why: ${g.reason}` : "";
  if (page.caps) {
    $("resume").disabled = !(page.caps.resume && g && g.paused);
    if (page.caps.auto_referee && g) {
      $("auto").textContent = g.manual ? "off (manual)" : "on";
      $("auto").classList.toggle("on", !g.manual);
    }
  }
  for (const tr of $("teams").tBodies[0].rows) {
    const t = tr.dataset.team;
    tr.querySelector(".cmd").textContent = cmds[t] ? cmds[t].mode : "–";
    tr.querySelector(".score").textContent = score(t);
    tr.querySelector(".fouls").textContent = g && g.fouls[t] !== undefined ? g.fouls[t] : "–";
    tr.querySelector(".cards").textContent = g ? `${g.yellow_cards[t] || 0}Y ${g.red_cards[t] || 0}R` : "–";
  }
  const off = new Set(f.sent_off || []);
  const cards = f.cards || {};
  for (const tr of $("robots-table").tBodies[0].rows) {
    const name = tr.dataset.robot, isOff = off.has(name), [y, r] = cards[name] || [0, 0];
    tr.classList.toggle("off", isOff);
    tr.querySelector("button.sendoff").textContent = isOff ? "Back" : "Off";
    tr.querySelector(".cards").textContent = (y ? `${y} Y ` : "") + (r ? `${r} R` : "") + (isOff ? " off" : "");
  }
  const b = f.ball;
  if (b && !page.view.dragBall) $("ballpos").textContent = `ball (${fmt(b.x)}, ${fmt(b.y)}, ${fmt(b.z)})`;
}
