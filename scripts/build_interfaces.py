#!/usr/bin/env python3
"""Generate, build and install the Python typesupport of sigcore's ROS 2 interface packages.

ROS 2 Jazzy's rclpy has no dynamic-message API: every message, service and action type needs generated and
compiled typesupport. The PyPI wheels (``ros-jazzy-*``) cover the common packages, but not ``tf2_msgs``,
``simulation_interfaces`` or sigcore's own ``sigcore_msgs``. This script builds those from ``interfaces/``
against the wheels installed in a virtual environment, without any ROS installation:

1. Discovers the packages in ``interfaces/`` (directories with a ``package.xml``) and orders them by their
   dependencies on each other.
2. For each package computes a cache key: a hash of its interface sources (``package.xml``,
   ``CMakeLists.txt``, ``msg/``, ``srv/``, ``action/``), the pinned requirement files, the CMake workaround,
   the venv's Python version and numpy version, and the keys of the local packages it depends on.
3. If the venv already has the package installed with that key, does nothing. Otherwise, if the cache holds a
   wheel with that key, installs it. Otherwise configures, builds and installs the package with CMake into a
   staging prefix, packs the staging prefix into a wheel (Python modules into site-packages, ``lib/``,
   ``share/`` and ``include/`` as data files at the venv root, like the ROS wheels), stores it in the cache
   and installs it.

The wheels are installed with the venv's own pip (``--no-deps --no-index``), so ``pip uninstall`` and
upgrades remove stale files. The cache defaults to ``~/.cache/sigcore/interfaces``; ``$SIGCORE_CACHE_DIR``
overrides it.

Usage::

    python scripts/build_interfaces.py --venv .venv

Only the standard library is used, so any Python 3.9+ can run this script; the venv needs the wheels of
``scripts/ros2_requirements.txt``, and for a build (cache miss) also those of
``scripts/ros2_build_requirements.txt``, a C/C++ compiler and the Python headers.
"""

from __future__ import annotations

import argparse
import base64
import csv
import dataclasses
import hashlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

SCRIPTS_DIR = Path(__file__).resolve().parent
REPO_ROOT = SCRIPTS_DIR.parent
DEFAULT_INTERFACES_DIR = REPO_ROOT / "interfaces"
CMAKE_WORKAROUND = SCRIPTS_DIR / "cmake" / "drop_missing_include_dirs.cmake"
REQUIREMENT_FILES = (SCRIPTS_DIR / "ros2_requirements.txt", SCRIPTS_DIR / "ros2_build_requirements.txt")

# Bump when the way packages are built or packed changes, to invalidate every cached wheel.
BUILD_FORMAT = "1"
# Distribution name prefix of the wheels this script makes (the Python import names stay the package names).
DIST_PREFIX = "sigcore_interface_"
# Order among packages that do not depend on each other: upstream definitions first, sigcore's own (which
# changes most often) last.
PREFERRED_ORDER = ("tf2_msgs", "simulation_interfaces", "sigcore_msgs")
# Cached wheels kept per package; older ones are deleted.
KEEP_WHEELS_PER_PACKAGE = 3
# Minimum CMake version: scripts/cmake/drop_missing_include_dirs.cmake uses cmake_language(DEFER).
MIN_CMAKE = (3, 19)
# Files and directories of a package that define its interfaces and hence enter its cache key.
SOURCE_FILES = ("package.xml", "CMakeLists.txt")
SOURCE_DIRS = ("msg", "srv", "action")


class BuildError(Exception):
    """A package failed to configure, build, install or pack; carries a user-facing message."""


@dataclasses.dataclass
class Package:
    """An interface package found in the interfaces directory.

    Attributes:
        name: ROS package name (also the Python import name).
        version: Version from package.xml.
        path: Directory holding package.xml.
        build_deps: Packages needed to build it (build, buildtool and plain depends).
        run_deps: Packages needed at run time (exec, build_export and plain depends).
        key: Cache key, set by compute_keys().
    """

    name: str
    version: str
    path: Path
    build_deps: set[str]
    run_deps: set[str]
    key: str = ""

    @property
    def dist_name(self) -> str:
        """Name of the wheel distribution that carries this package."""
        return DIST_PREFIX + self.name

    @property
    def wheel_version(self) -> str:
        """Wheel version: the package version with the cache key as local version label."""
        return f"{self.version}+k{self.key}"

    @property
    def interface_count(self) -> int:
        """Number of .msg/.srv/.action definitions in the package."""
        return sum(1 for d in SOURCE_DIRS for f in (self.path / d).glob(f"*.{d}") if f.is_file())


