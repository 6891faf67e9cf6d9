#!/usr/bin/env bash
# README command 1: set up, build, and run the main job on a mesh Blender creates (Suzanne).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
./scripts/build.sh
mkdir -p out/demo
blender -b --factory-startup --python-exit-code 1 --python scripts/make_suzanne.py -- out/demo/suzanne.obj 2>&1 | grep -E "^suzanne" || true
echo
echo "== qgp info out/demo/suzanne.obj"
build/bin/qgp info out/demo/suzanne.obj --report out/demo/suzanne_info.json
echo "(report: out/demo/suzanne_info.json)"
echo
echo "== qgp remesh out/demo/suzanne.obj -o out/demo/suzanne_quads.obj --faces 2000"
build/bin/qgp remesh out/demo/suzanne.obj -o out/demo/suzanne_quads.obj --faces 2000 \
  --uv-out out/demo/suzanne_uv.obj --layout-out out/demo/suzanne_layout.obj --report out/demo/suzanne_remesh.json
echo "quad mesh: out/demo/suzanne_quads.obj, integer-grid UVs: out/demo/suzanne_uv.obj,"
echo "T-mesh layout: out/demo/suzanne_layout.obj, report: out/demo/suzanne_remesh.json"
