"""Reaching Debian's ROS 1 from simatch's Python, and the message packages ROS tools need.

**rospy in the bridge process.** Debian's ROS 1 (``python3-rospy`` and friends, ``apt-get``) lives in
``/usr/lib/python3/dist-packages``, built for Debian's Python 3.11. simatch runs in its own virtual
environment (CPython 3.11, 3.12 or 3.13, e.g. pyenv's), whose packages the bridge needs too (Zenoh, MuJoCo for
an embedded run, numpy 2). rospy, genpy and rosgraph are pure Python and import under all three; Debian's few
C extensions (roslz4, netifaces, Cryptodome) are built for CPython 3.11's ABI and load only under 3.11; what
the bridge does with rospy reaches none of them (its tests pass under 3.13; simatch writes bags with rosbags).
`use_rospy` therefore *appends* Debian's folder to ``sys.path``, after the venv's site-packages, and only in the
process that bridges (``simatch ros1``, or ``simatch run --ros1``): the venv's own packages keep precedence, and
Debian's fill in only what the venv lacks (rospy, genpy, rosgraph, yaml...). Nothing is installed into the
venv, and no other simatch process sees Debian's packages. One exception: ROS *message* packages. ROS 2's
wheels (the ``ros2`` extra) put packages of the same names into the venv (``std_msgs``, ``geometry_msgs``,
``rosgraph_msgs``: ROS 2's, without ROS 1's ``rosgraph_msgs/Log`` that rospy imports), so Debian's message
packages are put *before* the venv's, through a folder of links to them alone (`_ros1_messages_first`).

**Message packages.** ``share/`` holds the ROS packages simatch speaks (``nubot_common``, ``gazebo_msgs``:
``package.xml`` and ``.msg`` files) and the example team (``simatch_demo``). `workspace` copies them into a
cache folder and generates their Python classes there with Debian's genpy (``genmsg_py.py``, as catkin
would), once per content: ROS tools find the packages through ``ROS_PACKAGE_PATH`` (``rosmsg``,
``roslaunch``) and import the classes through ``PYTHONPATH`` (``rostopic echo``); `environment` gives
those variables, and ``simatch ros1 --print-env`` prints them for a shell.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

from ..errors import UsageError

#: where Debian installs ROS 1's Python packages (python3-rospy, python3-genpy, ...)
DIST_PACKAGES = Path("/usr/lib/python3/dist-packages")
#: Debian's interpreter (genpy's generator runs under it) and the standard message folders
SYSTEM_PYTHON = Path("/usr/bin/python3")
GENMSG_PY = Path("/usr/lib/genpy/genmsg_py.py")
SYSTEM_SHARE = Path("/usr/share")
#: the ROS packages shipped in share/: message packages (classes generated) and the example team
SHARE = Path(__file__).resolve().parent / "share"
MESSAGE_PACKAGES = ("nubot_common", "gazebo_msgs")
#: message packages of Debian the shipped ones depend on
DEPENDS = ("std_msgs", "geometry_msgs")
INSTALL_HINT = (
    "Debian's ROS 1 is needed: apt-get install ros-core python3-rospy python3-rostopic python3-rosbag "
    "ros-std-msgs ros-geometry-msgs (scripts/install-system-deps.sh installs them)"
)


class RosUnavailable(UsageError):
    """ROS 1 is not installed, or the master cannot be reached: a one-line reason."""


def use_rospy() -> None:
    """Make ``import rospy`` and the shipped message packages work in this process (see the module's text)."""
    try:
        import rospy  # noqa: F401  (a ROS environment already set up, e.g. a sourced workspace)
    except ImportError:
        if not (DIST_PACKAGES / "rospy").is_dir():
            raise RosUnavailable(f"rospy is not installed. {INSTALL_HINT}") from None
        if str(DIST_PACKAGES) not in sys.path:
            sys.path.append(str(DIST_PACKAGES))
        _ros1_messages_first()
    python = str(workspace() / "python")
    if python not in sys.path:
        sys.path.append(python)  # after any nubot_common of the user's own workspace (the same md5sums)
    try:
        import rospy  # noqa: F401,F811
    except ImportError as exc:
        raise RosUnavailable(f"rospy does not import ({exc}). {INSTALL_HINT}") from None


def _ros1_messages_first() -> None:
    """Debian's ROS 1 message packages (``*_msgs``, ``*_srvs``) ahead of ROS 2's packages of the same names in
    the venv: a folder of links to them alone goes first on ``sys.path`` (not Debian's whole folder, whose
    numpy and yaml would shadow the venv's)."""
    names = sorted(p.name for p in DIST_PACKAGES.iterdir() if p.is_dir() and p.name.endswith(("_msgs", "_srvs")))
    if not names:
        return
    folder = cache_root() / ("ros1-messages-" + hashlib.sha256("\0".join(names).encode()).hexdigest()[:12])
    if not folder.is_dir():
        folder.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=".ros1-messages-", dir=folder.parent))
        for name in names:
            (tmp / name).symlink_to(DIST_PACKAGES / name)
        try:
            tmp.rename(folder)
        except OSError:  # another process made it meanwhile
            shutil.rmtree(tmp, ignore_errors=True)
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
    for name in names:  # a ROS 2 package of that name imported already would stay in the way
        for mod in [m for m in sys.modules if m == name or m.startswith(name + ".")]:
            del sys.modules[mod]