@dataclasses.dataclass
class VenvInfo:
    """Facts about the target virtual environment, queried from its interpreter.

    Attributes:
        root: The venv directory (its sys.prefix).
        python: Path of the venv's python executable.
        version: Python version "major.minor".
        implementation: sys.implementation.name, e.g. "cpython".
        python_tag: Wheel interpreter/ABI tag, e.g. "cp311".
        platform_tag: Wheel platform tag, e.g. "linux_x86_64".
        platlib: The venv's site-packages directory.
        include_dir: Directory that should hold Python.h.
        numpy_version: Installed numpy version, or None.
    """

    root: Path
    python: Path
    version: str
    implementation: str
    python_tag: str
    platform_tag: str
    platlib: Path
    include_dir: Path
    numpy_version: str | None


def log(message: str) -> None:
    """Print a progress line immediately."""
    print(message, flush=True)


# ------------------------------------------------------------------------------------------------------------
# Discovery and cache keys
# ------------------------------------------------------------------------------------------------------------


def read_package(path: Path) -> Package:
    """Read a package's name, version and dependencies from its package.xml.

    Args:
        path: The package directory.

    Returns:
        The package description.

    Raises:
        BuildError: If package.xml is malformed.
    """
    try:
        root = ET.parse(path / "package.xml").getroot()
    except ET.ParseError as exc:
        raise BuildError(f"{path / 'package.xml'}: {exc}") from exc

    def texts(tag: str) -> set[str]:
        return {(e.text or "").strip() for e in root.findall(tag) if (e.text or "").strip()}

    name = (root.findtext("name") or "").strip()
    version = (root.findtext("version") or "").strip()
    if not name or not re.fullmatch(r"\d+\.\d+\.\d+", version):
        raise BuildError(f"{path / 'package.xml'}: needs a <name> and a <version> of the form X.Y.Z")
    depend = texts("depend")
    return Package(
        name=name,
        version=version,
        path=path,
        build_deps=depend | texts("build_depend") | texts("buildtool_depend"),
        run_deps=depend | texts("exec_depend") | texts("build_export_depend"),
    )


def discover_packages(interfaces_dir: Path) -> list[Package]:
    """Find the interface packages and sort them so that each comes after the local packages it depends on.

    Args:
        interfaces_dir: Directory whose subdirectories are ROS packages.

    Returns:
        The packages in build order.

    Raises:
        BuildError: If there is no package or the local dependencies form a cycle.
    """
    found = {
        p.name: p
        for p in (read_package(d) for d in sorted(interfaces_dir.iterdir()) if (d / "package.xml").is_file())
    }
    if not found:
        raise BuildError(f"no interface package (directory with package.xml) in {interfaces_dir}")

    def rank(name: str) -> tuple[int, str]:
        return (PREFERRED_ORDER.index(name) if name in PREFERRED_ORDER else len(PREFERRED_ORDER), name)

    ordered: list[Package] = []
    pending = dict(found)
    while pending:
        ready = [n for n, p in pending.items() if not (p.build_deps | p.run_deps) & pending.keys() - {n}]
        if not ready:
            raise BuildError(f"dependency cycle among interface packages: {', '.join(sorted(pending))}")
        name = min(ready, key=rank)
        ordered.append(pending.pop(name))
    return ordered


def hash_package_sources(package: Package, digest: hashlib._Hash) -> None:
    """Feed a package's interface sources (names and contents) into a hash.

    Args:
        package: The package.
        digest: The hash object to update.
    """
    files = [package.path / f for f in SOURCE_FILES if (package.path / f).is_file()]
    for directory in SOURCE_DIRS:
        if (package.path / directory).is_dir():
            files += sorted(f for f in (package.path / directory).rglob("*") if f.is_file())
    for file in files:
        digest.update(file.relative_to(package.path).as_posix().encode() + b"\0")
        digest.update(hashlib.sha256(file.read_bytes()).digest())


