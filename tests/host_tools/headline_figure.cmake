# The README's picture, docs/results/victoria_park.svg, is what `./geojcbb run victoria` draws with
# the code as it is: Victoria Park converted, replayed with PCJCBB, the estimated antenna track and
# the mapped trees over the GPS fixes (its title gives the GPS RMSE and the landmark count).
#   cmake -DEVAL=<geojcbb_eval> -DWORK=<folder> -DWANT=<docs/results/victoria_park.svg> -P headline_figure.cmake
# Run through with_data.cmake (skipped without the data). GEOJCBB_UPDATE_FIGURES=1 writes WANT
# instead of comparing (what `./geojcbb run victoria` does).
file(MAKE_DIRECTORY "${WORK}")
execute_process(COMMAND "${EVAL}" convert-victoria-park --out "${WORK}/victoria_park.csv" RESULT_VARIABLE rc
                OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "convert-victoria-park: exit status ${rc}")
endif()
execute_process(COMMAND "${EVAL}" replay --log "${WORK}/victoria_park.csv" --strategies PCJCBB --no-progress
                        --out-dir "${WORK}" RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "replay: exit status ${rc}")
endif()
if("$ENV{GEOJCBB_UPDATE_FIGURES}" STREQUAL "1")
  file(COPY_FILE "${WORK}/replay_path.svg" "${WANT}")
  message("written: ${WANT}")
  return()
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${WORK}/replay_path.svg" "${WANT}" RESULT_VARIABLE same)
if(NOT same EQUAL 0)
  message(FATAL_ERROR "${WANT} is not what the code draws now (${WORK}/replay_path.svg): `./geojcbb run victoria` "
                      "draws it again; commit it with the figures it shows")
endif()
message("${WANT}: current")
