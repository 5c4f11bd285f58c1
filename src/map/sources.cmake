# Sources of the map module (relative to this folder).
list(APPEND MODULE_SOURCES)
list(APPEND MODULE_SOURCES deform.cpp)
list(APPEND MODULE_SOURCES layout.cpp)
list(APPEND MODULE_SOURCES integer_program.cpp)
list(APPEND MODULE_SOURCES quantize.cpp)
list(APPEND MODULE_SOURCES extract.cpp)
list(APPEND MODULE_SOURCES polysquare_map.cpp)
list(APPEND MODULE_SOURCES piecewise_map.cpp)
