# README.md's commands run: every ```sh block but the first (./scripts/demo, ./scripts/test) and those marked
# `<!-- long: run in bench -->` is run from the repository root against the bundled data, with the README's
# ./build/polysquare replaced by the CLI built here and out/ by a scratch directory (scripts/readme-commands).
# Not under fuzzing (no CLI) nor the sanitizers (the commands check the README, not the code).
if(NOT POLYSQUARE_FUZZ AND NOT POLYSQUARE_SANITIZE)
  find_package(Python3 COMPONENTS Interpreter)
  if(Python3_Interpreter_FOUND)
    add_test(NAME readme.commands
             COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/scripts/readme-commands
                     $<TARGET_FILE:polysquare_cli> ${PROJECT_BINARY_DIR}/readme-commands ${PROJECT_SOURCE_DIR}/README.md)
    set_tests_properties(readme.commands PROPERTIES TIMEOUT 600)
  else()
    message(STATUS "python3 not found: the README command test (readme.commands) is not added")
  endif()
endif()
