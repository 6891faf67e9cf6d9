#!/usr/bin/env bash
# Installs Blender as a Python module (PyPI's `bpy`) in one virtual environment per tested Blender
# version, for the tests that run the add-on on Blender 4.5 LTS and 5.0 (tests/blender/module/):
#   .venv-bpy-4.5  bpy==4.5.*   .venv-bpy-5.0  bpy==5.0.*   (git-ignored, at the checkout's root)
# Needs `python3` 3.11 with pip and venv on PATH (PyPI's bpy wheels are built for Python 3.11 only;
# Debian 12's python3 with python3-venv, from scripts/setup.sh, will do) and access to PyPI.
# Idempotent: a venv that already holds the pinned version is left alone. Each download is about
# 0.4 GB (bpy 373 MB, numpy and the rest 28 MB), each venv about 1 GB, each install under a minute.
# Called by scripts/test.sh, which configures with -DQGP_BPY_TESTS=ON (ctest blender_module_4_5,
# blender_module_5_0; the default AUTO adds them when both venvs exist).
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
  start=$SECONDS
  rm -rf "$venv"
  "$PYTHON" -m venv "$venv"
  # pip's own lines name the downloads and their sizes.
  "$venv/bin/python" -m pip install --progress-bar off --disable-pip-version-check "bpy==$spec" |
    grep -E "^ *(Downloading|Successfully installed)" || true
  "$venv/bin/python" -c 'import importlib.metadata as m; m.version("bpy")'  # fails if pip did
  echo "setup_bpy: $venv has bpy $("$venv/bin/python" -c 'import importlib.metadata as m; print(m.version("bpy"))')" \
    "($(du -sh "$venv" | cut -f1), $((SECONDS - start)) s)"
done
