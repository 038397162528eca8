"""Web UI benchmark: frames per second that several viewers receive from a live msl_5v5 run with ten
moving robots, and what serving them costs (CPU seconds per wall second, the simulation included).

The viewers are WebSocket clients in a thread of this process (two coach pages, the referee console and a
replay page), so the figure is what the server delivers, without a browser's drawing time.
"""

from __future__ import annotations

import asyncio
import threading
import time

DEFAULT_SECONDS = 10.0


def run(seconds: float | None = None) -> dict:
    import aiohttp

    from ..simulation import Simulation
    from ..web.live import LiveView

    seconds = seconds or DEFAULT_SECONDS
    sim = Simulation("msl_5v5", seed=0)
    view = LiveView(sim, port=0).start()
    labels = ["cyan coach", "magenta coach", "referee", "replay"]
    counts = {label: 0 for label in labels}
    sizes: list[int] = []
    stop = threading.Event()

    async def watch(session, label):
        role, _, team = label.partition(" coach") if label.endswith("coach") else (label, "", "")
        token = view.access.token("coach", role) if label.endswith("coach") else view.access.token(label)
        base = view.server.base_url.replace("http://", "ws://")
        async with session.ws_connect(f"{base}/ws?token={token}") as ws:
            while not stop.is_set():
                try:
                    msg = await ws.receive(timeout=0.5)
                except TimeoutError:
                    continue
                if msg.type != aiohttp.WSMsgType.TEXT:
                    return
                if msg.data.startswith('{"type":"frame"'):
                    counts[label] += 1
                    sizes.append(len(msg.data))

    async def viewers():
        async with aiohttp.ClientSession() as session:
            await asyncio.gather(*(watch(session, label) for label in labels))

    thread = threading.Thread(target=lambda: asyncio.run(viewers()), daemon=True)
    try:
        for coach in sim.coaches.values():
            coach.start_play()
        thread.start()
        view.wait_for_viewer(10.0)
        while view.server.live_viewers < 3:
            time.sleep(0.05)
        for k in counts:
            counts[k] = 0
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
        fps = {k: v / wall for k, v in counts.items()}
        return {
            "web_viewers": len(labels),
            "web_fps_min": round(min(fps.values()), 1),
            "web_fps_mean": round(sum(fps.values()) / len(fps), 1),
            "web_frame_bytes_mean": round(sum(sizes) / max(1, len(sizes))),
            "web_sim_rtf_while_viewed": round((sim.time - sim0) / wall, 3),
            "web_cpu_per_wall_s": round(cpu / wall, 3),
        }
    finally:
        stop.set()
        thread.join(5.0)
        view.close()
        sim.close()