def compute_keys(packages: list[Package], venv: VenvInfo) -> None:
    """Set the cache key of every package (packages must be in build order).

    Args:
        packages: The packages, in build order.
        venv: The target venv, whose Python and numpy versions enter the key.
    """
    common = hashlib.sha256()
    common.update(f"format={BUILD_FORMAT}\0".encode())
    common.update(
        f"python={venv.implementation}-{venv.version}-{venv.python_tag}-{venv.platform_tag}\0".encode()
    )
    # The generated C extensions are compiled against numpy's headers.
    common.update(f"numpy={venv.numpy_version}\0".encode())
    for file in (*REQUIREMENT_FILES, CMAKE_WORKAROUND):
        common.update(file.name.encode() + b"\0")
        common.update(hashlib.sha256(file.read_bytes() if file.is_file() else b"").digest())

    keys: dict[str, str] = {}
    for package in packages:
        digest = common.copy()
        digest.update(package.name.encode() + b"\0")
        hash_package_sources(package, digest)
        for dep in sorted((package.build_deps | package.run_deps) & keys.keys()):
            digest.update(f"dep={dep}:{keys[dep]}\0".encode())
        package.key = keys[package.name] = digest.hexdigest()[:16]


# ------------------------------------------------------------------------------------------------------------
# The target venv
# ------------------------------------------------------------------------------------------------------------

_VENV_QUERY = r"""
import json, sys, sysconfig
try:
    import numpy
    numpy_version = numpy.__version__
except Exception:
    numpy_version = None
print(json.dumps({
    "prefix": sys.prefix,
    "base_prefix": sys.base_prefix,
    "version": "%d.%d" % sys.version_info[:2],
    "implementation": sys.implementation.name,
    "nodot": sysconfig.get_config_var("py_version_nodot"),
    "platform": sysconfig.get_platform(),
    "platlib": sysconfig.get_paths()["platlib"],
    "include": sysconfig.get_paths()["include"],
    "numpy": numpy_version,
}))
"""


def query_venv(venv_dir: Path) -> VenvInfo:
    """Ask the venv's interpreter about itself.

    Args:
        venv_dir: The virtual environment directory.

    Returns:
        Facts about the venv.

    Raises:
        BuildError: If the directory is not a working virtual environment.
    """
    python = venv_dir / "bin" / "python"
    if not python.exists():
        raise BuildError(
            f"{venv_dir} is not a virtual environment (no bin/python); create it with python3 -m venv"
        )
    proc = subprocess.run(
        [str(python), "-c", _VENV_QUERY], capture_output=True, text=True, env=clean_environment()
    )
    if proc.returncode != 0:
        raise BuildError(f"{python} failed to run:\n{proc.stderr.strip()}")
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    if info["prefix"] == info["base_prefix"]:
        raise BuildError(
            f"{venv_dir} is not a virtual environment; the ROS wheels must be installed into one"
        )
    if info["implementation"] != "cpython":
        raise BuildError(f"{python} is {info['implementation']}; the ROS 2 wheels need CPython")
    return VenvInfo(
        root=Path(info["prefix"]),
        python=python,
        version=info["version"],
        implementation=info["implementation"],
        python_tag=f"cp{info['nodot']}",
        platform_tag=re.sub(r"[^A-Za-z0-9]", "_", info["platform"]),
        platlib=Path(info["platlib"]),
        include_dir=Path(info["include"]),
        numpy_version=info["numpy"],
    )


def ros_packages_in(venv: VenvInfo) -> set[str]:
    """Return the names of the ROS packages registered in the venv's ament index."""
    index = venv.root / "share" / "ament_index" / "resource_index" / "packages"
    return {p.name for p in index.iterdir()} if index.is_dir() else set()


def installed_version(venv: VenvInfo, package: Package) -> str | None:
    """Return the version of the package's wheel installed in the venv, or None."""
    for dist_info in venv.platlib.glob(f"{package.dist_name}-*.dist-info"):
        return dist_info.name[len(package.dist_name) + 1 : -len(".dist-info")]
    return None


