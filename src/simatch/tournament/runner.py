"""Where a tournament's matches run: Ray (`RayPool`), or a plain loop in this process (`PlainLoop`).

Both have ``map(jobs)``, a generator of ``(job, outcome)`` in the order matches finish, so the driver stores
each result as soon as it comes back.

`RayPool` starts a local Ray instance (every core of this machine, no dashboard, a small object store) or
joins a running cluster (``address``; inside ``ray job submit`` the job's own cluster). Each match is a task
(`simatch.tournament.match.play_match`, one CPU). The pool keeps as many matches in flight as there are
worker slots — the cluster's CPUs, or ``workers`` — and hands out the next one as soon as one finishes, so a
time limit counts from a match's start, and an interrupted tournament has at most that many matches lost.

* a task whose worker process dies (killed, out of memory) is retried once by Ray; a second death is
  recorded as ``crashed`` (the next run of the command plays it again);
* a match past its time limit is stopped in its worker (`match.MatchTimeout`); if its code never gives the
  worker back (a loop in compiled code), the pool ends that worker after `KILL_GRACE` more seconds and
  records the match as ``timeout``;
* Ctrl-C (or SIGTERM) in the driver stops the matches in flight (a local instance is shut down with its
  workers; on a joined cluster they are cancelled): they are not recorded, and are played by the next run
  of the command.
"""

from __future__ import annotations

import collections
import datetime
import logging
import os
import sys
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

from .. import version
from ..errors import UsageError
from .match import play_match

log = logging.getLogger(__name__)

KILL_GRACE = 60.0  # [s] after a match's time limit before its worker is ended from outside
LOCAL_OBJECT_STORE = 128 * 1024 * 1024  # [bytes] results are small: no need for Ray's default (30 % of RAM)

# Ray's settings for the local instance the command starts (``_system_config``, read by the GCS and the raylet;
# a cluster joined with --address keeps its own). Each match is a long CPU-bound task that nobody watches
# through Ray's dashboard, so Ray's bookkeeping for observability only costs CPU beside the matches (measured
# by `simatch bench --only tournament`, docs/tournament.md "Measured"):
LOCAL_SYSTEM_CONFIG = {
    # Ray lowers its workers' priority by 15 (to keep its own processes responsive); here the workers are the
    # work, so they run at the command's own priority (under `nice`, as nice as the command; under load, as
    # fast as a plain loop would play the same matches).
    "worker_niceness": 0,
    # metrics, task events and the timeline feed the dashboard and the state API, which are not started
    "enable_metrics_collection": False,
    "task_events_report_interval_ms": 0,
    "enable_timeline": False,
    "event_stats": False,
    "emit_main_service_metrics": False,
    "debug_dump_period_milliseconds": 0,  # the raylet's debug_state.txt every 10 s
    # periodic checks made ten times a second by default; once a second is plenty for matches of minutes
    "memory_monitor_refresh_ms": 1000,
    "raylet_report_resources_period_milliseconds": 1000,
    "kill_idle_workers_interval_ms": 1000,
    "local_fs_monitor_interval_ms": 1000,
}
# Ray's log monitor looks for new log files (a glob of the log folder) ten times a second; the workers' output
# is not forwarded here (log_to_driver=False), so once every 5 s is enough (environment of the processes the
# local instance starts).
LOCAL_ENVIRONMENT = {"RAY_LOG_MONITOR_MANY_FILES_THRESHOLD": "0", "LOG_NAME_UPDATE_INTERVAL_S": "5"}


class PlainLoop:
    """The matches one after another in this process (no Ray): for a plug-in's first test, and the measure of
    what Ray costs (`simatch bench --only tournament`)."""

    slots = 1
    description = "plain loop in this process"

    def map(self, jobs: Iterable[dict]) -> Iterator[tuple[dict, dict]]:
        for job in jobs:
            yield job, play_match(job)

    def close(self) -> None:
        pass


