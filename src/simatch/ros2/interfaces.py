"""simatch's messages (and ``tf2_msgs``) as ROS 2 interface packages, built with ROS 2's own tools.

The ``ros2`` extra installs ROS 2's rosidl generators and ament_cmake as wheels into this Python's prefix (a
venv is an ament prefix: ``share/<pkg>/cmake``, ``include``, ``lib``). `build` runs them on the ``.msg``
files, exactly as ``colcon build`` of an interface package would (cmake, then a C/C++ compiler), and installs
the result into the same prefix: afterwards any ``rclpy`` node of this Python imports
``from simatch_msgs.msg import OmniVisionInfo``, and Fast DDS matches the types by their RIHS01 hashes.

Two packages:

* ``simatch_msgs``: the very ``.msg`` files of `simatch.msgs`. The bus's CDR *is* ROS 2's CDR of these
  definitions, so the bridge forwards the bytes it gets from the run without decoding them.
* ``tf2_msgs``: only ``TFMessage`` (one line: ``geometry_msgs/TransformStamped[] transforms``), which RViz
  and tf2 read on ``/tf``; PyPI has no wheel of ``tf2_msgs``. A type's hash depends only on its own
  definition, so this ``TFMessage`` is the one of every ROS 2 installation (checked in the tests).

The wheels were built in a manylinux image, and their exported CMake targets of the Python typesupport name
that image's Python include folder (``/opt/python/cp311-cp311/...``); the generated CMakeLists drops those
paths (the generators add this Python's own). A build takes a minute or two on two cores; it is done once
per prefix and done again only when a definition changes (a stamp file keeps the hash of the inputs).
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from .. import msgs

#: what is written into each built package's share folder: the hash of its inputs
STAMP = "simatch-interfaces.json"

_TF_MESSAGE = "geometry_msgs/TransformStamped[] transforms\n"


class BuildError(RuntimeError):
    """The interface packages cannot be built here; the message says what is missing."""


@dataclass(frozen=True)
class Package:
    name: str
    messages: dict[str, str]  # name -> .msg text
    depends: tuple[str, ...]
    description: str

    def digest(self) -> str:
        h = hashlib.sha256(self.name.encode())
        for name in sorted(self.messages):
            h.update(b"\0" + name.encode() + b"\0" + self.messages[name].encode())
        h.update(_GENERATOR_VERSION.encode())
        return h.hexdigest()


#: bump to rebuild every prefix (a change of the generated CMakeLists or package.xml)
_GENERATOR_VERSION = "1"


def packages() -> list[Package]:
    folder = resources.files(msgs).joinpath(msgs.PACKAGE, "msg")
    simatch_msgs = {
        e.name[:-4]: e.read_text(encoding="utf-8")
        for e in sorted(folder.iterdir(), key=lambda e: e.name)
        if e.name.endswith(".msg")
    }
    return [
        Package("simatch_msgs", simatch_msgs, (), "simatch's messages (simatch.msgs), as a ROS 2 interface package"),
        Package("tf2_msgs", {"TFMessage": _TF_MESSAGE}, ("geometry_msgs",), "tf2_msgs/msg/TFMessage only"),
    ]


def default_prefix() -> Path:
    """Where the packages go: this Python's prefix (a venv), where the ROS 2 wheels are."""
    return Path(sys.prefix)


def _site_packages(prefix: Path) -> Path:
    return prefix / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"


def is_installed(pkg: Package, prefix: Path | None = None) -> bool:
    prefix = prefix or default_prefix()
    stamp = prefix / "share" / pkg.name / STAMP
    try:
        ok = json.loads(stamp.read_text())["digest"] == pkg.digest()
    except (OSError, ValueError, KeyError):
        return False
    return ok and (_site_packages(prefix) / pkg.name / "msg" / "__init__.py").exists()


def missing(prefix: Path | None = None) -> list[Package]:
    """The packages not built (or built from other definitions) in ``prefix``."""
    return [p for p in packages() if not is_installed(p, prefix)]


def _package_xml(pkg: Package) -> str:
    deps = "".join(f"  <depend>{d}</depend>\n" for d in pkg.depends)
    return f"""<?xml version="1.0"?>
<package format="3">
  <name>{pkg.name}</name>
  <version>0.0.0</version>
  <description>{pkg.description}</description>
  <maintainer email="simatch@example.org">simatch</maintainer>
  <license>Apache-2.0</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
{deps}  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


def _cmakelists(pkg: Package) -> str:
    finds = "".join(f"find_package({d} REQUIRED)\n" for d in pkg.depends)
    files = " ".join(f'"msg/{m}.msg"' for m in sorted(pkg.messages))
    deps = f" DEPENDENCIES {' '.join(pkg.depends)}" if pkg.depends else ""
    return f"""cmake_minimum_required(VERSION 3.16)
