# Sources of the partition module (relative to this folder).
list(APPEND MODULE_SOURCES partition.cpp separators.cpp)
