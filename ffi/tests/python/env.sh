#!/usr/bin/env bash
# Makes (once) the Python virtual environment with FMPy and
# fmu-manipulation-toolbox that the FMU tests use, and prints its python.
# Usage: env.sh VENV_DIR
set -euo pipefail
venv="$1"
requirements="$(dirname "$0")/requirements.txt"
stamp="$venv/.requirements"
if [ ! -x "$venv/bin/python" ] || ! cmp -s "$requirements" "$stamp"; then
    python3 -m venv "$venv" >&2
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$requirements" >&2
    cp "$requirements" "$stamp"
fi
echo "$venv/bin/python"