def check_runtime(venv: VenvInfo, packages: list[Package]) -> None:
    """Check that the ROS packages needed at run time are in the venv.

    Args:
        venv: The target venv.
        packages: The interface packages to install.

    Raises:
        BuildError: Naming what is missing and how to install it.
    """
    local = {p.name for p in packages}
    missing = sorted(set().union(*(p.run_deps for p in packages)) - local - ros_packages_in(venv))
    if missing:
        raise BuildError(
            f"the venv {venv.root} lacks the ROS packages {', '.join(missing)}; "
            "install the runtime wheels first:\n"
            f"  {venv.root}/bin/pip install -r {REQUIREMENT_FILES[0]}"
        )


def find_tools(venv: VenvInfo) -> tuple[Path, Path | None]:
    """Find CMake (>= 3.19) and, if present, ninja, preferring the venv's own (pip) ones.

    Args:
        venv: The target venv.

    Returns:
        The cmake executable and the ninja executable (None when absent).

    Raises:
        BuildError: If no suitable CMake is found.
    """
    search_path = os.pathsep.join([str(venv.root / "bin"), os.environ.get("PATH", "")])
    cmake = shutil.which("cmake", path=search_path)
    if cmake is None:
        raise BuildError("CMake not found; install the build requirements (they include cmake)")
    out = subprocess.run([cmake, "--version"], capture_output=True, text=True).stdout
    match = re.search(r"(\d+)\.(\d+)", out)
    if not match or (int(match[1]), int(match[2])) < MIN_CMAKE:
        raise BuildError(
            f"{cmake} is too old ({out.splitlines()[0] if out else '?'}); CMake >= 3.19 is needed"
        )
    ninja = shutil.which("ninja", path=search_path)
    return Path(cmake), Path(ninja) if ninja else None


def check_build_prerequisites(venv: VenvInfo, packages: list[Package]) -> None:
    """Check what a build needs: build-time ROS wheels, catkin_pkg, a compiler and the Python headers.

    Args:
        venv: The target venv.
        packages: The packages that will be built.

    Raises:
        BuildError: Naming what is missing and how to get it.
    """
    problems = []
    local = {p.name for p in packages}
    needed = set().union(*(p.build_deps for p in packages)) | {"ament_cmake", "rosidl_default_generators"}
    missing = sorted(needed - local - ros_packages_in(venv))
    probe = subprocess.run(
        [str(venv.python), "-c", "import catkin_pkg, setuptools"],
        capture_output=True,
        env=clean_environment(),
    )
    if missing or probe.returncode != 0:
        what = ", ".join(missing + ([] if probe.returncode == 0 else ["catkin_pkg/setuptools"]))
        problems.append(
            f"the venv lacks the build-time packages {what}; install them with\n"
            f"  {venv.root}/bin/pip install -r {REQUIREMENT_FILES[1]}"
        )
    for compiler, env_var in (("cc", "CC"), ("c++", "CXX")):
        if not (os.environ.get(env_var) or shutil.which(compiler)):
            problems.append(f"no {compiler} compiler found (e.g. apt-get install g++)")
    if not (venv.include_dir / "Python.h").is_file():
        problems.append(
            f"Python headers missing ({venv.include_dir}/Python.h), "
            f"e.g. apt-get install python{venv.version}-dev"
        )
    if problems:
        raise BuildError("cannot build the interface packages:\n- " + "\n- ".join(problems))


# ------------------------------------------------------------------------------------------------------------
# Building
# ------------------------------------------------------------------------------------------------------------


# Variables that must not leak into the build: a sourced ROS setup's paths, and the ROS wheels' bootstrap
# marker (set when this script runs under a bootstrapped interpreter, it would stop the target venv's python
# from setting its own LD_LIBRARY_PATH).
_FOREIGN_ENV = frozenset(
    {
        "PYTHONPATH",
        "PYTHONHOME",
        "COLCON_PREFIX_PATH",
        "AMENT_CURRENT_PREFIX",
        "CMAKE_PREFIX_PATH",
        "_ROS_WHEELS_BOOTSTRAP_COMPLETE",
    }
)


def clean_environment() -> dict[str, str]:
    """Return this process's environment without the variables of _FOREIGN_ENV."""
    return {k: v for k, v in os.environ.items() if k not in _FOREIGN_ENV}


