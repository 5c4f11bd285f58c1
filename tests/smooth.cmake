list(APPEND TEST_SOURCES smooth/test_untangle.cpp)
