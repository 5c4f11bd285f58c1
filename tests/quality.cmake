list(APPEND TEST_SOURCES quality/test_gmsh_reference.cpp)