def build_environment(venv: VenvInfo) -> dict[str, str]:
    """Return the environment for CMake: the venv as the only ROS prefix, nothing from a sourced ROS setup."""
    env = clean_environment()
    env.update(
        VIRTUAL_ENV=str(venv.root),
        PATH=os.pathsep.join([str(venv.root / "bin"), os.environ.get("PATH", "")]),
        # Without this rosidl fails with "No 'rosidl_typesupport_c' found".
        AMENT_PREFIX_PATH=str(venv.root),
        CMAKE_PREFIX_PATH=str(venv.root),
        PYTHONDONTWRITEBYTECODE="1",
    )
    return env


def run_step(
    step: str, cmd: list[str], env: dict[str, str], log_file: Path, package: Package, build_dir: Path
) -> None:
    """Run one build step, appending its output to the log file.

    Args:
        step: Step name for messages ("configure", "build", "install").
        cmd: The command.
        env: Its environment.
        log_file: Log file to append to.
        package: The package being built.
        build_dir: The CMake build tree (named in the error message; kept after a failure).

    Raises:
        BuildError: If the command fails, with the end of the log and the log's path.
    """
    with log_file.open("a") as out:
        out.write(f"\n$ {' '.join(cmd)}\n")
        out.flush()
        code = subprocess.run(cmd, env=env, stdout=out, stderr=subprocess.STDOUT).returncode
    if code != 0:
        tail = "".join(log_file.read_text(errors="replace").splitlines(keepends=True)[-30:])
        raise BuildError(
            f"building {package.name} failed at the {step} step (exit code {code}).\n"
            f"--- last lines of the log ---\n{tail}"
            f"--- full log: {log_file}\n"
            f"--- build tree (kept): {build_dir}"
        )


def build_package(
    package: Package, venv: VenvInfo, cache_dir: Path, jobs: int, keep_build: bool
) -> tuple[Path, Path]:
    """Configure, build and install a package into a staging prefix.

    Args:
        package: The package to build.
        venv: The target venv, whose ROS wheels are built against.
        cache_dir: The cache directory (holds build trees and logs).
        jobs: Parallel compile jobs.
        keep_build: Keep the build tree after success (it is always kept after a failure).

    Returns:
        The staging prefix and the log file.

    Raises:
        BuildError: If a step fails.
    """
    cmake, ninja = find_tools(venv)
    (cache_dir / "logs").mkdir(parents=True, exist_ok=True)
    (cache_dir / "build").mkdir(parents=True, exist_ok=True)
    log_file = cache_dir / "logs" / f"{package.name}-{package.key}.log"
    log_file.write_text(f"# {package.name} {package.wheel_version} for {venv.root}\n")
    for stale in (cache_dir / "build").glob(f"{package.name}-*"):  # left by failed or interrupted builds
        shutil.rmtree(stale, ignore_errors=True)
    work = Path(tempfile.mkdtemp(prefix=f"{package.name}-", dir=cache_dir / "build"))
    build_dir, stage = work / "build", work / "stage"
    env = build_environment(venv)

    configure = [
        str(cmake), "-S", str(package.path), "-B", str(build_dir),
        f"-DCMAKE_INSTALL_PREFIX={stage}",
        "-DCMAKE_BUILD_TYPE=Release",
        "-DBUILD_TESTING=OFF",
        f"-DPython3_EXECUTABLE={venv.python}",
        # Remove the wheels' non-existent include directories from imported targets (see the file).
        f"-DCMAKE_PROJECT_INCLUDE={CMAKE_WORKAROUND}",
    ]  # fmt: skip
    if ninja:
        configure += ["-G", "Ninja", f"-DCMAKE_MAKE_PROGRAM={ninja}"]
    steps = [
        ("configure", configure),
        ("build", [str(cmake), "--build", str(build_dir), "--parallel", str(jobs)]),
        ("install", [str(cmake), "--install", str(build_dir)]),
    ]
    for step, cmd in steps:
        run_step(step, cmd, env, log_file, package, build_dir)
    if not keep_build:
        shutil.rmtree(build_dir, ignore_errors=True)
    return stage, log_file


