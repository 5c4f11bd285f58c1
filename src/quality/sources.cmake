# Sources of the quality module (relative to this folder).
list(APPEND MODULE_SOURCES)
list(APPEND MODULE_SOURCES quality.cpp)
