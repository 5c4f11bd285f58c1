list(APPEND MODULE_SOURCES split_triangles.cpp)
