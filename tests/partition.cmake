list(APPEND TEST_SOURCES partition/test_partition.cpp)