def make_relocatable(stage: Path, venv: VenvInfo) -> None:
    """Replace the build venv's path in the exported CMake files by their install prefix.

    rosidl exports the numpy include directory of the build venv as an absolute path; a cached wheel installed
    into another venv must point at that venv's numpy instead.

    Args:
        stage: The staging prefix.
        venv: The venv the package was built against.
    """
    for cmake_file in stage.glob("share/*/cmake/*.cmake"):
        text = cmake_file.read_text()
        if str(venv.root) in text and "_IMPORT_PREFIX" in text:
            cmake_file.write_text(text.replace(str(venv.root), "${_IMPORT_PREFIX}"))


# ------------------------------------------------------------------------------------------------------------
# Wheels
# ------------------------------------------------------------------------------------------------------------


def _record_hash(data: bytes) -> str:
    """Return a file hash in the format of a wheel's RECORD."""
    return "sha256=" + base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()


def pack_wheel(package: Package, stage: Path, venv: VenvInfo, out_dir: Path) -> Path:
    """Pack a staging prefix into a wheel whose data files land at the venv root.

    The contents of ``lib/pythonX.Y/site-packages`` become the wheel's root (installed into site-packages);
    all other files go to ``<dist>.data/data/`` (installed relative to the venv root: ``lib/``, ``share/``,
    ``include/``). Bytecode caches are left out.

    Args:
        package: The package.
        stage: Its staging prefix.
        venv: The target venv (gives the wheel tags).
        out_dir: Directory to write the wheel to (atomically).

    Returns:
        The wheel's path.
    """
    dist = f"{package.dist_name}-{package.wheel_version}"
    tag = f"{venv.python_tag}-{venv.python_tag}-{venv.platform_tag}"
    site_dirs = [d for d in stage.glob("lib*/python*/*-packages") if d.is_dir()]
    entries: list[tuple[str, Path]] = []
    for file in sorted(p for p in stage.rglob("*") if p.is_file()):
        if "__pycache__" in file.parts:
            continue
        site = next((d for d in site_dirs if d in file.parents), None)
        if site is not None:
            entries.append((file.relative_to(site).as_posix(), file))
        else:
            entries.append((f"{dist}.data/data/{file.relative_to(stage).as_posix()}", file))

    metadata = (
        "Metadata-Version: 2.1\n"
        f"Name: {package.dist_name}\n"
        f"Version: {package.wheel_version}\n"
        f"Summary: ROS 2 Jazzy typesupport of the {package.name} interface package, built by sigcore\n"
    )
    wheel_meta = (
        f"Wheel-Version: 1.0\nGenerator: sigcore build_interfaces.py\nRoot-Is-Purelib: false\nTag: {tag}\n"
    )

    out_dir.mkdir(parents=True, exist_ok=True)
    target = out_dir / f"{dist}-{tag}.whl"
    tmp = out_dir / f".{target.name}.{os.getpid()}.tmp"
    records = []
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:

        def add(arcname: str, data: bytes, mode: int = 0o644) -> None:
            info = zipfile.ZipInfo(arcname, date_time=(1980, 1, 1, 0, 0, 0))
            info.external_attr = (0o100000 | mode) << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            zf.writestr(info, data)
            records.append((arcname, _record_hash(data), str(len(data))))

        for arcname, file in entries:
            add(arcname, file.read_bytes(), 0o755 if os.access(file, os.X_OK) else 0o644)
        add(f"{dist}.dist-info/METADATA", metadata.encode())
        add(f"{dist}.dist-info/WHEEL", wheel_meta.encode())
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerows([*records, (f"{dist}.dist-info/RECORD", "", "")])
        info = zipfile.ZipInfo(f"{dist}.dist-info/RECORD", date_time=(1980, 1, 1, 0, 0, 0))
        info.external_attr = (0o100644) << 16
        zf.writestr(info, buf.getvalue(), compress_type=zipfile.ZIP_DEFLATED)
    os.replace(tmp, target)
    return target


def cached_wheel(package: Package, venv: VenvInfo, wheels_dir: Path) -> Path | None:
    """Return the cached wheel of the package with its current key, or None."""
    tag = f"{venv.python_tag}-{venv.python_tag}-{venv.platform_tag}"
    wheel = wheels_dir / f"{package.dist_name}-{package.wheel_version}-{tag}.whl"
    return wheel if wheel.is_file() else None


