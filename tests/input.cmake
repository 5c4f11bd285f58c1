list(APPEND TEST_SOURCES input/test_bad_input.cpp)
list(APPEND TEST_SOURCES input/test_split_features.cpp)
list(APPEND TEST_SOURCES input/test_simplify.cpp)
list(APPEND TEST_SOURCES input/test_gdal_input.cpp)
