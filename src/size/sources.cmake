# Sources of the size module (relative to this folder): the size field of graded meshes.
list(APPEND MODULE_SOURCES size_field.cpp size_conformity.cpp)
