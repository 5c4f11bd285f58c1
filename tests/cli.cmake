list(APPEND TEST_SOURCES cli/test_cli.cpp)
list(APPEND TEST_SOURCES cli/test_report.cpp)
list(APPEND TEST_SOURCES cli/test_progress.cpp)
list(APPEND TEST_SOURCES cli/test_cli_outputs.cpp)
