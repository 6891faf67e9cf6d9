#!/usr/bin/env bash
# The whole benchmark in one command (docs/benchmark.md):
#   1. Quantized Retopo vs Blender's QuadriFlow in one Blender process (bench/compare_quadriflow.py),
#      on the shared meshes and on sculpts it generates (a shared mesh subdivided and displaced)
#   2. scaling of the native pipeline against input size and target density (bench/scaling.py), and
#      re-quantizing at a new density in the same session, as the redo panel does (bench/requantize.py)
#   3. tables + plots (bench/plots.py) and side-by-side renders (bench/render.py)
#   4. every shared mesh through `qgp remesh` at 500 / 2 000 / 8 000 quads, each output checked
#      (bench/robustness.py; issue 23's sweep)
# Output: bench/results/ (compare.csv/.json/.md, scaling.csv/.md, requantize.csv/.md, robustness.csv/.md) and
# docs/images/ (plots, renders).
#
#   ./scripts/bench.sh [--quick] [--skip-compare] [--skip-scaling] [--skip-render] [--skip-robustness]
#   MESHES=spot.obj,fandisk.obj TARGETS=2000 ./scripts/bench.sh      # a subset
#   (also SCULPTS, MAX_TRIANGLES, DENSITIES, DENSITY_LEVEL, CASES, QGP_TIMEOUT, SCALING_TIMEOUT, QGP_MESHES,
#   ROBUSTNESS_MESHES, ROBUSTNESS_TARGETS, ROBUSTNESS_TIMEOUT)
# Defaults are the full run: every manifold mesh of ../shared/meshes at 2000 and 8000 quads and inputs
# of about 5 000 to 1 000 000 triangles. --quick: 3 small meshes, 2000 quads, inputs up to ~100k triangles.
set -euo pipefail
cd "$(dirname "$0")/.."

QUICK=0; DO_COMPARE=1; DO_SCALING=1; DO_RENDER=1; DO_ROBUSTNESS=1
for arg in "$@"; do
  case "$arg" in
    --quick) QUICK=1 ;;
    --skip-compare) DO_COMPARE=0 ;;
    --skip-scaling) DO_SCALING=0 ;;
    --skip-render) DO_RENDER=0 ;;
    --skip-robustness) DO_ROBUSTNESS=0 ;;
    *) echo "bench: unknown option $arg" >&2; exit 2 ;;
  esac
done

if [ "$QUICK" = 1 ]; then
  MESHES=${MESHES:-spot.obj,fertility.off,fandisk.obj}
  TARGETS=${TARGETS:-2000}
  MAX_TRIANGLES=${MAX_TRIANGLES:-120000}
  DENSITIES=${DENSITIES:-1000,2000,4000}
  DENSITY_LEVEL=${DENSITY_LEVEL:-1}
  CASES=${CASES:-spot.obj:2000,fertility.off:2000,fandisk.obj:2000}
  SCULPTS=${SCULPTS-spot.obj:2}   # BASE:LEVELS; spot at 2 levels: 0.14 M triangles
  REQUANTIZE_MESHES=${REQUANTIZE_MESHES:-spot.obj,fandisk.obj}
  ROBUSTNESS_MESHES=${ROBUSTNESS_MESHES:-spot.obj,truck.obj,teapot.obj}
  ROBUSTNESS_TARGETS=${ROBUSTNESS_TARGETS:-500}
else
  MESHES=${MESHES:-}   # empty: all manifold meshes
  TARGETS=${TARGETS:-2000,8000}
  MAX_TRIANGLES=${MAX_TRIANGLES:-1200000}
  DENSITIES=${DENSITIES:-500,1000,2000,4000,8000,16000,32000}
  DENSITY_LEVEL=${DENSITY_LEVEL:-2}
  CASES=${CASES:-spot.obj:2000,fertility.off:2000,fandisk.obj:8000}
  SCULPTS=${SCULPTS-spot.obj:3,spot.obj:4}   # about 0.56 M and 2.2 M triangles
  REQUANTIZE_MESHES=${REQUANTIZE_MESHES:-spot.obj,kitten.obj,fandisk.obj,rocker-arm.obj,stanford-bunny.obj,armadillo.obj,nefertiti.obj}
  ROBUSTNESS_MESHES=${ROBUSTNESS_MESHES:-}   # empty: every mesh file
  ROBUSTNESS_TARGETS=${ROBUSTNESS_TARGETS:-500,2000,8000}
