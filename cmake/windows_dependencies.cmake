# Every dependency linked statically into qgp.dll and qgp.exe for Windows x64, cross-compiled with
# mingw-w64 (scripts/build_windows.sh builds them into QGP_WINDOWS_PREFIX from Debian's sources).
# The GCC, C++, Fortran and winpthread runtimes are linked statically too: both files need no DLL
# beyond Windows' own. Defines the interface target qgp_dependencies (and the CLI's PNG).
set(QGP_WINDOWS_PREFIX "" CACHE PATH "Cross-built static dependencies (scripts/build_windows.sh)")
set(_prefix_lib ${QGP_WINDOWS_PREFIX}/lib)
# In link order.
include(${CMAKE_CURRENT_LIST_DIR}/static_archive_group.cmake)
qgp_static_archive_group(_archive_group "run scripts/build_windows.sh"
  ${_prefix_lib}/libipopt.a ${_prefix_lib}/libdmumps.a
  ${_prefix_lib}/libmumps_common.a ${_prefix_lib}/libpord.a ${_prefix_lib}/libmpiseq.a
  ${_prefix_lib}/libcholmod.a ${_prefix_lib}/libmetis.a ${_prefix_lib}/liblapack.a
  ${_prefix_lib}/libblas.a ${_prefix_lib}/libgmpxx.a ${_prefix_lib}/libgmp.a)

add_library(qgp_dependencies INTERFACE)
# Eigen is header-only; its folder holds nothing else (/usr/include itself must not be seen).
target_include_directories(qgp_dependencies SYSTEM INTERFACE /usr/include/eigen3
  ${QGP_WINDOWS_PREFIX}/include ${QGP_WINDOWS_PREFIX}/include/coin ${QGP_WINDOWS_PREFIX}/include/suitesparse)
target_compile_definitions(qgp_dependencies INTERFACE HAVE_CSTDDEF)
target_link_options(qgp_dependencies INTERFACE -static -static-libgcc -static-libstdc++)
target_link_libraries(qgp_dependencies INTERFACE
  "${_archive_group}" -lgfortran -lquadmath -lpthread)

add_library(qgp_png INTERFACE)  # the CLI's `qgp stitch`
target_link_libraries(qgp_png INTERFACE ${_prefix_lib}/libpng16.a ${_prefix_lib}/libz.a)
target_include_directories(qgp_png SYSTEM INTERFACE ${QGP_WINDOWS_PREFIX}/include)
add_library(PNG::PNG ALIAS qgp_png)
set(CLI11_INCLUDE_DIR ${QGP_WINDOWS_PREFIX}/include)
