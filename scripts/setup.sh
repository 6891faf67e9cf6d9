#!/usr/bin/env bash
# Installs the Debian packages the project needs. Idempotent; needs root or sudo.
set -euo pipefail

PACKAGES=(
  cmake g++ make pkg-config            # build
  clang libclang-rt-14-dev             # fuzzing (libFuzzer) and sanitizers
  libeigen3-dev libopenmesh-dev coinor-libipopt-dev libsuitesparse-dev libgmp-dev nlohmann-json3-dev
  libcli11-dev                         # the CLI's argument parser
  libpng-dev                           # qgp stitch: PNG images
  libgtest-dev                         # tests
  blender python3 python3-numpy python3-matplotlib   # add-on, Blender tests, benchmarks
  python3-venv                         # scripts/setup_bpy.sh: Blender 4.5 and 5.0 as Python modules
  libopenblas0-serial                  # optimized BLAS for MUMPS (Ipopt) factorizations: about 2x faster
  patchelf zip unzip                   # extension packaging
  curl patch gfortran libmumps-seq-dev libscotch-dev libopenblas-serial-dev zlib1g-dev libbz2-dev liblzma-dev
                                       # scripts/build_portable.sh: sources, and the static archives it links
  g++-mingw-w64-x86-64-posix gfortran-mingw-w64-x86-64-posix wine wine64
                                       # scripts/build_windows.sh (Windows x64 cross-build) and its test under Wine
  xvfb xauth                           # a real Blender window for the modal-operator test
  clang-format-14 python3-flake8 python3-clang-14   # code checks (format, Python style, function length)
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
echo "setup: done"
