list(APPEND TEST_SOURCES core/test_work_sharing.cpp)
list(APPEND TEST_SOURCES core/test_place_text.cpp)
