# Writes OUT (a header) with the source tree's git commit and whether it has uncommitted
# changes, at every build; the file is replaced only when that changes, so only
# engine/provenance.cpp recompiles. Run by the git_info target (CMakeLists.txt):
#   cmake -DSRC=dir -DOUT=file -P cmake/git_info.cmake
set(commit "unknown")
set(dirty "unknown")
find_package(Git QUIET)
if(GIT_FOUND AND EXISTS "${SRC}/.git")
  execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SRC}" rev-parse HEAD OUTPUT_VARIABLE c
                  RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(rc EQUAL 0)
    set(commit "${c}")
    execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SRC}" status --porcelain --untracked-files=no
                    OUTPUT_VARIABLE st RESULT_VARIABLE rc2 ERROR_QUIET)
    if(rc2 EQUAL 0)
      if(st STREQUAL "")
        set(dirty "false")
      else()
        set(dirty "true")
      endif()
    endif()
  endif()
endif()
file(WRITE "${OUT}.new" "#define SHOCKMPM_GIT_COMMIT \"${commit}\"\n#define SHOCKMPM_GIT_DIRTY \"${dirty}\"\n")
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different "${OUT}.new" "${OUT}")
file(REMOVE "${OUT}.new")
