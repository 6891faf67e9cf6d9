# The dependencies as the Debian packages install them (scripts/setup.sh): shared libraries, for the
# build the tests, the CLI and the benchmark use. Defines the interface target qgp_dependencies.
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(PkgConfig REQUIRED)
pkg_check_modules(IPOPT REQUIRED IMPORTED_TARGET ipopt)
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
find_library(GMP_LIBRARY gmp REQUIRED)
find_library(GMPXX_LIBRARY gmpxx REQUIRED)
find_path(NLOHMANN_JSON_INCLUDE_DIR nlohmann/json.hpp REQUIRED)
find_path(CLI11_INCLUDE_DIR CLI/CLI.hpp REQUIRED)
find_package(Threads REQUIRED)

add_library(qgp_dependencies INTERFACE)
target_include_directories(qgp_dependencies SYSTEM INTERFACE ${CHOLMOD_INCLUDE_DIR} ${NLOHMANN_JSON_INCLUDE_DIR})
target_link_libraries(qgp_dependencies INTERFACE
  Eigen3::Eigen PkgConfig::IPOPT
  ${CHOLMOD_LIBRARY} ${GMPXX_LIBRARY} ${GMP_LIBRARY} Threads::Threads ${CMAKE_DL_LIBS})
