list(APPEND TEST_SOURCES map/test_map_stages.cpp)
list(APPEND TEST_SOURCES map/test_ppm.cpp)
list(APPEND TEST_SOURCES map/test_integer_program.cpp)
list(APPEND TEST_SOURCES map/test_interface_turns.cpp)
