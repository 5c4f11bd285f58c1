list(APPEND TEST_SOURCES quality/test_gmsh_reference.cpp)
list(APPEND TEST_SOURCES quality/test_pinned_corners.cpp)
list(APPEND TEST_SOURCES quality/test_quality_refusals.cpp)
list(APPEND TEST_SOURCES quality/test_schism_checks.cpp)
