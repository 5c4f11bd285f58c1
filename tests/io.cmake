list(APPEND TEST_SOURCES io/test_mesh_io.cpp)
list(APPEND TEST_SOURCES io/test_solver_files.cpp)
list(APPEND TEST_SOURCES io/test_boundary_segments.cpp)

# deal.II as an independent reader of our MSH files (Debian: libdeal.ii-dev, about 200 packages and 1 GB, which
# scripts/install-deps installs; the tests skip without it). deal.II's CMake setup changes compiler flags, so only
# its own small target uses it, and only in plain Release/Debug builds.
option(POLYSQUARE_DEALII_TEST "Build the deal.II reader test when deal.II is found" ON)
if(POLYSQUARE_DEALII_TEST AND NOT POLYSQUARE_SANITIZE AND NOT POLYSQUARE_FUZZ
   AND CMAKE_BUILD_TYPE MATCHES "^(Release|Debug)$")
  find_package(deal.II 9.3 QUIET HINTS /usr/share/cmake/deal.II)
  if(deal.II_FOUND)
    message(STATUS "deal.II ${DEAL_II_PACKAGE_VERSION} found: building the deal.II MSH reader test")
    add_executable(dealii_read_msh ${CMAKE_CURRENT_SOURCE_DIR}/io/dealii_read_msh.cpp)
    deal_ii_setup_target(dealii_read_msh)
    set_source_files_properties(io/test_mesh_io.cpp PROPERTIES
      COMPILE_DEFINITIONS "POLYSQUARE_DEALII_READER=\"$<TARGET_FILE:dealii_read_msh>\"")
    # The default .msh of every bundled case, meshed with default options at its README size, read by deal.II
    # and by meshio (scripts/read-back-cases: quad counts, boundary ids and physical groups against the report).
    add_test(NAME read_back.every_case_default_msh
             COMMAND ${PROJECT_SOURCE_DIR}/scripts/read-back-cases ${PROJECT_BINARY_DIR}/read-back)
    set_tests_properties(read_back.every_case_default_msh PROPERTIES TIMEOUT 900
      ENVIRONMENT "POLYSQUARE_CLI=$<TARGET_FILE:polysquare_cli>;DEALII_READER=$<TARGET_FILE:dealii_read_msh>")
  else()
    message(STATUS "deal.II not found: the deal.II MSH reader test will be skipped")
  endif()
endif()
list(APPEND TEST_SOURCES io/test_render.cpp)
