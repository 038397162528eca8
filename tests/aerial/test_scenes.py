"""The two aerial scenes' judges as a user reads them: the aerial encirclement's captures (where each target
was caught, where it was stowed), the 3D pursuit's capture and collision counts. Real MuJoCo, the shipped
scenes."""

from __future__ import annotations

import math

import pytest

import simatch


@pytest.mark.slow
def test_the_aerial_encirclement_reports_where_each_target_was_caught_and_stows_it():
    with simatch.Simulation("aerial_encirclement", seed=0) as sim:
        sim.run()
        r = sim.result()["result"]
        states = sim.model_states()
        p = r["prison"]
        assert r["captured"] == r["targets"] == 7 and r["end"] == "all_captured"
        assert r["capture_time_s"] == max(c["t"] for c in r["captures"])
        events = {f"magenta/{e['robot']}": e for e in sim.events if e["type"] == "capture"}
        assert sorted(events) == sorted(c["robot"] for c in r["captures"])
        for c in r["captures"]:
            e = events[c["robot"]]
            # the event is where the target was caught (at the prison's entrance side), the capture record has
            # both that place and the stowed one at the back of the prison, where the target now stands
            assert (e["x"], e["y"]) == pytest.approx(tuple(c["caught_at"]), abs=1e-4)
            assert p["x0"] <= e["x"] <= p["x1"] and p["y0"] <= e["y"] <= p["y1"]
            assert p["x0"] <= c["x"] <= p["x1"] and p["y0"] <= c["y"] <= p["y1"]
            s = states[c["robot"]]
            assert (s.x, s.y) == pytest.approx((c["x"], c["y"]), abs=0.05)
        stowed = [(c["x"], c["y"]) for c in r["captures"]]
        assert min(math.dist(a, b) for i, a in enumerate(stowed) for b in stowed[i + 1 :]) >= 0.5
        # the back of the prison (the +x wall's side) fills first
        assert sum(x >= p["x1"] - 0.5 for x, _ in stowed) >= 5


def test_the_pursuit_judge_counts_collisions_and_ends_at_the_capture():
    with simatch.Simulation("pursuit_evasion_3d", seed=0) as sim:
        for name in ("cyan/1", "cyan/2", "cyan/3"):
            sim.take_control(name)
        sim.run(seconds=0.5)
        assert sim.result()["result"]["collisions"]["total"] == 0
        sim.send_vel("cyan/1", 0.0, 0.0, 0.0, -1.5)  # down to the floor at full descent
        sim.run(seconds=3.0)
        c = sim.result()["result"]["collisions"]
        assert c["by_robot"] == {"cyan/1": 1} and c["by_kind"] == {"floor": 1}, c
        e = sim.model_states()["magenta/1"]
        sim.set_model_state("cyan/2", x=e.x - 0.25, y=e.y, z=e.z, yaw=0.0)  # within 0.35 m of its centre
        sim.run(seconds=1.0)
        assert sim.done
        r = sim.result()["result"]
        assert r["captured"] and r["captured_by"] == "cyan/2" and r["end"] == "captured"
        assert r["capture_time_s"] == pytest.approx(sim.time - sim.dt) and r["closest_m"] <= 0.35
        (cap,) = [ev for ev in sim.events if ev["type"] == "capture"]
        assert cap["team"] == "magenta" and cap["robot"] == 1 and cap["t"] == r["capture_time_s"]
        assert "caught by cyan/2" in cap["detail"]
        frozen = sim.model_states()["magenta/1"]
        sim.step(400)  # the evader is frozen where it was caught (a weld: it settles by micrometres)
        after = sim.model_states()["magenta/1"]
        assert (after.x, after.y, after.z) == pytest.approx((frozen.x, frozen.y, frozen.z), abs=1e-3)