def _digest() -> str:
    h = hashlib.sha256()
    for path in sorted(SHARE.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            h.update(str(path.relative_to(SHARE)).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:16]


def cache_root() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "simatch" / "ros1"


def workspace() -> Path:
    """The folder holding ``share/`` (ROS packages) and ``python/`` (their generated message classes), made
    once per content of the shipped packages (several processes may race to make it: one wins)."""
    override = os.environ.get("SIMATCH_ROS1_WORKSPACE")
    target = Path(override) if override else cache_root() / _digest()
    if (target / "complete").exists():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".build-", dir=target.parent))
    try:
        _build(tmp)
        try:
            os.rename(tmp, target)
        except OSError:  # somebody else finished first (or an old incomplete one is there)
            if not (target / "complete").exists():
                shutil.rmtree(target, ignore_errors=True)
                os.rename(tmp, target)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return target


def _build(out: Path) -> None:
    share = out / "share"
    shutil.copytree(SHARE, share, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    for path in share.rglob("*"):  # roslaunch starts only executable nodes (package data loses the bit)
        if path.is_file() and path.parent.name == "nodes":
            path.chmod(path.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    if not GENMSG_PY.exists() or not SYSTEM_PYTHON.exists():
        raise RosUnavailable(f"genpy's message generator ({GENMSG_PY}) is missing. {INSTALL_HINT}")
    includes = [f"{pkg}:{share / pkg / 'msg'}" for pkg in MESSAGE_PACKAGES]
    includes += [f"{pkg}:{SYSTEM_SHARE / pkg / 'msg'}" for pkg in DEPENDS]
    for pkg in MESSAGE_PACKAGES:
        dest = out / "python" / pkg / "msg"
        dest.mkdir(parents=True)
        (dest.parent / "__init__.py").write_text("")
        files = sorted(str(f) for f in (share / pkg / "msg").glob("*.msg"))
        args = [str(SYSTEM_PYTHON), str(GENMSG_PY), "-p", pkg, "-o", str(dest)]
        for inc in includes:
            args += ["-I", inc]
        for extra in ([*files], ["--initpy"]):
            done = subprocess.run([*args, *extra], capture_output=True, text=True, timeout=120)
            if done.returncode != 0:
                raise RosUnavailable(f"generating the {pkg} messages failed: {done.stderr.strip()[-300:]}")
    (out / "complete").write_text("")


def environment(base: dict[str, str] | None = None, master: str | None = None) -> dict[str, str]:
    """Environment variables for ROS tools and nodes that use the shipped packages (``rosmsg``,
    ``rostopic``, ``roslaunch simatch_demo ...``): ``base`` (default: this process's) with the packages
    on ``ROS_PACKAGE_PATH`` and their classes on ``PYTHONPATH``, and ``ROS_MASTER_URI`` if given."""
    env = dict(os.environ if base is None else base)
    ws = workspace()
    env["ROS_PACKAGE_PATH"] = _join(str(ws / "share"), env.get("ROS_PACKAGE_PATH"))
    env["PYTHONPATH"] = _join(env.get("PYTHONPATH"), str(ws / "python"))
    if master:
        env["ROS_MASTER_URI"] = master
    return env


def _join(*parts: str | None) -> str:
    seen: list[str] = []
    for part in parts:
        for item in (part or "").split(os.pathsep):
            if item and item not in seen:
                seen.append(item)
    return os.pathsep.join(seen)


def shell_exports(master: str | None = None) -> str:
    """The ``export`` lines that set up a shell for the shipped packages (``eval "$(simatch ros1
    --print-env)"``)."""
    env = environment(master=master)
    keys = ["ROS_PACKAGE_PATH", "PYTHONPATH"] + (["ROS_MASTER_URI"] if master else [])
    return "\n".join(f"export {k}={_quote(env[k])}" for k in keys)


def _quote(text: str) -> str:
    return "'" + text.replace("'", "'\\''") + "'"