project({pkg.name})
find_package(ament_cmake REQUIRED)
find_package(Python3 REQUIRED COMPONENTS Interpreter Development.Module)
{finds}find_package(rosidl_default_generators REQUIRED)
# The wheels were built in a manylinux image: their exported Python targets name that image's include folders,
# which do not exist here. Drop them (rosidl_generator_py adds this Python's own).
get_property(_targets DIRECTORY PROPERTY IMPORTED_TARGETS)
foreach(_t ${{_targets}})
  get_target_property(_inc ${{_t}} INTERFACE_INCLUDE_DIRECTORIES)
  if(_inc)
    set(_kept)
    foreach(_d ${{_inc}})
      if(NOT _d MATCHES "^/opt/python/")
        list(APPEND _kept "${{_d}}")
      endif()
    endforeach()
    set_target_properties(${{_t}} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${{_kept}}")
  endif()
endforeach()
rosidl_generate_interfaces(${{PROJECT_NAME}} {files}{deps})
ament_package()
"""


def _tools() -> dict[str, str]:
    found = {}
    for tool, why in (("cmake", "cmake"), ("cc", "a C compiler"), ("c++", "a C++ compiler")):
        path = shutil.which(tool)
        if path is None:
            raise BuildError(
                f"building the ROS 2 interface packages needs {why} ({tool!r} is not on PATH): "
                f"install it (Debian: apt-get install cmake g++)"
            )
        found[tool] = path
    try:
        import ament_package  # noqa: F401
        import rosidl_generator_py  # noqa: F401  (the generators, from the ros2 extra)
    except ImportError as exc:
        raise BuildError(f"the ROS 2 generators are not installed ({exc}): pip install 'simatch[ros2]'") from None
    return found


@contextlib.contextmanager
def _lock(prefix: Path):
    """One build at a time per prefix (two test sessions, or a test and a user)."""
    lock_dir = prefix / "share"
    lock_dir.mkdir(parents=True, exist_ok=True)
    with open(lock_dir / ".simatch-interfaces.lock", "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _env(prefix: Path) -> dict[str, str]:
    env = dict(os.environ)
    bindir = str(Path(sys.executable).parent)
    env["PATH"] = bindir + os.pathsep + env.get("PATH", "")
    env["AMENT_PREFIX_PATH"] = os.pathsep.join(p for p in (str(prefix), env.get("AMENT_PREFIX_PATH", "")) if p)
    env["CMAKE_PREFIX_PATH"] = os.pathsep.join(p for p in (str(prefix), env.get("CMAKE_PREFIX_PATH", "")) if p)
    env.setdefault("MAKEFLAGS", f"-j{max(1, min(os.cpu_count() or 1, 4))}")
    return env


def build(prefix: Path | None = None, force: bool = False, say: Callable[[str], None] = lambda text: None) -> list[str]:
    """Build and install the packages that are missing or out of date in ``prefix`` (all with ``force``);
    returns their names. BuildError (with the log's tail) if a tool is missing or a step fails."""
    prefix = Path(prefix or default_prefix())
    todo = packages() if force else missing(prefix)
    if not todo:
        return []
    _tools()
    if not os.access(prefix, os.W_OK):
        raise BuildError(f"cannot write to {prefix}: build the interfaces as the owner of this Python's prefix")
    env = _env(prefix)
    done = []
    with _lock(prefix):
        todo = packages() if force else missing(prefix)  # another process may have built them meanwhile
        for pkg in todo:
            say(f"building the ROS 2 interface package {pkg.name} ({len(pkg.messages)} messages) into {prefix}")
            with tempfile.TemporaryDirectory(prefix=f"simatch-{pkg.name}-") as tmp:
                _build_one(pkg, Path(tmp), prefix, env)
            stamp = prefix / "share" / pkg.name / STAMP
            stamp.write_text(json.dumps({"digest": pkg.digest(), "messages": sorted(pkg.messages)}) + "\n")
            done.append(pkg.name)
    return done


def _build_one(pkg: Package, tmp: Path, prefix: Path, env: dict[str, str]) -> None:
    src = tmp / "src"
    (src / "msg").mkdir(parents=True)
    (src / "package.xml").write_text(_package_xml(pkg))
    (src / "CMakeLists.txt").write_text(_cmakelists(pkg))
    for name, text in pkg.messages.items():
        (src / "msg" / f"{name}.msg").write_text(text)
    build_dir = tmp / "build"
    log_path = tmp / "build.log"
    steps = [
        [
            "cmake",
            "-S",
            str(src),
            "-B",
            str(build_dir),
            f"-DCMAKE_INSTALL_PREFIX={prefix}",
            f"-DCMAKE_PREFIX_PATH={prefix}",
            f"-DPython3_EXECUTABLE={sys.executable}",
            f"-DPython3_INCLUDE_DIR={sysconfig.get_paths()['include']}",
            "-DBUILD_TESTING=OFF",
            "-DCMAKE_BUILD_TYPE=Release",
        ],
        ["cmake", "--build", str(build_dir)],
        ["cmake", "--install", str(build_dir)],
    ]
    with open(log_path, "w") as log:
        for cmd in steps:
            log.write(f"$ {' '.join(cmd)}\n")
            log.flush()
            code = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, cwd=tmp)
            if code != 0:
                tail = log_path.read_text(errors="replace").splitlines()[-25:]
                raise BuildError(
                    f"building {pkg.name} failed at `{' '.join(cmd[:2])}` (exit {code}); the end of its log:\n"
                    + "\n".join(tail)
                )
