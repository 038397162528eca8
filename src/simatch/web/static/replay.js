// The replay page: a timeline to play, pause, change speed and seek through the run.
import { EventLog, FieldView, clock, gameClock, startPage, teamColor } from "/static/simatch.js";

const $ = (id) => document.getElementById(id);
const page = { hello: null, view: null, frame: null, seeking: false };
const log = new EventLog($("events"), 50);

startPage(page, {
  onHello(h) {
    page.hello = h;
    $("scene").textContent = h.source === "recording" ? `${h.scene} · ${h.recording}` : h.scene;
    if (h.source === "recording") {
      $("live").textContent = "Now playing";
      $("live").title = "jump to the moment the live pages show (the recording playing on the bus)";
    }
    if (!page.view) page.view = new FieldView($("field"), h);
    else page.view.hello = h;
  },
  render,
});

function timeline(action, value = 0) { return page.conn.request({ type: "timeline", action, value }).catch(() => {}); }

$("play").onclick = () => timeline(page.frame && page.frame.timeline.playing ? "pause" : "play");
$("speed").onchange = () => timeline("speed", Number($("speed").value));
$("live").onclick = () => { $("speed").value = "1"; timeline("live"); };
$("seek").addEventListener("input", () => { page.seeking = true; timeline("seek", Number($("seek").value)); });
$("seek").addEventListener("change", () => { page.seeking = false; });
document.addEventListener("keydown", (ev) => {
  if (ev.code === "Space" && document.activeElement.tagName !== "SELECT") { ev.preventDefault(); $("play").click(); }
  if (ev.code === "ArrowLeft" || ev.code === "ArrowRight") {
    ev.preventDefault();
    const tl = page.frame && page.frame.timeline;
    if (tl) timeline("seek", tl.t + (ev.code === "ArrowLeft" ? -5 : 5));
  }
});
$("opttrail").onchange = () => { page.view.options.trail = $("opttrail").checked; page.view.trail = []; };
$("optflip").onchange = () => { page.view.flip = $("optflip").checked; };

function render(f) {
  const tl = f.timeline, h = page.hello, g = f.game;
  $("t").textContent = clock(tl.t);
  $("end").textContent = clock(tl.end);
  $("play").textContent = tl.playing ? "Pause" : "Play";
  const seek = $("seek");
  seek.min = tl.start; seek.max = tl.end;
  if (!page.seeking) seek.value = tl.t;
  $("runstatus").textContent = h.source === "recording" ? (tl.complete ? "recording" : "loading the recording…")
    : (tl.complete ? "run complete" : "run in progress");
  $("stage").textContent = g ? `${g.stage} ${clock(gameClock(g, f.t))}` : "–";
  const teams = h.teams.map((t) => t.name);
  const score = (t) => (g && g.score[t] !== undefined ? g.score[t] : 0);
  $("scoreboard").innerHTML = teams.length === 2
    ? `<span style="color:${teamColor(h, teams[0])}">${teams[0]}</span><span class="score">${score(teams[0])} : ${score(teams[1])}</span><span style="color:${teamColor(h, teams[1])}">${teams[1]}</span>` : "";
  log.render(f.events || []);
}
