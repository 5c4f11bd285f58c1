# Sources of the core module (relative to this folder).
list(APPEND MODULE_SOURCES)
list(APPEND MODULE_SOURCES version.cpp)
list(APPEND MODULE_SOURCES quad_topology.cpp)
list(APPEND MODULE_SOURCES work_sharing.cpp)
list(APPEND MODULE_SOURCES place_text.cpp)
