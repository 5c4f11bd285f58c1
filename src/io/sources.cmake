# Sources of the io module (relative to this folder).
list(APPEND MODULE_SOURCES)
