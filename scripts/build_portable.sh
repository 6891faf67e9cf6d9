#!/usr/bin/env bash
# Builds build-portable/lib/libqgp.so, the native library of the Linux extension zip: it loads on
# glibc 2.28 and later (Blender's own Linux builds need 2.28) and needs no C++ runtime from the
# system. Then: /usr/bin/python3 scripts/build_extension.py (packages build-portable/ by default)
#
# How (docs/portable-build.md has the why):
#   - Zig (PyPI's ziglang, pinned, in .venv-zig) compiles C and C++ against glibc 2.28's symbol
#     versions and links its own libc++ statically.
#   - Every C++ dependency is built from Debian bookworm's sources with it (OpenMesh, Ipopt), and so
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
DEBIAN=https://deb.debian.org/debian/pool/main
ZIG_VERSION=0.17.1
GLIBC_TARGET=x86_64-linux-gnu.2.28
step() { echo "== build_portable: $1 (at ${SECONDS} s)"; }

fetch() {  # file name, URL, SHA-256: downloads into $SOURCES once and checks the digest
  local file=$SOURCES/$1
  if [ ! -f "$file" ]; then
    curl -fsSL --retry 3 -o "$file.part" "$2"
    mv "$file.part" "$file"
  fi
  echo "$3  $file" | sha256sum --check --quiet || { echo "build_portable: $1: wrong SHA-256" >&2; exit 1; }
}

unpack() {  # archive file name, folder it makes: unpacks into $SOURCES once
  [ -d "$SOURCES/$2" ] || tar -xf "$SOURCES/$1" -C "$SOURCES"
}

apply_debian_patches() {  # source folder, Debian packaging archive: Debian's patches, once
  [ -f "$1/.debian-patched" ] && return
  local debian
  debian=$SOURCES/debian-$(basename "$1")
  mkdir -p "$debian"
  tar -xf "$SOURCES/$2" -C "$debian"
  while read -r patch; do
    patch -d "$1" -p1 -s <"$debian/debian/patches/$patch"
  done < <(grep -v '^#' "$debian/debian/patches/series")
  touch "$1/.debian-patched"
}

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
  fetch metis_5.1.0.dfsg.orig.tar.xz "$DEBIAN/m/metis/metis_5.1.0.dfsg.orig.tar.xz" \
    c50a88b92b01fa3972c5c92cf50117f126c62589b8f793657c7d865c59c23615
  unpack metis_5.1.0.dfsg.orig.tar.xz metis-5.1.0
  local src=$SOURCES/metis-5.1.0
  cmake -S "$src" -B "$OUT/deps/metis" "${CMAKE_ZIG[@]}" -DGKLIB_PATH="$src/GKlib" -DSHARED=OFF >/dev/null
  cmake --build "$OUT/deps/metis" -j"$JOBS" --target metis >/dev/null
  cp "$OUT/deps/metis/libmetis/libmetis.a" "$PREFIX/lib/"
  cp "$src/include/metis.h" "$PREFIX/include/"
}

build_gmp() {
  fetch gmp_6.2.1+dfsg1.orig.tar.xz "$DEBIAN/g/gmp/gmp_6.2.1+dfsg1.orig.tar.xz" \
    471b9e463e04362a0124f215afc5f0a4b99caedeeb62634c61bbc12988efa64c
  fetch gmp_6.2.1+dfsg1-1.1.debian.tar.xz "$DEBIAN/g/gmp/gmp_6.2.1+dfsg1-1.1.debian.tar.xz" \
    4e3e324d72fe688e409c716d33b35aa8657f6016cc1aabd5d9c7ec137412e5ef
  unpack gmp_6.2.1+dfsg1.orig.tar.xz gmp-6.2.1
  local src=$SOURCES/gmp-6.2.1
  apply_debian_patches "$src" gmp_6.2.1+dfsg1-1.1.debian.tar.xz
  # Debian's source has no doc/ (GFDL); build the library folders only.
  sed -i 's|^SUBDIRS = tests mpn mpz mpq mpf printf scanf rand cxx demos tune doc$|SUBDIRS = mpn mpz mpq mpf printf scanf rand cxx|' "$src/Makefile.in"
  sed -i 's| doc/Makefile | |' "$src/configure"
  mkdir -p "$OUT/deps/gmp"
  # Generic x86-64 code (no host CPU detection), position-independent, with gmpxx.h for libc++.
  (cd "$OUT/deps/gmp" && env "${AUTOTOOLS_ZIG[@]}" CFLAGS="-O2 -fPIC" CXXFLAGS="-O2 -fPIC" "$src/configure" \
    --host=x86_64-pc-linux-gnu --build=x86_64-pc-linux-gnu --enable-static --disable-shared --with-pic \
    --enable-cxx --prefix="$PREFIX" >/dev/null && make -j"$JOBS" >/dev/null && make install >/dev/null)
}

