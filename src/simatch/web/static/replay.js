// The replay page: a timeline to play, pause, change speed and seek through the run.
import { EventLog, FieldView, clock, gameClock, scoreboard, startPage } from "/static/simatch.js";
import { TimelineBar } from "/static/timeline.js";

const $ = (id) => document.getElementById(id);
const page = { hello: null, view: null, frame: null };
const log = new EventLog($("events"), 50);

const bar = new TimelineBar(page, $("timeline"), ["Latest", "jump to the newest moment"]);

startPage(page, {
  onHello(h) {
    page.hello = h;
    $("scene").textContent = h.source === "recording" ? `${h.scene} · ${h.recording}` : h.scene;
    if (h.source === "recording") bar.label(["Now playing", "jump to the moment the live pages show (the recording playing on the bus)"]);
    if (!page.view) page.view = new FieldView($("field"), h);
    else page.view.hello = h;
  },
  render,
});

$("opttrail").onchange = () => { page.view.options.trail = $("opttrail").checked; page.view.trail = []; };
$("optflip").onchange = () => { page.view.flip = $("optflip").checked; };

function render(f) {
  const tl = f.timeline, h = page.hello, g = f.game;
  bar.render(tl);
  $("runstatus").textContent = h.source === "recording" ? (tl.complete ? "recording" : "loading the recording…")
    : (tl.complete ? "run complete" : "run in progress");
  $("stage").textContent = g ? `${g.stage} ${clock(gameClock(g, f.t))}` : "–";
  $("scoreboard").innerHTML = scoreboard(h, g);
  log.render(f.events || []);
}
