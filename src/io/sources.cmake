# Sources of the io module (relative to this folder).
list(APPEND MODULE_SOURCES)
list(APPEND MODULE_SOURCES geojson.cpp)
list(APPEND MODULE_SOURCES atomic_file.cpp)
list(APPEND MODULE_SOURCES msh.cpp)
list(APPEND MODULE_SOURCES vtu_svg.cpp)
list(APPEND MODULE_SOURCES crs_info.cpp)
list(APPEND MODULE_SOURCES solver_files.cpp)
list(APPEND MODULE_SOURCES ugrid.cpp)
