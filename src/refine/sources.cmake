list(APPEND MODULE_SOURCES refine.cpp local_patch.cpp relax_valences.cpp)
