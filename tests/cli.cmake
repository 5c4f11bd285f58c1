list(APPEND TEST_SOURCES cli/test_cli.cpp)
list(APPEND TEST_SOURCES cli/test_cli_outputs.cpp)
