list(APPEND MODULE_SOURCES split_triangles.cpp patch.cpp patch_valence.cpp perfect_matching.cpp)
# LEMON 1.3's headers do not compile as C++20 (std::allocator::construct): its one user is C++17.
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/perfect_matching.cpp PROPERTIES COMPILE_OPTIONS "-std=c++17")
