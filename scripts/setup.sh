#!/usr/bin/env bash
# Set up sigcore on a fresh machine: a virtual environment in .venv with the core, every bundled plugin and the
# test tools. Idempotent: a second run only checks. Usage: bash scripts/setup.sh
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
want=$(cat pyproject.toml plugins/*/pyproject.toml scripts/constraints.txt scripts/setup.sh | sha256sum | cut -c1-16)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "setup: .venv is up to date"
else
  echo "setup: installing sigcore, its plugins and test tools into .venv (about 1 minute on a fresh machine)"
  "$V/python" -m pip install -q --disable-pip-version-check --upgrade pip setuptools wheel
  pkgs=(-e ".[test]")
  for p in plugins/*/; do pkgs+=(-e "$p"); done
  "$V/python" -m pip install -q --disable-pip-version-check -c scripts/constraints.txt "${pkgs[@]}"
  echo "$want" > "$stamp"
fi
"$V/sigcore" plugins
