list(APPEND MODULE_SOURCES refine.cpp)
