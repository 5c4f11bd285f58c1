# Sources of the pipeline module (relative to this folder).
list(APPEND MODULE_SOURCES invariants.cpp mesh_region.cpp report.cpp check_options.cpp local_frame.cpp)