fi
MESH_DIR=${QGP_MESHES:-$(cd .. && pwd)/shared/meshes}
QGP_TIMEOUT=${QGP_TIMEOUT:-900}          # s before a Quantized Retopo run in Blender is cancelled
SCALING_TIMEOUT=${SCALING_TIMEOUT:-1800}  # s before a scaling run (qgp process) is killed
RESULTS=bench/results
IMAGES=docs/images
PYTHON=/usr/bin/python3   # Debian's Python: numpy + matplotlib
mkdir -p "$RESULTS" "$IMAGES"

if [ ! -x build/bin/qgp ] || [ ! -f build/lib/libqgp.so ]; then
  ./scripts/setup.sh
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build -j"$(nproc)" --target qgp qgp_cli
fi

start=$(date +%s)
if [ "$DO_COMPARE" = 1 ]; then
  # Full Blender output in compare.log; progress lines on the terminal. If Blender dies (a crash in
  # either tool), the run resumes after the case that was running, which is recorded as 'crashed'.
  : >"$RESULTS/compare.log"
  resume=""
  for attempt in 1 2 3 4 5 6; do
    blender -b --factory-startup --python-exit-code 1 --python bench/compare_quadriflow.py -- --mesh-dir "$MESH_DIR" \
      --meshes "$MESHES" --sculpts "$SCULPTS" --targets "$TARGETS" --timeout "$QGP_TIMEOUT" --out "$RESULTS" --save-meshes $resume >>"$RESULTS/compare.log" 2>&1 &
    blender_pid=$!
    tail -n 0 -f "$RESULTS/compare.log" --pid=$blender_pid | grep --line-buffered -E '^(compare|Traceback|  File|[A-Za-z]*Error)' || true
    # A library can end Blender with status 0 (MUMPS after an internal error): the case file left
    # behind, not the status, says whether the run was cut short.
    if wait $blender_pid && [ ! -f "$RESULTS/compare.pending" ]; then break; fi
    echo "bench: Blender exited with an error (attempt $attempt); resuming after the failed case"
    resume="--resume"
  done
fi
t_compare=$(date +%s)
if [ "$DO_SCALING" = 1 ]; then
  QGP_MESHES="$MESH_DIR" $PYTHON bench/scaling.py --max-triangles "$MAX_TRIANGLES" --densities "$DENSITIES" \
    --density-level "$DENSITY_LEVEL" --timeout "$SCALING_TIMEOUT" --out "$RESULTS"
  QGP_MESHES="$MESH_DIR" QGP_LIBRARY="$PWD/build/lib/libqgp.so" $PYTHON bench/requantize.py --meshes "$REQUANTIZE_MESHES" \
    --out "$RESULTS"
fi
t_scaling=$(date +%s)
$PYTHON bench/plots.py --results "$RESULTS" --images "$IMAGES"
if [ "$DO_RENDER" = 1 ]; then
  blender -b --factory-startup --python-exit-code 1 --python bench/render.py -- --mesh-dir "$MESH_DIR" --cases "$CASES" \
    --results "$RESULTS" --out "$IMAGES" >"$RESULTS/render.log" 2>&1 || { tail -20 "$RESULTS/render.log"; exit 1; }
  grep -E '^render' "$RESULTS/render.log" || true
fi
t_render=$(date +%s)
if [ "$DO_ROBUSTNESS" = 1 ]; then
  $PYTHON bench/robustness.py --qgp build/bin/qgp --mesh-dir "$MESH_DIR" --meshes "$ROBUSTNESS_MESHES" \
    --targets "$ROBUSTNESS_TARGETS" --timeout "${ROBUSTNESS_TIMEOUT:-300}" --out "$RESULTS"
fi
end=$(date +%s)
echo "bench: compare $((t_compare - start)) s, scaling $((t_scaling - t_compare)) s, plots+renders" \
  "$((t_render - t_scaling)) s, robustness $((end - t_render)) s"
echo "bench: tables $RESULTS/compare.md $RESULTS/scaling.md $RESULTS/requantize.md $RESULTS/robustness.md," \
  "images $IMAGES/"