class RayPool:
    def __init__(
        self,
        address: str | None = None,
        workers: int | None = None,
        paths: Iterable[str] = (),
        kill_grace: float = KILL_GRACE,
    ):
        joining = bool(address or os.environ.get("RAY_ADDRESS"))
        if joining:
            _token_auth_if_configured()
        elif "RAY_AUTH_MODE" not in os.environ:
            _token_auth()  # a local instance: Ray's default, chosen explicitly (else Ray warns that it chose it)
        try:
            import ray
        except ImportError:
            raise UsageError(
                "simatch tournament runs its matches on Ray, which is not installed: "
                "pip install 'simatch[tournament]' (or give --no-ray to play them one by one here)"
            ) from None
        self.ray = ray
        self.kill_grace = kill_grace
        if workers is not None and workers < 1:
            raise UsageError(f"--workers must be at least 1, got {workers}")
        _export_paths(paths)
        self.started = False
        options = dict(log_to_driver=False, logging_level=logging.WARNING, configure_logging=True)
        try:
            if joining:
                ray.init(address=address or None, **options)
                where = f"Ray cluster at {address or os.environ['RAY_ADDRESS']}"
            else:
                cpus = workers or os.cpu_count() or 1
                for key, value in LOCAL_ENVIRONMENT.items():
                    os.environ.setdefault(key, value)
                ray.init(
                    address="local",  # a new instance, never one that `ray start` left on this machine
                    num_cpus=cpus,
                    include_dashboard=False,
                    object_store_memory=LOCAL_OBJECT_STORE,
                    _system_config=LOCAL_SYSTEM_CONFIG,
                    **options,
                )
                self.started = True
                where = f"local Ray instance ({cpus} CPU{'s' if cpus > 1 else ''})"
        except (ConnectionError, RuntimeError, ValueError) as exc:
            raise UsageError(f"cannot start or join Ray{f' at {address}' if address else ''}: {exc}") from None
        cluster = int(ray.cluster_resources().get("CPU", 1))
        self.slots = max(1, min(workers, cluster) if workers else cluster)
        self.description = f"{where}, {self.slots} match{'es' if self.slots > 1 else ''} at once"
        self._remote = ray.remote(num_cpus=1, max_retries=1, retry_exceptions=False)(play_match)

    def map(self, jobs: Iterable[dict]) -> Iterator[tuple[dict, dict]]:
        ray = self.ray
        pending = collections.deque(jobs)
        inflight: dict = {}  # ref -> (job, submitted at)
        try:
            while pending or inflight:
                while pending and len(inflight) < self.slots:
                    job = pending.popleft()
                    inflight[self._remote.remote(job)] = (job, time.monotonic())
                ready, _ = ray.wait(list(inflight), num_returns=1, timeout=0.5)
                for ref in ready:
                    job, _ = inflight.pop(ref)
                    outcome = self._get(ref, job)
                    if outcome is not None:
                        yield job, outcome
                now = time.monotonic()
                for ref, (job, since) in list(inflight.items()):
                    limit = job.get("timeout")
                    if limit and now - since > limit + self.kill_grace:
                        ray.cancel(ref, force=True)
                        inflight.pop(ref)
                        yield (
                            job,
                            _failed(
                                job,
                                "timeout",
                                f"the match ran longer than its limit of {limit:g} s of wall time and did not stop; "
                                f"its worker was ended after {now - since:.0f} s",
                                now - since,
                            ),
                        )
        finally:
            # Interrupted (Ctrl-C, SIGTERM) or left early: the matches in flight stop now. A local instance this
            # pool started is shut down with its workers rather than each match force-cancelled: Ray 2.60's task
            # manager can fail its own check (``CompletePendingTask``) and end this process with status 1 when a
            # force-cancel crosses the reply of a task that has just finished (seen once in a CI run, after the
            # results were stored). On a cluster it joined, the matches are cancelled.
            if inflight and self.started:
                self.close()
            else:
                for ref in inflight:
                    try:
                        ray.cancel(ref, force=True)
                    except Exception:  # the cluster may be gone already
                        pass

    def _get(self, ref, job: dict) -> dict | None:
        ray = self.ray
        try:
            return ray.get(ref)
        except ray.exceptions.TaskCancelledError:
            return None
        except ray.exceptions.RayTaskError as exc:
            cause = getattr(exc, "cause", None)
            if isinstance(cause, (KeyboardInterrupt, SystemExit)):
                return None  # the worker was interrupted: not a verdict on the match, play it again
            return _failed(job, "error", f"{type(cause or exc).__name__}: {cause or exc}")
        except ray.exceptions.RayError as exc:  # the worker process died (twice: Ray retried once)
            text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            return _failed(job, "crashed", f"{type(exc).__name__}: {text}")

    def close(self) -> None:
        if self.started:
            self.ray.shutdown()
            self.started = False


def _failed(job: dict, status: str, error: str, wall: float = 0.0) -> dict:
    home, away = job["colours"]
    return {
        "row": {
            "match_id": job["match_id"],
            "seed": job["seed"],
            "home_colour": home,
            "away_colour": away,
            "status": status,
            "error": error,
            "wall_seconds": round(wall, 3),
            "worker": "",
            "simatch_version": version(),
            "finished_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        },
        "analysis": None,
    }


def _token_auth_if_configured() -> None:
    """Send this machine's Ray token to a cluster, as ``ray start`` and a local ``ray.init`` use it when one is
    there (``ray.init(address=...)`` does not by itself): RAY_AUTH_MODE, when set, decides."""
    if "RAY_AUTH_MODE" in os.environ:
        return
    if os.environ.get("RAY_AUTH_TOKEN") or (Path.home() / ".ray" / "auth_token").is_file():
        _token_auth()


def _token_auth() -> None:
    """Token authentication for this process and the ones it starts (a new local instance makes its token)."""
    os.environ["RAY_AUTH_MODE"] = "token"
    if "ray" in sys.modules:  # Ray reads its settings when imported: read them again
        try:
            sys.modules["ray"]._raylet.Config.initialize("")
        except AttributeError:
            pass


def _export_paths(paths: Iterable[str]) -> None:
    """Put the folders the plug-ins were imported from on the PYTHONPATH of the processes Ray starts here
    (a local instance inherits the driver's environment), as absolute paths."""
    extra = [str(Path(p).resolve()) for p in paths if p]
    current = [str(Path(p).resolve()) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    merged = list(dict.fromkeys(current + extra))
    if merged:
        os.environ["PYTHONPATH"] = os.pathsep.join(merged)


def plugin_paths(modules: Iterable[str]) -> list[str]:
    """The sys.path folders the given modules were imported from (for workers started from here)."""
    out = []
    for name in modules:
        mod = sys.modules.get(name)
        file = getattr(mod, "__file__", None)
        if not file:
            continue
        depth = len(name.split(".")) - (0 if Path(file).name == "__init__.py" else 1)
        root = Path(file).resolve().parents[depth]
        if not any(part in ("site-packages", "dist-packages") for part in root.parts):
            out.append(str(root))
    return list(dict.fromkeys(out))
