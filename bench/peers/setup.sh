#!/usr/bin/env bash
# Creates bench/peers/.venv and installs the pinned peer simulators into it.
# Usage: bench/peers/setup.sh        (from anywhere; needs Python >= 3.11)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
py="${PYTHON:-python3}"
if ! "$py" -c 'import sys; sys.exit(0 if sys.version_info[:2] >= (3, 11) else 1)'; then
    echo "setup.sh: $py is $("$py" --version 2>&1); mujoco 4 and the opensim wheels need Python >= 3.11 (set PYTHON=...)" >&2
    exit 1
fi
if [ ! -x "$here/.venv/bin/python" ]; then
    "$py" -m venv "$here/.venv"
fi
"$here/.venv/bin/python" -m pip install --quiet --upgrade pip
"$here/.venv/bin/python" -m pip install --quiet -r "$here/requirements.txt"
"$here/.venv/bin/python" - <<'PY'
import mujoco, opensim, numpy
print(f"peers ready: mujoco {mujoco.__version__}, opensim {opensim.__version__}, numpy {numpy.__version__}")
PY
