# Sources of the input module (relative to this folder).
list(APPEND MODULE_SOURCES)
list(APPEND MODULE_SOURCES read_region.cpp)
list(APPEND MODULE_SOURCES split_features.cpp)
list(APPEND MODULE_SOURCES simplify.cpp)
list(APPEND MODULE_SOURCES make_valid.cpp)
list(APPEND MODULE_SOURCES read_gdal.cpp)
list(APPEND MODULE_SOURCES project_region.cpp)
list(APPEND MODULE_SOURCES snap_points.cpp)
