"""The web UI draws the new worlds and the drones: real run, real server, Debian's chromium (Playwright)."""

from __future__ import annotations

import math

from tests.web.conftest import shot, wait_frame

RGB = """([x, y]) => {
  const v = window.simatch.view, dpr = window.devicePixelRatio || 1;
  const [px, py] = v.toScreen(x, y);
  const d = v.ctx.getImageData(Math.round(px * dpr), Math.round(py * dpr), 1, 1).data;
  return [d[0], d[1], d[2]];
}"""


def near(rgb, want, tol=40) -> bool:
    return all(abs(a - b) <= tol for a, b in zip(rgb, want))


def test_obstacles_zones_and_drones_with_their_heights_are_drawn(live, open_page):
    sim, view = live("aerial_encirclement", seed=1)
    sim.run(seconds=3.0)  # the drones have taken off
    page = open_page(view.urls["referee"])
    wait_frame(page, sim.time)
    hello = page.evaluate("window.simatch.hello")
    assert hello["field"]["kind"] == "arena"
    field = sim.simulator.field
    assert [o["name"] for o in hello["field"]["obstacles"]] == [o.name for o in field.obstacles]
    drones = {r["name"]: r for r in hello["robots"] if r.get("aerial")}
    assert sorted(drones) == ["cyan/10", "cyan/11", "cyan/12"] and drones["cyan/10"]["model"] == "quadrotor"
    frame = page.evaluate("window.simatch.frame")
    states = sim.model_states()
    for r in frame["robots"]:
        if r["name"] in drones:
            assert abs(r["z"] - states[r["name"]].z) < 0.05 and r["z"] > 2.0  # (the frame is a moment old)
        else:
            assert "z" not in r
    # an obstacle is drawn where the world has it (beside its centre, where its height is written)
    for ob in field.obstacles:
        if ob.shape == "cylinder":
            x, y = ob.x, ob.y + 0.7 * ob.radius  # above the centre on the screen, clear of the text
        else:  # along whichever of the box's axes is nearer the screen's vertical
            c, s = math.cos(ob.yaw), math.sin(ob.yaw)
            ax, ay, half = (-s, c, ob.half_y) if abs(c) >= abs(s) else (c, s, ob.half_x)
            x, y = ob.x + 0.7 * half * ax, ob.y + 0.7 * half * ay
        assert near(page.evaluate(RGB, [x, y]), (58, 62, 70)), ob.name
    # a drone: its rotor discs in the team's colour, round its centre along the arms
    s = states["cyan/11"]
    page.wait_for_function("t => window.simatch.frame.t >= t", arg=round(sim.time - 0.02, 3))
    scale = page.evaluate("window.simatch.view.scale")
    arm = max(7.0, 0.0628 * scale) * (1 + min(s.z, 6) * 0.08) / scale  # as simatch.js draws it [m]
    hits = 0
    for a in (math.pi / 4, 3 * math.pi / 4, -3 * math.pi / 4, -math.pi / 4):
        rgb = page.evaluate(RGB, [s.x + arm * math.cos(s.yaw + a), s.y + arm * math.sin(s.yaw + a)])
        hits += near(rgb, (0x19, 0xC6, 0xDA))
    assert hits >= 3
    shot(page, "aerial_encirclement")


def test_the_coach_page_shows_its_drones_heights(live, open_page):
    sim, view = live("pursuit_evasion_3d", seed=1)
    sim.run(seconds=1.0)
    page = open_page(view.urls["cyan coach"])
    wait_frame(page, sim.time)
    robots = page.evaluate("window.simatch.frame.robots")
    assert all(r["z"] > 1.0 for r in robots)
    seen = page.evaluate("window.simatch.frame.obstacles")
    assert any(len(o) == 4 and o[3] > 1.0 for lst in seen.values() for o in lst)  # the evader, with its height
    shot(page, "pursuit_coach")
