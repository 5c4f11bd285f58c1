list(APPEND TEST_SOURCES core/test_work_sharing.cpp)
