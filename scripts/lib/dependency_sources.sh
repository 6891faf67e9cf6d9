# Sourced by build_portable.sh and build_windows.sh: Debian bookworm's sources of the native
# dependencies, pinned by SHA-256, fetched, unpacked and patched once into $SOURCES, and the
# helpers that run each dependency's build once. The caller sets SOURCES, PREFIX, OUT, JOBS and
# STEP_LABEL.
# shellcheck shell=bash
DEBIAN=https://deb.debian.org/debian/pool/main

step() { echo "== $STEP_LABEL: $1 (at ${SECONDS} s)"; }

fetch() {  # file name, URL, SHA-256: downloads into $SOURCES once and checks the digest
  local file=$SOURCES/$1
  if [ ! -f "$file" ]; then
    curl -fsSL --retry 3 -o "$file.part" "$2"
    mv "$file.part" "$file"
  fi
  echo "$3  $file" | sha256sum --check --quiet || { echo "$STEP_LABEL: $1: wrong SHA-256" >&2; exit 1; }
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

build_dependency() {  # name: runs build_<name> once (a stamp in the prefix records it)
  if [ ! -f "$PREFIX/.built-$1" ]; then
    step "$1"
    "build_$1"
    touch "$PREFIX/.built-$1"
  fi
}

# Each source_<name> leaves the unpacked (and patched) source folder in $src.
source_metis() {
  fetch metis_5.1.0.dfsg.orig.tar.xz "$DEBIAN/m/metis/metis_5.1.0.dfsg.orig.tar.xz" \
    c50a88b92b01fa3972c5c92cf50117f126c62589b8f793657c7d865c59c23615
  unpack metis_5.1.0.dfsg.orig.tar.xz metis-5.1.0
  src=$SOURCES/metis-5.1.0
}

cmake_metis() {  # CMake arguments (the toolchain)...: METIS from $src, into $PREFIX
  cmake -S "$src" -B "$OUT/deps/metis" "$@" -DGKLIB_PATH="$src/GKlib" -DSHARED=OFF >/dev/null
  cmake --build "$OUT/deps/metis" -j"$JOBS" --target metis >/dev/null
  cp "$OUT/deps/metis/libmetis/libmetis.a" "$PREFIX/lib/"
  cp "$src/include/metis.h" "$PREFIX/include/"
}

source_gmp() {
  fetch gmp_6.2.1+dfsg1.orig.tar.xz "$DEBIAN/g/gmp/gmp_6.2.1+dfsg1.orig.tar.xz" \
    471b9e463e04362a0124f215afc5f0a4b99caedeeb62634c61bbc12988efa64c
  fetch gmp_6.2.1+dfsg1-1.1.debian.tar.xz "$DEBIAN/g/gmp/gmp_6.2.1+dfsg1-1.1.debian.tar.xz" \
    4e3e324d72fe688e409c716d33b35aa8657f6016cc1aabd5d9c7ec137412e5ef
  unpack gmp_6.2.1+dfsg1.orig.tar.xz gmp-6.2.1
  src=$SOURCES/gmp-6.2.1
  apply_debian_patches "$src" gmp_6.2.1+dfsg1-1.1.debian.tar.xz
  # Debian's source has no doc/ (GFDL); build the library folders only.
  sed -i 's|^SUBDIRS = tests mpn mpz mpq mpf printf scanf rand cxx demos tune doc$|SUBDIRS = mpn mpz mpq mpf printf scanf rand cxx|' "$src/Makefile.in"
  sed -i 's| doc/Makefile | |' "$src/configure"
}

source_suitesparse() {  # only the parts CHOLMOD needs (cmake/portable/suitesparse builds them)
  fetch suitesparse_5.12.0+dfsg.orig.tar.xz "$DEBIAN/s/suitesparse/suitesparse_5.12.0+dfsg.orig.tar.xz" \
    bb106c43049138c19675cd70322e72ff8e4fd8bdcab3a096307fd78488913faf
  [ -d "$SOURCES/SuiteSparse-5.12.0" ] || tar -xf "$SOURCES/suitesparse_5.12.0+dfsg.orig.tar.xz" -C "$SOURCES" \
    --wildcards '*/SuiteSparse_config/*' '*/AMD/*' '*/CAMD/*' '*/COLAMD/*' '*/CCOLAMD/*' '*/CHOLMOD/*'
  src=$SOURCES/SuiteSparse-5.12.0
}

cmake_suitesparse() {  # CMake arguments (the toolchain)...: CHOLMOD from $src, into $PREFIX
  cmake -S cmake/portable/suitesparse -B "$OUT/deps/suitesparse" "$@" -DSUITESPARSE_DIR="$src" \
    -DMETIS_INCLUDE_DIR="$PREFIX/include" -DCMAKE_INSTALL_PREFIX="$PREFIX" >/dev/null
  cmake --build "$OUT/deps/suitesparse" -j"$JOBS" >/dev/null
  cmake --install "$OUT/deps/suitesparse" >/dev/null
}

source_ipopt() {
  fetch coinor-ipopt_3.11.9.orig.tar.gz "$DEBIAN/c/coinor-ipopt/coinor-ipopt_3.11.9.orig.tar.gz" \
    84991b13ce22e4a4aa0756a5db290c2b811bf82ff4e9124d1a71867118e6ab2d
  fetch coinor-ipopt_3.11.9-2.3.debian.tar.xz "$DEBIAN/c/coinor-ipopt/coinor-ipopt_3.11.9-2.3.debian.tar.xz" \
    ffbb7a4b2295af0d183f31d440483118b7a49871df9626cd3b12f29aca445b6b
  unpack coinor-ipopt_3.11.9.orig.tar.gz Ipopt-3.11.9
  src=$SOURCES/Ipopt-3.11.9
  apply_debian_patches "$src" coinor-ipopt_3.11.9-2.3.debian.tar.xz
}

source_lapack() {  # reference BLAS and LAPACK
  fetch lapack_3.11.0.orig.tar.gz "$DEBIAN/l/lapack/lapack_3.11.0.orig.tar.gz" \
    4b9ba79bfd4921ca820e83979db76ab3363155709444a787979e81c22285ffa9
  unpack lapack_3.11.0.orig.tar.gz lapack-3.11.0
  src=$SOURCES/lapack-3.11.0
}

source_mumps() {
  fetch mumps_5.5.1.orig.tar.gz "$DEBIAN/m/mumps/mumps_5.5.1.orig.tar.gz" \
    1abff294fa47ee4cfd50dfd5c595942b72ebfcedce08142a75a99ab35014fa15
  unpack mumps_5.5.1.orig.tar.gz MUMPS_5.5.1
  src=$SOURCES/MUMPS_5.5.1
}

source_zlib() {
  fetch zlib_1.2.13.dfsg.orig.tar.bz2 "$DEBIAN/z/zlib/zlib_1.2.13.dfsg.orig.tar.bz2" \
    71feb7947e3c00ef125f83b79a4e529bde31171e5babe48b391f06758d1ab0a1
  unpack zlib_1.2.13.dfsg.orig.tar.bz2 zlib-1.2.13.dfsg
  src=$SOURCES/zlib-1.2.13.dfsg
}

source_libpng() {
  fetch libpng1.6_1.6.39.orig.tar.gz "$DEBIAN/libp/libpng1.6/libpng1.6_1.6.39.orig.tar.gz" \
    a00e9d2f2f664186e4202db9299397f851aea71b36a35e74910b8820e380d441
  unpack libpng1.6_1.6.39.orig.tar.gz libpng-1.6.39
  src=$SOURCES/libpng-1.6.39
}
