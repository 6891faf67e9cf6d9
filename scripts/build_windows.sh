#!/usr/bin/env bash
# Builds the Windows x64 native library and CLI: build-windows/bin/qgp.dll and qgp.exe (and the C API
# test program capi_job.exe), cross-compiled
# on Debian with mingw-w64 (GCC 12, posix threads; scripts/setup.sh installs it). Each needs no
# DLL beyond Windows' own: the C++ and Fortran runtimes and every dependency are linked statically.
# Then: /usr/bin/python3 scripts/build_extension.py --platform windows-x64; tests/windows/ runs both
# under Wine.
#
# Every dependency is built from Debian bookworm's sources (scripts/lib/dependency_sources.sh,
# pinned by SHA-256): METIS, GMP, CHOLMOD, Ipopt as for the portable Linux library, plus
# reference BLAS/LAPACK and sequential MUMPS (Debian ships neither for mingw-w64), and zlib and
# libpng for the CLI. Each step is skipped when its result exists; delete build-windows/ to start
# over. Needs the network (deb.debian.org) the first time.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
OUT=$ROOT/build-windows
PREFIX=$OUT/prefix
SOURCES=$OUT/sources
STEP_LABEL=build_windows
JOBS=$(nproc)
HOST=x86_64-w64-mingw32
# shellcheck source=lib/dependency_sources.sh
source scripts/lib/dependency_sources.sh
export QGP_WINDOWS_PREFIX=$PREFIX  # cmake/windows/mingw-w64.cmake searches it

CMAKE_MINGW=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_TOOLCHAIN_FILE="$ROOT/cmake/windows/mingw-w64.cmake"
  -DCMAKE_INSTALL_PREFIX="$PREFIX")
AUTOTOOLS_MINGW=(CC=$HOST-gcc-posix CXX=$HOST-g++-posix F77=$HOST-gfortran-posix FC=$HOST-gfortran-posix
  AR=$HOST-ar RANLIB=$HOST-ranlib)

build_metis() {
  source_metis
  # mingw's <stdlib.h> defines __argc and __argv as macros: GKlib's prototypes use them as names.
  sed -i 's/int __argc, char \*\*__argv/int argc_, char **argv_/' "$src/GKlib/gk_getopt.h"
  # GKlib includes <sys/resource.h> on every compiler but MSVC; mingw has none (nor needs it).
  sed -i 's|^  #include <sys/resource.h>$|  #ifndef __MINGW32__\n  #include <sys/resource.h>\n  #endif|' "$src/GKlib/gk_arch.h"
  cmake_metis "${CMAKE_MINGW[@]}"
}

build_gmp() {
  source_gmp
  mkdir -p "$OUT/deps/gmp"
  (cd "$OUT/deps/gmp" && env "${AUTOTOOLS_MINGW[@]}" CFLAGS="-O2" CXXFLAGS="-O2" "$src/configure" \
    --host=$HOST --build=x86_64-pc-linux-gnu --enable-static --disable-shared --enable-cxx \
    --prefix="$PREFIX" >/dev/null && make -j"$JOBS" >/dev/null && make install >/dev/null)
}

build_suitesparse() {
  source_suitesparse
  cmake_suitesparse "${CMAKE_MINGW[@]}"
}

