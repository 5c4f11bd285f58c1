list(APPEND TEST_SOURCES map/test_map_stages.cpp)
