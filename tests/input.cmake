list(APPEND TEST_SOURCES input/test_bad_input.cpp)