# Reference BLAS whole, and of LAPACK only the routines CHOLMOD, MUMPS and Ipopt call, with every
# routine those call: 46 of LAPACK's 2 000 files (CMake's build of all of double and complex double
# precision took 165 s of the step, 2026-11-29).
LAPACK_ROOTS="dgetrf dgetrs dlamch dlarfg dorgqr dpotrf dpotrs dsyev ilaenv zpotrf"  # their undefined symbols
build_lapack() {
  source_lapack
  local build=$OUT/deps/lapack fc=$HOST-gfortran-posix
  rm -rf "$build" && mkdir -p "$build/blas" "$build/lapack"
  # The Fortran modules the .f90 routines use (la_constants, la_xisnan).
  (cd "$build" && $fc -O2 -c "$src/SRC/la_constants.f90" "$src/SRC/la_xisnan.F90")
  (cd "$build/blas" && printf '%s\n' "$src"/BLAS/SRC/*.f "$src"/BLAS/SRC/*.f90 |
    xargs -P "$JOBS" -n 16 $fc -O2 -I"$build" -c && $HOST-ar rcs "$PREFIX/lib/libblas.a" ./*.o)
  local defined=" $($HOST-nm --defined-only "$PREFIX/lib/libblas.a" | awk '$2 == "T" {print $3}' | tr '\n' ' ')"
  local wanted=$LAPACK_ROOTS name file candidate
  while [ -n "$wanted" ]; do
    local next=""
    for name in $wanted; do
      [ -f "$build/lapack/$name.o" ] && continue
      [[ $defined == *" ${name}_ "* ]] && continue  # in the BLAS (lsame, xerbla)
      file=""
      for candidate in "$src/SRC/$name.f" "$src/SRC/$name.f90" "$src/INSTALL/$name.f"; do
        [ -f "$candidate" ] && file=$candidate && break
      done
      [ -n "$file" ] || { echo "build_windows: no LAPACK source for $name" >&2; exit 1; }
      (cd "$build/lapack" && $fc -O2 -I"$build" -c "$file" -o "$name.o")
      next+=" $($HOST-nm -u "$build/lapack/$name.o" | awk '$2 ~ /_$/ && $2 !~ /^_gfortran/ {sub(/_$/, "", $2); print $2}')"
    done
    wanted=$(echo "$next" | tr ' ' '\n' | sort -u | tr '\n' ' ')
    [ -n "${wanted// /}" ] || wanted=""
  done
  $HOST-ar rcs "$PREFIX/lib/liblapack.a" "$build"/lapack/*.o "$build"/la_*.o
}

build_mumps() {  # sequential double-precision MUMPS with the PORD and METIS orderings
  source_mumps
  local build=$OUT/deps/mumps
  rm -rf "$build" && cp -r "$src" "$build"
  cat >"$build/Makefile.inc" <<MAKE
PLAT =
LIBEXT = .a
OUTC = -o
OUTF = -o
RM = /bin/rm -f
CC = $HOST-gcc-posix
FC = $HOST-gfortran-posix
FL = $HOST-gfortran-posix
AR = $HOST-ar vr 
RANLIB = $HOST-ranlib
LPORDDIR = \$(topdir)/PORD/lib/
IPORD = -I\$(topdir)/PORD/include/
LPORD = -L\$(LPORDDIR) -lpord
IMETIS = -I$PREFIX/include
LMETIS = -L$PREFIX/lib -lmetis
ORDERINGSF = -Dpord -Dmetis
ORDERINGSC = \$(ORDERINGSF)
LORDERINGS = \$(LMETIS) \$(LPORD)
IORDERINGSF =
IORDERINGSC = \$(IMETIS) \$(IPORD)
INCSEQ = -I\$(topdir)/libseq
LIBSEQ = \$(LAPACK) -L\$(topdir)/libseq -lmpiseq
LIBSEQNEEDED = libseqneeded
INCS = \$(INCSEQ)
LIBS = \$(LIBSEQ)
LIBBLAS = -L$PREFIX/lib -lblas
LAPACK = -L$PREFIX/lib -llapack
SCALAP =
LIBOTHERS =
CDEFS = -DAdd_
OPTF = -O2 -fallow-argument-mismatch
OPTC = -O2
OPTL = -O2
MAKE
  make -C "$build" -j"$JOBS" prerequisites >/dev/null  # libseq and PORD
  make -C "$build/src" -j"$JOBS" d >/dev/null  # the libraries without the examples
  cp "$build"/lib/libdmumps.a "$build"/lib/libmumps_common.a "$build"/PORD/lib/libpord.a \
    "$build"/libseq/libmpiseq.a "$PREFIX/lib/"
  mkdir -p "$PREFIX/include/mumps"
  cp "$build"/include/{dmumps_c.h,mumps_c_types.h,mumps_compat.h,mumps_int_def.h} "$build/libseq/mpi.h" \
    "$PREFIX/include/mumps/"
}

build_ipopt() {
  source_ipopt
  local l=$PREFIX/lib
  local fortran="-lgfortran -lquadmath"
  local blas="$l/liblapack.a $l/libblas.a $fortran"
  local mumps="$l/libdmumps.a $l/libmumps_common.a $l/libpord.a $l/libmpiseq.a $l/libmetis.a"
  mkdir -p "$OUT/deps/ipopt"
  (cd "$OUT/deps/ipopt" && env "${AUTOTOOLS_MINGW[@]}" CPPFLAGS="-DHAVE_CSTDDEF" CFLAGS="-O2" CXXFLAGS="-O2" \
    FFLAGS="-O2" "$src/configure" --host=$HOST --build=x86_64-pc-linux-gnu \
    --enable-static --disable-shared --disable-pkg-config --prefix="$PREFIX" \
    --with-mumps-incdir="$PREFIX/include/mumps" --with-mumps-lib="$mumps $blas" \
    --with-blas-lib="$blas" --with-lapack-lib="$blas" >/dev/null &&
    make -j"$JOBS" >/dev/null && make install >/dev/null)
}

build_zlib() {
  source_zlib
  cmake -S "$src" -B "$OUT/deps/zlib" "${CMAKE_MINGW[@]}" >/dev/null
  cmake --build "$OUT/deps/zlib" -j"$JOBS" --target zlibstatic >/dev/null
  cp "$OUT/deps/zlib/libzlibstatic.a" "$PREFIX/lib/libz.a"
  cp "$src/zlib.h" "$OUT/deps/zlib/zconf.h" "$PREFIX/include/"
}

build_libpng() {
  source_libpng
  cmake -S "$src" -B "$OUT/deps/libpng" "${CMAKE_MINGW[@]}" -DPNG_SHARED=OFF -DPNG_TESTS=OFF \
    -DPNG_EXECUTABLES=OFF -DZLIB_LIBRARY="$PREFIX/lib/libz.a" -DZLIB_INCLUDE_DIR="$PREFIX/include" >/dev/null
  cmake --build "$OUT/deps/libpng" -j"$JOBS" >/dev/null
  cmake --install "$OUT/deps/libpng" >/dev/null
}

header_only() {  # nlohmann-json and CLI11 from Debian's packages: /usr/include itself holds glibc's headers
  [ -d "$PREFIX/include/nlohmann" ] || cp -r /usr/include/nlohmann "$PREFIX/include/"
  [ -d "$PREFIX/include/CLI" ] || cp -r /usr/include/CLI "$PREFIX/include/"
}

mkdir -p "$SOURCES" "$PREFIX/lib" "$PREFIX/include"
for dependency in metis gmp suitesparse lapack mumps ipopt zlib libpng; do
  build_dependency "$dependency"
done
header_only

step "qgp.dll and qgp.exe"
cmake -S . -B "$OUT" "${CMAKE_MINGW[@]}" -DQGP_WINDOWS=ON -DQGP_BUILD_TESTS=OFF -DQGP_WINDOWS_PREFIX="$PREFIX" >/dev/null
cmake --build "$OUT" -j"$JOBS" --target qgp qgp_cli >/dev/null  # compiler messages go to stderr
# The C API test program (tests/windows/test_wine.py runs it under Wine against qgp.dll).
$HOST-gcc-posix -O2 -static -Inative/include tests/windows/capi_job.c -o "$OUT/bin/capi_job.exe"
echo "build_windows: $OUT/bin/qgp.dll and $OUT/bin/qgp.exe"
