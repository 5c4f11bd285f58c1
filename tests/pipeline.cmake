list(APPEND TEST_SOURCES pipeline/test_cases.cpp)
list(APPEND TEST_SOURCES pipeline/test_hard_geometry.cpp)
list(APPEND TEST_SOURCES pipeline/test_gpm.cpp)
list(APPEND TEST_SOURCES pipeline/test_fallback.cpp)