def prune_cache(package: Package, wheels_dir: Path) -> None:
    """Delete all but the newest KEEP_WHEELS_PER_PACKAGE cached wheels of a package."""
    wheels = sorted(
        wheels_dir.glob(f"{package.dist_name}-*.whl"), key=lambda p: p.stat().st_mtime, reverse=True
    )
    for old in wheels[KEEP_WHEELS_PER_PACKAGE:]:
        old.unlink(missing_ok=True)


def install_wheel(wheel: Path, venv: VenvInfo, package: Package) -> None:
    """Install a wheel into the venv with the venv's pip, replacing any other version of it.

    Args:
        wheel: The wheel file.
        venv: The target venv.
        package: The package it carries.

    Raises:
        BuildError: If pip fails.
    """
    cmd = [
        str(venv.python), "-m", "pip", "install", "--no-deps", "--no-index", "--no-cache-dir",
        "--force-reinstall", "--disable-pip-version-check", "--quiet", str(wheel),
    ]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True, env=clean_environment())
    if proc.returncode != 0:
        raise BuildError(
            f"installing {package.name} ({wheel}) into {venv.root} failed:\n{proc.stderr.strip()}"
        )


# ------------------------------------------------------------------------------------------------------------
# Timings (for the "about N s" estimates)
# ------------------------------------------------------------------------------------------------------------


def load_timings(cache_dir: Path) -> dict[str, tuple[float, int]]:
    """Return the last measured build of each package: (seconds, number of interfaces then)."""
    try:
        raw = json.loads((cache_dir / "timings.json").read_text())
        return {k: (float(v["seconds"]), int(v["interfaces"])) for k, v in raw.items()}
    except (OSError, ValueError, TypeError, KeyError, AttributeError):
        return {}


def save_timing(cache_dir: Path, package: Package, seconds: float) -> None:
    """Record a package's build time and its number of interfaces."""
    timings = load_timings(cache_dir)
    timings[package.name] = (round(seconds, 1), package.interface_count)
    data = {k: {"seconds": t, "interfaces": n} for k, (t, n) in timings.items()}
    (cache_dir / "timings.json").write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")


def _model_seconds(interfaces: int, jobs: int) -> float:
    """Build-time model measured on 2 cores: 8 s plus 2.2 s per interface, scaled by the parallelism."""
    return (8 + 2.2 * interfaces) * 2 / max(1, min(jobs, os.cpu_count() or 1))


def estimate_seconds(package: Package, timings: dict[str, tuple[float, int]], jobs: int) -> float:
    """Estimate a build's duration: the last measurement scaled to today's interface count, else the model."""
    count = package.interface_count
    if package.name in timings:
        seconds, then = timings[package.name]
        return seconds * _model_seconds(count, jobs) / _model_seconds(then, jobs)
    return _model_seconds(count, jobs)


def format_duration(seconds: float) -> str:
    """Format a duration for humans ("45 s", "about 2 min")."""
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.0f} min"


# ------------------------------------------------------------------------------------------------------------
# Main
# ------------------------------------------------------------------------------------------------------------


def default_cache_dir() -> Path:
    """Return $SIGCORE_CACHE_DIR, else ~/.cache/sigcore/interfaces."""
    env = os.environ.get("SIGCORE_CACHE_DIR")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "sigcore" / "interfaces"


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    """Parse the command line."""
    parser = argparse.ArgumentParser(
        description="Build (or fetch from the cache) and install the ROS 2 typesupport of the interface "
        "packages in interfaces/ into a virtual environment holding the ROS 2 Jazzy wheels.",
    )
    parser.add_argument(
        "--venv",
        type=Path,
        default=os.environ.get("VIRTUAL_ENV"),
        help="target virtual environment (default: $VIRTUAL_ENV)",
    )
    parser.add_argument(
        "--interfaces-dir",
        type=Path,
        default=DEFAULT_INTERFACES_DIR,
        help=f"directory of the interface packages (default: {DEFAULT_INTERFACES_DIR})",
    )
    parser.add_argument(
        "--cache-dir",
        type=Path,
        default=default_cache_dir(),
        help="wheel cache (default: $SIGCORE_CACHE_DIR or ~/.cache/sigcore/interfaces)",
    )
    parser.add_argument(
        "--packages",
        nargs="+",
        metavar="NAME",
        help="only these packages (and the local ones they depend on)",
    )
    parser.add_argument("--jobs", "-j", type=int, default=os.cpu_count() or 2, help="parallel compile jobs")
    parser.add_argument("--rebuild", action="store_true", help="build even if the cache has the wheel")
    parser.add_argument(
        "--reinstall", action="store_true", help="install even if the venv has the same build"
    )
    parser.add_argument("--keep-build", action="store_true", help="keep the CMake build trees")
    args = parser.parse_args(argv)
    if args.venv is None:
        parser.error("--venv is required when no virtual environment is active")
    return args


