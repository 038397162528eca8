"""``simatch run --view`` and ``simatch serve`` as a user runs them: real processes, a real WebSocket."""

from __future__ import annotations

import asyncio
import concurrent.futures
import json
import os
import re
import subprocess
import sys
import time

import aiohttp
import pytest

URL = re.compile(r"^\s+(?P<label>[a-z0-9 ]+?)\s+(?P<url>http://\S+)$")


def _start(*argv: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "simatch", *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def _urls(proc: subprocess.Popen, timeout: float = 60.0, lines: list | None = None) -> dict[str, str]:
    """The page addresses the command prints on stderr (read until the waiting line; ``lines`` gets them all)."""
    urls: dict[str, str] = {}
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        if lines is not None:
            lines.append(line.rstrip("\n"))
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
        assert set(urls) == {"cyan coach", "magenta coach", "referee", "replay", "3d view"}
        assert all(u.startswith("http://127.0.0.1:") for u in urls.values()), "loopback by default"
        assert len({u.split("token=")[1] for u in urls.values()}) == 5, "one token per page"
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


def test_open_hands_the_referee_console_to_the_users_browser(tmp_path, browser):
    """`--open` opens the referee console with Python's webbrowser, which runs $BROWSER here: a stand-in that
    notes the address; the address then opens in real chromium as a user's browser would, and the run plays."""
    noted, proc = _with_stand_in_browser(tmp_path, "--duration", "1", "--open")
    printed: list[str] = []
    try:
        urls = _urls(proc, lines=printed)
        _wait_noted(noted)
        assert noted.read_text().split() == [urls["referee"]], "the referee console, once"
        page = browser.new_page()
        page.goto(noted.read_text().strip())
        page.wait_for_function("window.simatch && window.simatch.frame && window.simatch.frame.status === 'ended'")
        assert page.evaluate("window.simatch.hello.role") == "referee"
        page.close()
        out, err = _finish(proc)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert json.loads(out)["sim_seconds"] == pytest.approx(1.0)
    # the addresses stand out: a rule above and below, the console first
    rules = [i for i, line in enumerate(printed) if line == "-" * 79]
    assert len(rules) == 2 and printed[rules[0] - 1] == ""
    block = printed[rules[0] + 1 : rules[1]]
    assert block[2].split()[0] == "referee" and len(block) == 7 and "--open opens" not in " ".join(block)


def test_open_3d_hands_the_3d_view_to_the_users_browser(tmp_path):
    noted, proc = _with_stand_in_browser(tmp_path, "--duration", "0.2", "--open-3d", "--view-wait", "3")
    try:
        urls = _urls(proc)
        _wait_noted(noted)
        assert noted.read_text().split() == [urls["3d view"]], "the 3D view, once"
        _finish(proc)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0


def _with_stand_in_browser(tmp_path, *options: str):
    """``simatch run msl_5v5 --view`` with ``options``, its $BROWSER a stand-in that notes the address it is given
    in the file returned (with the process)."""
    noted = tmp_path / "opened.txt"
    stand_in = tmp_path / "browser.sh"
    stand_in.write_text(f'#!/bin/sh\necho "$1" >> {noted}\n')
    stand_in.chmod(0o755)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["BROWSER"] = str(stand_in)
    proc = subprocess.Popen(
        [sys.executable, "-m", "simatch", "run", "msl_5v5", "--view", *options]
        + ["--view-port", "0", "--json", "--quiet"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    return noted, proc


def _wait_noted(noted, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while not (noted.exists() and noted.read_text().strip()) and time.monotonic() < deadline:
        time.sleep(0.1)


def test_open_without_a_browser_says_so_and_the_run_goes_on():
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "BROWSER")}
    proc = subprocess.run(
        [sys.executable, "-m", "simatch", "run", "msl_5v5", "--duration", "0.2", "--view", "--open"]
        + ["--view-port", "0", "--view-wait", "0", "--json"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert "no graphical browser here" in proc.stderr and "/referee?token=" in proc.stderr
    bad = subprocess.run(
        [sys.executable, "-m", "simatch", "run", "msl_5v5", "--open"], capture_output=True, text=True, timeout=60
    )
    assert bad.returncode == 2 and "it goes with --view" in bad.stderr
