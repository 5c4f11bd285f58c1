list(APPEND TEST_SOURCES cli/test_cli.cpp)
