#!/usr/bin/env bash
# Builds build-portable/lib/libqgp.so, the native library of the Linux extension zip: it loads on
# glibc 2.28 and later (Blender's own Linux builds need 2.28) and needs no C++ runtime from the
# system. Then: /usr/bin/python3 scripts/build_extension.py (packages build-portable/ by default)
#
# How (docs/portable-build.md has the why):
#   - Zig (PyPI's ziglang, pinned, in .venv-zig) compiles C and C++ against glibc 2.28's symbol
#     versions and links its own libc++ statically.
#   - Every C++ dependency is built from Debian bookworm's sources with it (Ipopt), and so
#     are the C ones that Debian ships only as shared or as position-dependent static archives
#     (METIS, GMP, CHOLMOD). Sources are pinned by SHA-256.
#   - Debian's static MUMPS, SCOTCH and OpenBLAS archives (scripts/setup.sh) are linked in as they are.
#   - The Fortran runtime (MUMPS and LAPACK are Fortran) is the manylinux_2_28 build that scipy's
#     wheel (pinned) carries; it is bundled next to the library.
# Each step is skipped when its result exists; delete build-portable/ to start over. Needs the
# network (deb.debian.org, PyPI) the first time; about 10 minutes on 2 cores (605-633 s measured).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
OUT=$ROOT/build-portable
PREFIX=$OUT/prefix
SOURCES=$OUT/sources
TOOLS=$OUT/toolchain
JOBS=$(nproc)
ZIG_VERSION=0.17.1
GLIBC_TARGET=x86_64-linux-gnu.2.28
STEP_LABEL=build_portable
# shellcheck source=lib/dependency_sources.sh
source scripts/lib/dependency_sources.sh

