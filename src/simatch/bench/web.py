"""Web UI benchmark: frames per second that several viewers receive from a live msl_5v5 run with ten
moving robots, and what serving them costs (CPU seconds per wall second, the simulation included), for
the 2D pages and for the 3D view.

The viewers are WebSocket clients in a thread of this process, so the figure is what the server delivers,
without a browser's drawing time: first four 2D pages (two coach pages, the referee console and a replay
page: ``web_*``), then, in a run of its own, four 3D views (``web3d_*``), one of which looks back over the
run (its own timeline, as when a viewer pauses or seeks) while three follow the live picture.
"""

from __future__ import annotations

import asyncio
import threading
import time

DEFAULT_SECONDS = 10.0
PAGES_2D = ["cyan coach", "magenta coach", "referee", "replay"]
PAGES_3D = ["3d view", "3d view", "3d view", "3d view"]


def run(seconds: float | None = None) -> dict:
    seconds = seconds or DEFAULT_SECONDS
    out = _measure(PAGES_2D, seconds, "web")
    out.update(_measure(PAGES_3D, seconds, "web3d", looking_back=1))
    return out


def _measure(labels: list[str], seconds: float, prefix: str, looking_back: int = 0) -> dict:
    """Serve ``labels`` (page labels, repeated for several viewers of one page) for ``seconds`` of a run paced at
    real time; the first ``looking_back`` of them ask for a timeline of their own (a seek back 2 s)."""
    import aiohttp

    from ..simulation import Simulation
    from ..web.live import LiveView

    sim = Simulation("msl_5v5", seed=0)
    view = LiveView(sim, port=0).start()
    counts = [0] * len(labels)
    sizes: list[int] = []
    stop = threading.Event()

    async def watch(session, k, label):
        grant = next(g for g in view.access.tokens if g.label == label)
        base = view.server.base_url.replace("http://", "ws://")
        async with session.ws_connect(f"{base}/ws?token={view.access.tokens[grant]}") as ws:
            asked = k >= looking_back
            while not stop.is_set():
                try:
                    msg = await ws.receive(timeout=0.5)
                except TimeoutError:
                    continue
                if msg.type != aiohttp.WSMsgType.TEXT:
                    return
                if msg.data.startswith('{"type":"frame"'):
                    counts[k] += 1
                    sizes.append(len(msg.data))
                    if not asked and sim.time > 2.5:
                        await ws.send_json({"type": "timeline", "action": "seek", "value": sim.time - 2.0})
                        asked = True

    async def viewers():
        async with aiohttp.ClientSession() as session:
            await asyncio.gather(*(watch(session, k, label) for k, label in enumerate(labels)))

    thread = threading.Thread(target=lambda: asyncio.run(viewers()), daemon=True)
    try:
        for coach in sim.coaches.values():
            coach.start_play()
        thread.start()
        view.wait_for_viewer(10.0)
        live = sum(1 for label in labels if label != "replay")
        while view.server.live_viewers < live:
            time.sleep(0.05)
        counts[:] = [0] * len(labels)
        sizes.clear()
        wall0, cpu0, sim0 = time.perf_counter(), time.process_time(), sim.time

        def keep_moving(t: float) -> None:
            """Every two seconds push the robots off their start poses, so that they drive back."""
            if round(t * 10) % 20 == 0:
                for name, s in sim.model_states().items():
                    if name != "ball":
                        sim.set_model_state(name, x=s.x, y=-s.y if abs(s.y) > 0.5 else s.y + 2.0)

        sim.run(seconds=seconds, progress=keep_moving)  # one call: paced at real time as `run --view` is
        wall = time.perf_counter() - wall0
        cpu = time.process_time() - cpu0
        fps = [n / wall for n in counts]
        return {
            f"{prefix}_viewers": len(labels),
            f"{prefix}_fps_min": round(min(fps), 1),
            f"{prefix}_fps_mean": round(sum(fps) / len(fps), 1),
            f"{prefix}_frame_bytes_mean": round(sum(sizes) / max(1, len(sizes))),
            f"{prefix}_sim_rtf_while_viewed": round((sim.time - sim0) / wall, 3),
            f"{prefix}_cpu_per_wall_s": round(cpu / wall, 3),
        }
    finally:
        stop.set()
        thread.join(5.0)
        view.close()
        sim.close()
