# Sources of the input module (relative to this folder).
list(APPEND MODULE_SOURCES)
list(APPEND MODULE_SOURCES read_region.cpp)
list(APPEND MODULE_SOURCES split_features.cpp)
list(APPEND MODULE_SOURCES simplify.cpp)
list(APPEND MODULE_SOURCES make_valid.cpp)
