#!/usr/bin/env bash
# Installs Blender as a Python module (PyPI's `bpy`) in one virtual environment per tested Blender
# version, for the tests that run the add-on on Blender 4.5 LTS and 5.0 (tests/blender/module/):
#   .venv-bpy-4.5  bpy==4.5.*   .venv-bpy-5.0  bpy==5.0.*   (git-ignored, at the checkout's root)
# Needs `python3` 3.11 with pip and venv on PATH (PyPI's bpy wheels are built for Python 3.11 only)
# and access to PyPI. Idempotent: a venv that already holds the pinned version is left alone.
# Each download is about 0.4 GB and each installed venv about 1 GB; pip's cache keeps the wheels.
# Called by scripts/test.sh; configure with -DQGP_BPY_TESTS=ON (the default when the venvs exist).
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${QGP_BPY_PYTHON:-python3}
VERSIONS=("4.5.*" "5.0.*")

if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
  echo "setup_bpy: $PYTHON is not Python 3.11 (PyPI's bpy needs 3.11); set QGP_BPY_PYTHON" >&2
  exit 1
fi

for spec in "${VERSIONS[@]}"; do
  series=${spec%.\*}
  venv=.venv-bpy-$series
  if [ -x "$venv/bin/python" ] && "$venv/bin/python" - "$series" <<'EOF' 2>/dev/null; then
import importlib.metadata
import sys
sys.exit(not importlib.metadata.version("bpy").startswith(sys.argv[1] + "."))
EOF
    echo "setup_bpy: $venv has bpy $("$venv/bin/python" -c 'import importlib.metadata as m; print(m.version("bpy"))')"
    continue
  fi
  echo "setup_bpy: creating $venv with bpy==$spec"
  rm -rf "$venv"
  "$PYTHON" -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "bpy==$spec"
  echo "setup_bpy: $venv has bpy $("$venv/bin/python" -c 'import importlib.metadata as m; print(m.version("bpy"))')"
done
