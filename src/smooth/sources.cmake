list(APPEND MODULE_SOURCES smooth.cpp untangle.cpp)
