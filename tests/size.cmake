list(APPEND TEST_SOURCES size/test_size_field.cpp)
list(APPEND TEST_SOURCES size/test_graded.cpp)
list(APPEND TEST_SOURCES size/test_size_attribute.cpp)