toolchain() {  # Zig in .venv-zig and wrappers that fix its target: $TOOLS/{cc,c++,ar,ranlib}
  if ! [ -x .venv-zig/bin/python ] || ! .venv-zig/bin/python -m ziglang version 2>/dev/null | grep -qx "$ZIG_VERSION"; then
    python3 -m venv .venv-zig
    .venv-zig/bin/pip install -q "ziglang==$ZIG_VERSION"
  fi
  mkdir -p "$TOOLS"
  local zig="$ROOT/.venv-zig/bin/python -m ziglang"
  printf '#!/bin/sh\nexec %s cc -target %s "$@"\n' "$zig" "$GLIBC_TARGET" >"$TOOLS/cc"
  printf '#!/bin/sh\nexec %s c++ -target %s "$@"\n' "$zig" "$GLIBC_TARGET" >"$TOOLS/c++"
  printf '#!/bin/sh\nexec %s ar "$@"\n' "$zig" >"$TOOLS/ar"
  printf '#!/bin/sh\nexec %s ranlib "$@"\n' "$zig" >"$TOOLS/ranlib"
  chmod +x "$TOOLS"/*
}

CMAKE_ZIG=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER="$TOOLS/cc" -DCMAKE_CXX_COMPILER="$TOOLS/c++"
  -DCMAKE_AR="$TOOLS/ar" -DCMAKE_RANLIB="$TOOLS/ranlib" -DCMAKE_POSITION_INDEPENDENT_CODE=ON)
AUTOTOOLS_ZIG=(CC="$TOOLS/cc" CXX="$TOOLS/c++" AR="$TOOLS/ar" RANLIB="$TOOLS/ranlib")

build_metis() {
  source_metis
  cmake_metis "${CMAKE_ZIG[@]}"
}

build_gmp() {
  source_gmp
  mkdir -p "$OUT/deps/gmp"
  # Generic x86-64 code (no host CPU detection), position-independent, with gmpxx.h for libc++.
  (cd "$OUT/deps/gmp" && env "${AUTOTOOLS_ZIG[@]}" CFLAGS="-O2 -fPIC" CXXFLAGS="-O2 -fPIC" "$src/configure" \
    --host=x86_64-pc-linux-gnu --build=x86_64-pc-linux-gnu --enable-static --disable-shared --with-pic \
    --enable-cxx --prefix="$PREFIX" >/dev/null && make -j"$JOBS" >/dev/null && make install >/dev/null)
}

build_suitesparse() {
  source_suitesparse
  cmake_suitesparse "${CMAKE_ZIG[@]}"
}

build_ipopt() {
  source_ipopt
  local lib=/usr/lib/x86_64-linux-gnu
  # Debian's MUMPS headers in a folder of their own: -I/usr/include would put glibc 2.36's headers
  # ahead of Zig's.
  mkdir -p "$PREFIX/include/mumps"
  cp /usr/include/{dmumps_c.h,mumps_c_types.h,mumps_compat.h,mumps_int_def.h} /usr/include/mumps_seq/mpi.h "$PREFIX/include/mumps/"
  local fortran="$(gfortran -print-file-name=libgfortran.a) $(gfortran -print-file-name=libquadmath.a)"
  local blas="$lib/openblas-serial/libopenblas.a $fortran -lm"
  local mumps="$lib/libdmumps_seq.a $lib/libmumps_common_seq.a $lib/libpord_seq.a $lib/libmpiseq_seq.a"
  mumps+=" $lib/libesmumps.a $lib/libscotch.a $lib/libscotcherr.a $PREFIX/lib/libmetis.a $lib/libz.a $lib/libbz2.a $lib/liblzma.a"
  mkdir -p "$OUT/deps/ipopt"
  # configure only needs its link checks to pass (with gfortran's static runtime); the library
  # itself links the shared manylinux runtime.
  (cd "$OUT/deps/ipopt" && env "${AUTOTOOLS_ZIG[@]}" F77=gfortran CPPFLAGS="-DHAVE_CSTDDEF" CFLAGS="-O2 -fPIC" \
    CXXFLAGS="-O2 -fPIC -Wno-reserved-user-defined-literal" FFLAGS="-O2 -fPIC" "$src/configure" \
    --enable-static --disable-shared --disable-pkg-config --prefix="$PREFIX" \
    --with-mumps-incdir="$PREFIX/include/mumps" --with-mumps-lib="$mumps $blas" \
    --with-blas-lib="$blas" --with-lapack-lib="$blas" >/dev/null &&
    make -j"$JOBS" >/dev/null && make install >/dev/null)
}

build_fortran_runtime() {  # libgfortran and libquadmath of scipy 1.17.1's manylinux_2_28 wheel
  local wheel=scipy-1.17.1-cp311-cp311-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl
  if [ ! -f "$SOURCES/$wheel" ]; then
    .venv-zig/bin/pip download -q --no-deps --only-binary=:all: --platform manylinux_2_28_x86_64 \
      --python-version 3.11 -d "$SOURCES" scipy==1.17.1
  fi
  echo "43af8d1f3bea642559019edfe64e9b11192a8978efbd1539d7bc2aaa23d92de4  $SOURCES/$wheel" | sha256sum --check --quiet
  unzip -o -q -j "$SOURCES/$wheel" 'scipy.libs/libgfortran-8f1e9814.so.5.0.0' \
    'scipy.libs/libquadmath-828275a7.so.0.0.0' -d "$PREFIX/lib"
  patchelf --set-rpath '$ORIGIN' "$PREFIX/lib/libgfortran-8f1e9814.so.5.0.0"  # finds libquadmath beside it
}

mkdir -p "$SOURCES" "$PREFIX/lib" "$PREFIX/include"
step "toolchain (Zig $ZIG_VERSION, $GLIBC_TARGET)"
toolchain
build_dependency metis
build_dependency gmp
build_dependency suitesparse
build_dependency ipopt
build_dependency fortran_runtime
[ -d "$PREFIX/include/nlohmann" ] || cp -r /usr/include/nlohmann "$PREFIX/include/"  # header-only

step "libqgp.so"
cmake -S . -B "$OUT" "${CMAKE_ZIG[@]}" -DQGP_PORTABLE=ON -DQGP_BUILD_TESTS=OFF -DQGP_PORTABLE_PREFIX="$PREFIX" >/dev/null
cmake --build "$OUT" -j"$JOBS" --target qgp >/dev/null  # compiler messages go to stderr
echo "build_portable: $OUT/lib/libqgp.so (glibc 2.28 and later)"
