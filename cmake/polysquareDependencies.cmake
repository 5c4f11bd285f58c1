# The libraries polysquare links, found the same way when polysquare is built and when an installed polysquare
# is used through find_package(polysquare) (polysquareConfig.cmake includes this file). The library is static by
# default, so a program linking it needs every one of them, not only the public nlohmann-json.
# POLYSQUARE_FIND_PACKAGE is find_package in the build and find_dependency in the installed config (which then
# reports a missing dependency as polysquare not found instead of failing).
if(NOT COMMAND polysquare_find)
  macro(polysquare_find)
    if(POLYSQUARE_FIND_WITH_DEPENDENCY)
      find_dependency(${ARGV})
    else()
      find_package(${ARGV} REQUIRED)
    endif()
  endmacro()
endif()

polysquare_find(CGAL 5.5)
polysquare_find(Eigen3 3.4 NO_MODULE)
polysquare_find(TBB)
polysquare_find(nlohmann_json 3.11)
polysquare_find(spdlog)
polysquare_find(GDAL)

# METIS, LEMON, netCDF and Cairo (pictures): Debian ships no usable CMake package for them (netCDF's pulls
# in HDF5 targets), so each becomes an imported target polysquare::dep_<name> made here, in both places.
foreach(dep IN ITEMS "METIS;metis.h;metis" "LEMON;lemon/matching.h;lemon" "NETCDF;netcdf.h;netcdf"
                    "CAIRO;cairo/cairo.h;cairo")
  list(GET dep 0 name)
  list(GET dep 1 header)
  list(GET dep 2 lib)
  string(TOLOWER ${name} lower)
  if(NOT TARGET polysquare::dep_${lower})
    find_path(${name}_INCLUDE_DIR ${header})
    find_library(${name}_LIBRARY ${lib})
    if(NOT ${name}_INCLUDE_DIR OR NOT ${name}_LIBRARY)
      if(POLYSQUARE_FIND_WITH_DEPENDENCY)
        set(polysquare_FOUND FALSE)
        set(polysquare_NOT_FOUND_MESSAGE "polysquare needs ${name} (${header}, lib${lib})")
        return()  # from this file; polysquareConfig.cmake checks polysquare_FOUND
      endif()
      message(FATAL_ERROR "polysquare needs ${name}: ${header} or lib${lib} not found (scripts/install-deps)")
    endif()
    add_library(polysquare::dep_${lower} UNKNOWN IMPORTED)
    set_target_properties(polysquare::dep_${lower} PROPERTIES IMPORTED_LOCATION "${${name}_LIBRARY}"
                                                              INTERFACE_INCLUDE_DIRECTORIES "${${name}_INCLUDE_DIR}")
  endif()
endforeach()

# COIN-OR Cbc and Clp (quantization's integer programs): Debian ships a pkg-config file, no CMake package.
if(NOT TARGET polysquare::dep_cbc)
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(POLYSQUARE_CBC QUIET IMPORTED_TARGET GLOBAL cbc)
  endif()
  if(NOT POLYSQUARE_CBC_FOUND)
    if(POLYSQUARE_FIND_WITH_DEPENDENCY)
      set(polysquare_FOUND FALSE)
      set(polysquare_NOT_FOUND_MESSAGE "polysquare needs COIN-OR Cbc (pkg-config cbc)")
      return()
    endif()
    message(FATAL_ERROR "polysquare needs COIN-OR Cbc: pkg-config cbc not found (scripts/install-deps)")
  endif()
  add_library(polysquare::dep_cbc ALIAS PkgConfig::POLYSQUARE_CBC)
endif()
