// A page's own timeline (the replay page, the 3D view): play/pause, the position slider, the speed and the button
// back to the moment the live pages show, with their keys (Space plays or pauses, the arrows seek 5 s). The
// server keeps the position (a "timeline" request per move); `render(tl)` shows the one a frame carries.
import { clock } from "/static/simatch.js";

const $ = (id) => document.getElementById(id);

const CONTROLS = `
  <button id="play" class="big" style="min-width:90px">Pause</button>
  <span><b id="t">0:00.0</b> / <span id="end">0:00.0</span></span>
  <input id="seek" type="range" min="0" max="0" step="0.01" value="0" aria-label="position">
  <label>speed <select id="speed">
    <option value="0.25">¼×</option><option value="0.5">½×</option><option value="1" selected>1×</option>
    <option value="2">2×</option><option value="4">4×</option><option value="8">8×</option><option value="16">16×</option>
  </select></label>
  <button id="live"></button>`;

export class TimelineBar {
  // `container` gets the controls; `live` is the text and title of the button back to the live moment.
  constructor(page, container, live) {
    this.page = page;
    this.seeking = false;
    container.innerHTML = CONTROLS;
    this.label(live);
    $("play").onclick = () => this.send(this.current && this.current.playing ? "pause" : "play");
    $("speed").onchange = () => this.send("speed", Number($("speed").value));
    $("live").onclick = () => { $("speed").value = "1"; this.send("live"); };
    $("seek").addEventListener("input", () => { this.seeking = true; this.send("seek", Number($("seek").value)); });
    $("seek").addEventListener("change", () => { this.seeking = false; });
    document.addEventListener("keydown", (ev) => {
      if (ev.code === "Space" && document.activeElement.tagName !== "SELECT") { ev.preventDefault(); $("play").click(); }
      if (ev.code === "ArrowLeft" || ev.code === "ArrowRight") {
        ev.preventDefault();
        if (this.current) this.send("seek", this.current.t + (ev.code === "ArrowLeft" ? -5 : 5));
      }
    });
  }

  label([text, title]) {
    $("live").textContent = text;
    $("live").title = title;
  }

  send(action, value = 0) {
    return this.page.conn.request({ type: "timeline", action, value }).catch(() => {});
  }

  render(tl) {
    this.current = tl;
    $("t").textContent = clock(tl.t);
    $("end").textContent = clock(tl.end);
    $("play").textContent = tl.playing ? "Pause" : "Play";
    const seek = $("seek");
    seek.min = tl.start; seek.max = tl.end;
    if (!this.seeking) seek.value = tl.t;
  }
}