def select(packages: list[Package], names: list[str] | None) -> list[Package]:
    """Restrict packages to the named ones plus the local packages they depend on, keeping the build order.

    Raises:
        BuildError: If a name is unknown.
    """
    if not names:
        return packages
    by_name = {p.name: p for p in packages}
    unknown = sorted(set(names) - by_name.keys())
    if unknown:
        raise BuildError(f"unknown interface package(s): {', '.join(unknown)} (have: {', '.join(by_name)})")
    wanted: set[str] = set()
    todo = list(names)
    while todo:
        name = todo.pop()
        if name not in wanted:
            wanted.add(name)
            todo += sorted((by_name[name].build_deps | by_name[name].run_deps) & by_name.keys())
    return [p for p in packages if p.name in wanted]


def run(args: argparse.Namespace) -> None:
    """Bring every interface package of the venv up to date: installed, cached, or built.

    Args:
        args: The parsed command line.

    Raises:
        BuildError: On any failure, with a message for the user.
    """
    started = time.monotonic()
    venv = query_venv(Path(args.venv).expanduser().absolute())
    cache_dir = Path(args.cache_dir).expanduser().absolute()
    wheels_dir = cache_dir / "wheels"
    if os.environ.get("ROS_DISTRO"):
        log(
            f"note: a ROS {os.environ['ROS_DISTRO']} environment is sourced; it is ignored "
            "(see docs/ros2-interfaces.md)"
        )

    packages = discover_packages(Path(args.interfaces_dir).absolute())
    compute_keys(packages, venv)  # keys of dependencies are needed even when not selected
    packages = select(packages, args.packages)
    check_runtime(venv, packages)
    log(
        f"interface packages for {venv.root} (Python {venv.version}, numpy {venv.numpy_version}), "
        f"cache {cache_dir}"
    )

    timings = load_timings(cache_dir)
    prerequisites_checked = False
    summary = []
    for package in packages:
        t0 = time.monotonic()
        if not (args.reinstall or args.rebuild) and installed_version(venv, package) == package.wheel_version:
            log(f"up to date: {package.name} (installed, key {package.key})")
            summary.append((package.name, "up to date", time.monotonic() - t0))
            continue
        wheel = None if args.rebuild else cached_wheel(package, venv, wheels_dir)
        if wheel is not None:
            install_wheel(wheel, venv, package)
            log(f"cached: {package.name} (installed from {wheel.name})")
            summary.append((package.name, "cached", time.monotonic() - t0))
            continue
        if not prerequisites_checked:
            check_build_prerequisites(venv, packages)
            prerequisites_checked = True
        estimate = estimate_seconds(package, timings, args.jobs)
        log(
            f"building {package.name} ({package.interface_count} interfaces, "
            f"about {format_duration(estimate)}, -j{args.jobs})..."
        )
        stage, log_file = build_package(package, venv, cache_dir, args.jobs, args.keep_build)
        make_relocatable(stage, venv)
        wheel = pack_wheel(package, stage, venv, wheels_dir)
        if not args.keep_build:
            shutil.rmtree(stage.parent, ignore_errors=True)
        prune_cache(package, wheels_dir)
        install_wheel(wheel, venv, package)
        elapsed = time.monotonic() - t0
        save_timing(cache_dir, package, elapsed)
        log(f"built: {package.name} in {elapsed:.1f} s (log {log_file})")
        summary.append((package.name, "built", elapsed))

    total = time.monotonic() - started
    log("summary: " + ", ".join(f"{name} {what} ({secs:.1f} s)" for name, what, secs in summary))
    log(f"done in {total:.1f} s")


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point; returns the exit code."""
    args = parse_args(argv)
    try:
        run(args)
    except BuildError as exc:
        print(f"error: {exc}", file=sys.stderr, flush=True)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
