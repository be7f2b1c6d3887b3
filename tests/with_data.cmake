# A CTest command that needs a real data set (README.md, "Data"; docs/data.md):
#   cmake -DDATA_DIR=<default folder> -DDATA_ENV=<variable that overrides it> -DDATA_NAME=<name>
#         -DCOMMAND=<command;args...> -P with_data.cmake
# runs the command when the folder is there (and fails with it). When it is absent the test is
# skipped (it prints "skipped: ..."; the test's SKIP_REGULAR_EXPRESSION matches), or fails when
# GEOJCBB_REQUIRE_DATA=1 (CI), as tests/support/data.hpp does for the unit tests.
set(dir "${DATA_DIR}")
if(DEFINED ENV{${DATA_ENV}} AND NOT "$ENV{${DATA_ENV}}" STREQUAL "")
  set(dir "$ENV{${DATA_ENV}}")
endif()
if(NOT IS_DIRECTORY "${dir}")
  set(why "the ${DATA_NAME} data are not at '${dir}' (set ${DATA_ENV}, or see README.md, \"Data\", for where to get them)")
  if("$ENV{GEOJCBB_REQUIRE_DATA}" STREQUAL "1")
    message(FATAL_ERROR "GEOJCBB_REQUIRE_DATA=1 and ${why}")
  endif()
  message("skipped: ${why}")
  return()
endif()
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "exit status ${rc}: ${COMMAND}")
endif()
