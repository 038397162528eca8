"""``simatch run --view`` and ``simatch serve`` as a user runs them: real processes, a real WebSocket."""

from __future__ import annotations

import asyncio
import concurrent.futures
import json
import re
import subprocess
import sys
import time

import aiohttp
import pytest

URL = re.compile(r"^\s+(?P<label>[a-z ]+?)\s+(?P<url>http://\S+)$")


def _start(*argv: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "simatch", *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def _urls(proc: subprocess.Popen, timeout: float = 60.0) -> dict[str, str]:
    """The page addresses the command prints on stderr (read until the waiting line)."""
    urls: dict[str, str] = {}
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        m = URL.match(line.rstrip("\n"))
        if m:
            urls[m["label"]] = m["url"]
        if "waiting for a page" in line:
            return urls
    raise AssertionError(f"no addresses printed; got {urls}")


async def _watch(url: str, seconds: float) -> list[dict]:
    ws_url = url.replace("http://", "ws://").split("/", 3)
    token = url.split("token=")[1]
    got = []
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(f"{ws_url[0]}//{ws_url[2]}/ws?token={token}") as ws:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                try:
                    msg = await ws.receive(timeout=max(0.05, end - time.monotonic()))
                except TimeoutError:
                    break
                if msg.type != aiohttp.WSMsgType.TEXT:
                    break
                got.append(json.loads(msg.data))
    return got


def _run(coro):
    """``coro`` run to its end on an event loop of its own, in a thread: the session's browser (Playwright's sync
    API) keeps its loop running on this thread once a test has opened it, and asyncio.run refuses to nest."""
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
        return pool.submit(asyncio.run, coro).result()


def _finish(proc: subprocess.Popen, timeout: float = 30.0) -> tuple[str, str]:
    try:
        out, err = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return out, err


@pytest.mark.parametrize(
    "command", [["run", "msl_5v5", "--duration", "1", "--view"], ["serve", "msl_5v5", "--duration", "1"]]
)
def test_a_viewed_run_waits_for_a_page_plays_at_real_time_and_ends_when_the_page_closes(command):
    proc = _start(*command, "--view-port", "0", "--json", "--quiet")
    try:
        urls = _urls(proc)
        assert set(urls) == {"cyan coach", "magenta coach", "referee", "replay"}
        assert all(u.startswith("http://127.0.0.1:") for u in urls.values()), "loopback by default"
        assert len({u.split("token=")[1] for u in urls.values()}) == 4, "one token per page"
        messages = _run(_watch(urls["referee"], 2.5))
        frames = [m for m in messages if m["type"] == "frame"]
        assert messages[0]["type"] == "hello" and messages[0]["role"] == "referee"
        assert frames and frames[-1]["t"] == pytest.approx(1.0, abs=0.05)
        # paced at real time while the page was open: it saw the second of play unfold, not only its end
        assert len({f["t"] for f in frames if f["t"] < 0.95}) >= 15
        assert frames[-1]["status"] == "ended"
        out, err = _finish(proc)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    result = json.loads(out)
    assert result["sim_seconds"] == pytest.approx(1.0)


def test_a_viewed_run_with_no_wait_runs_at_once_and_prints_one_json_object():
    proc = _start("run", "msl_5v5", "--duration", "0.5", "--view", "--view-port", "0", "--view-wait", "0", "--json")
    out, err = _finish(proc, timeout=120)
    assert proc.returncode == 0, err
    assert json.loads(out)["sim_seconds"] == pytest.approx(0.5)
    assert "/referee?token=" in err


def test_a_busy_port_is_a_clear_error():
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        proc = _start("run", "msl_5v5", "--duration", "0.1", "--view", "--view-port", str(port), "--view-wait", "0")
        out, err = _finish(proc, timeout=120)
    assert proc.returncode == 2
    assert f"cannot serve the web UI on 127.0.0.1:{port}" in err and "Traceback" not in err


@pytest.mark.parametrize(
    "argv, why",
    [
        (["serve", "/nowhere/match.mcap"], "no such recording"),
        (["serve", "msl_5v5", "--speed", "2"], "--speed is for a recording"),
        (["serve", "match.mcap", "--set", "ball.mass=1"], "--set: a recording is shown as it was recorded"),
    ],
)
def test_serve_refuses_what_does_not_fit_a_scene_or_a_recording(argv, why):
    proc = _start(*argv, "--view-port", "0")
    out, err = _finish(proc, timeout=60)
    assert proc.returncode == 2 and why in err and "Traceback" not in err, err