build_suitesparse() {
  fetch suitesparse_5.12.0+dfsg.orig.tar.xz "$DEBIAN/s/suitesparse/suitesparse_5.12.0+dfsg.orig.tar.xz" \
    bb106c43049138c19675cd70322e72ff8e4fd8bdcab3a096307fd78488913faf
  [ -d "$SOURCES/SuiteSparse-5.12.0" ] || tar -xf "$SOURCES/suitesparse_5.12.0+dfsg.orig.tar.xz" -C "$SOURCES" \
    --wildcards '*/SuiteSparse_config/*' '*/AMD/*' '*/CAMD/*' '*/COLAMD/*' '*/CCOLAMD/*' '*/CHOLMOD/*'
  cmake -S cmake/portable/suitesparse -B "$OUT/deps/suitesparse" "${CMAKE_ZIG[@]}" \
    -DSUITESPARSE_DIR="$SOURCES/SuiteSparse-5.12.0" -DMETIS_INCLUDE_DIR="$PREFIX/include" \
    -DCMAKE_INSTALL_PREFIX="$PREFIX" >/dev/null
  cmake --build "$OUT/deps/suitesparse" -j"$JOBS" >/dev/null
  cmake --install "$OUT/deps/suitesparse" >/dev/null
}

build_openmesh() {
  fetch openmesh_9.0.orig.tar.gz "$DEBIAN/o/openmesh/openmesh_9.0.orig.tar.gz" \
    4df84295f5cca86b1ae8bfee8ff4db5efb6850e4e5b571ad0199147176dea796
  unpack openmesh_9.0.orig.tar.gz OpenMesh-9.0.0
  local src=$SOURCES/OpenMesh-9.0.0
  cmake -S "$src" -B "$OUT/deps/openmesh" "${CMAKE_ZIG[@]}" -DBUILD_APPS=OFF -DOPENMESH_DOCS=OFF >/dev/null
  cmake --build "$OUT/deps/openmesh" -j"$JOBS" --target OpenMeshCoreStatic >/dev/null
  find "$OUT/deps/openmesh" -name 'libOpenMesh*.a' -exec cp {} "$PREFIX/lib/" \;
  # The headers, with the template definitions (.cc) they include.
  (cd "$src/src" && find OpenMesh \( -name '*.hh' -o -name '*.cc' \) -exec cp --parents {} "$PREFIX/include/" \;)
}

build_ipopt() {
  fetch coinor-ipopt_3.11.9.orig.tar.gz "$DEBIAN/c/coinor-ipopt/coinor-ipopt_3.11.9.orig.tar.gz" \
    84991b13ce22e4a4aa0756a5db290c2b811bf82ff4e9124d1a71867118e6ab2d
  fetch coinor-ipopt_3.11.9-2.3.debian.tar.xz "$DEBIAN/c/coinor-ipopt/coinor-ipopt_3.11.9-2.3.debian.tar.xz" \
    ffbb7a4b2295af0d183f31d440483118b7a49871df9626cd3b12f29aca445b6b
  unpack coinor-ipopt_3.11.9.orig.tar.gz Ipopt-3.11.9
  local src=$SOURCES/Ipopt-3.11.9 lib=/usr/lib/x86_64-linux-gnu
  apply_debian_patches "$src" coinor-ipopt_3.11.9-2.3.debian.tar.xz
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

build_dependency() {  # name: runs build_<name> once (a stamp in the prefix records it)
  if [ ! -f "$PREFIX/.built-$1" ]; then
    step "$1"
    "build_$1"
    touch "$PREFIX/.built-$1"
  fi
}

mkdir -p "$SOURCES" "$PREFIX/lib" "$PREFIX/include"
step "toolchain (Zig $ZIG_VERSION, $GLIBC_TARGET)"
toolchain
build_dependency metis
build_dependency gmp
build_dependency suitesparse
build_dependency openmesh
build_dependency ipopt
build_dependency fortran_runtime
[ -d "$PREFIX/include/nlohmann" ] || cp -r /usr/include/nlohmann "$PREFIX/include/"  # header-only

step "libqgp.so"
cmake -S . -B "$OUT" "${CMAKE_ZIG[@]}" -DQGP_PORTABLE=ON -DQGP_BUILD_TESTS=OFF -DQGP_PORTABLE_PREFIX="$PREFIX" >/dev/null
cmake --build "$OUT" -j"$JOBS" --target qgp >/dev/null  # compiler messages go to stderr
echo "build_portable: $OUT/lib/libqgp.so (glibc 2.28 and later)"
