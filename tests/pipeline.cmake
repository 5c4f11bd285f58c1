list(APPEND TEST_SOURCES pipeline/test_cases.cpp)
