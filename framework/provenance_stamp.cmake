# Run at every build (CMakeLists.txt, target mhbench_provenance_stamp) with GIT, SOURCE_DIR and
# OUTPUT: writes OUTPUT, a header that defines MHBENCH_GIT_COMMIT as the commit of the sources in
# SOURCE_DIR, with "+modified" when tracked files differ from it, so that experiment.json and
# report.html never name a commit whose code was not the one built. The header is rewritten only
# when the stamp changes, so an unchanged tree recompiles nothing.
set(stamp unknown)
if(GIT)
  execute_process(COMMAND ${GIT} rev-parse HEAD WORKING_DIRECTORY ${SOURCE_DIR}
                  RESULT_VARIABLE failed OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(NOT failed)
    set(stamp ${commit})
    execute_process(COMMAND ${GIT} status --porcelain --untracked-files=no WORKING_DIRECTORY ${SOURCE_DIR}
                    RESULT_VARIABLE failed OUTPUT_VARIABLE changes OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
    if(failed OR NOT changes STREQUAL "")
      string(APPEND stamp "+modified")
    endif()
  endif()
endif()
set(content "#pragma once\n// Written by framework/provenance_stamp.cmake at build time.\n#define MHBENCH_GIT_COMMIT \"${stamp}\"\n")
if(EXISTS ${OUTPUT})
  file(READ ${OUTPUT} old)
endif()
if(NOT old STREQUAL content)
  file(WRITE ${OUTPUT} "${content}")
endif()
