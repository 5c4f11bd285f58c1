list(APPEND TEST_SOURCES io/test_mesh_io.cpp)
