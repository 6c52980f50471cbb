# Runs clang-format --dry-run --Werror over the tracked C++ files of ROOT (git ls-files), or
# over the source folders when ROOT is not a git checkout. Fails on the first violation.
find_program(GIT git)
set(files "")
if(GIT)
  execute_process(COMMAND ${GIT} -C ${ROOT} ls-files *.h *.hpp *.cc *.cpp
    OUTPUT_VARIABLE listed RESULT_VARIABLE git_rc OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(git_rc EQUAL 0)
    string(REPLACE "\n" ";" files "${listed}")
  endif()
endif()
if(NOT files)
  file(GLOB_RECURSE files RELATIVE ${ROOT} ${ROOT}/include/*.h ${ROOT}/src/*.h ${ROOT}/src/*.cc
    ${ROOT}/tests/*.h ${ROOT}/tests/*.cc ${ROOT}/apps/*.h ${ROOT}/apps/*.cc ${ROOT}/python/*.cc
    ${ROOT}/benchmarks/*.cc ${ROOT}/examples/*.cc)
endif()
execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror ${files} WORKING_DIRECTORY ${ROOT}
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "clang-format: the files above differ from their formatted form; "
    "run clang-format -i on them")
endif()
list(LENGTH files n)
message(STATUS "clang-format: ${n} files formatted")
