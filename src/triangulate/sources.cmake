# Sources of the triangulate module (relative to this folder).
list(APPEND MODULE_SOURCES)
list(APPEND MODULE_SOURCES background_triangulation.cpp)
