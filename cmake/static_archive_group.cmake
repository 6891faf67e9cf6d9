# Shared by portable_dependencies.cmake and windows_dependencies.cmake.
# qgp_static_archive_group(OUT HINT archive...): fails naming the first archive that is missing (HINT
# says what builds it), else sets OUT to one linker group of the archives, in the order given (they
# refer to one another: MUMPS, METIS, the BLAS, ...).
function(qgp_static_archive_group out hint)
  foreach(archive IN LISTS ARGN)
    if(NOT EXISTS "${archive}")
      message(FATAL_ERROR "static archive missing: ${archive} (${hint})")
    endif()
  endforeach()
  string(REPLACE ";" " " text "${ARGN}")
  set(${out} "-Wl,--start-group ${text} -Wl,--end-group" PARENT_SCOPE)
endfunction()
