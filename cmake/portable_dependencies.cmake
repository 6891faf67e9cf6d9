# Every dependency linked statically into libqgp.so, for the extension zip that loads on glibc 2.28
# and later (scripts/build_portable.sh drives this with Zig's C/C++ compilers targeting glibc 2.28).
# C and Fortran code comes from Debian's static archives: a static archive holds unversioned symbol
# references, so the link binds them to the glibc 2.28 versions. C++ code must use one standard
# library (Zig's libc++), so Ipopt is built from Debian's sources into
# QGP_PORTABLE_PREFIX, with METIS (Debian ships no static METIS). Headers come from that prefix and
# from dedicated folders only: /usr/include itself holds glibc 2.36's headers, which must not be seen.
# Defines the interface target qgp_dependencies.
set(QGP_PORTABLE_PREFIX "" CACHE PATH "Static Ipopt, METIS and private headers (scripts/build_portable.sh)")
if(NOT EXISTS "${QGP_PORTABLE_PREFIX}/lib/libipopt.a")
  message(FATAL_ERROR "QGP_PORTABLE_PREFIX (${QGP_PORTABLE_PREFIX}) holds no lib/libipopt.a; run scripts/build_portable.sh")
endif()
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Threads REQUIRED)

set(_debian_lib /usr/lib/x86_64-linux-gnu)
set(_prefix_lib ${QGP_PORTABLE_PREFIX}/lib)
# In link order.
include(${CMAKE_CURRENT_LIST_DIR}/static_archive_group.cmake)
qgp_static_archive_group(_archive_group "run scripts/setup.sh and scripts/build_portable.sh"
  ${_prefix_lib}/libipopt.a
  ${_debian_lib}/libdmumps_seq.a ${_debian_lib}/libmumps_common_seq.a ${_debian_lib}/libpord_seq.a
  ${_debian_lib}/libmpiseq_seq.a ${_debian_lib}/libesmumps.a ${_debian_lib}/libscotch.a
  ${_debian_lib}/libscotcherr.a ${_prefix_lib}/libcholmod.a ${_prefix_lib}/libmetis.a
  ${_debian_lib}/openblas-serial/libopenblas.a ${_prefix_lib}/libgmp.a
  ${_debian_lib}/libz.a ${_debian_lib}/libbz2.a ${_debian_lib}/liblzma.a)
# The Fortran runtime (MUMPS and LAPACK are Fortran) stays shared: GCC's static libgfortran uses
# local-exec TLS, which a shared library cannot hold. These two are the manylinux_2_28 builds
# (GCC 14, glibc 2.27 symbols) that build_portable.sh takes from a pinned PyPI wheel.
file(GLOB _fortran_runtime ${_prefix_lib}/libgfortran-*.so.5.0.0 ${_prefix_lib}/libquadmath-*.so.0.0.0)
list(LENGTH _fortran_runtime _fortran_runtime_count)
if(NOT _fortran_runtime_count EQUAL 2)
  message(FATAL_ERROR "expected one libgfortran and one libquadmath in ${_prefix_lib}: ${_fortran_runtime}")
endif()

add_library(qgp_dependencies INTERFACE)
target_include_directories(qgp_dependencies SYSTEM INTERFACE
  ${QGP_PORTABLE_PREFIX}/include ${QGP_PORTABLE_PREFIX}/include/coin ${QGP_PORTABLE_PREFIX}/include/suitesparse)
# QGP_STATIC_OPENBLAS: core/blas_kernels.cpp pins the static OpenBLAS's kernels by direct calls.
target_compile_definitions(qgp_dependencies INTERFACE HAVE_CSTDDEF QGP_STATIC_OPENBLAS)
target_link_options(qgp_dependencies INTERFACE -Wl,--strip-debug)  # 115 MB with the archives' debug info
target_link_libraries(qgp_dependencies INTERFACE Eigen3::Eigen
  "${_archive_group}" ${_fortran_runtime} m dl Threads::Threads)
