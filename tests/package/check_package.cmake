# CTest: configure, build and run a downstream project (this folder's CMakeLists.txt) that reaches
# geojcbb by MODE = find_package | add_subdirectory | fetchcontent, from a clean directory.
#   MODE, GEOJCBB_SOURCE_DIR (geojcbb's source tree), SOURCE_DIR (the consumer), WORK_DIR (scratch)
# Every package geojcbb's tools and tests use is disabled (CMAKE_DISABLE_FIND_PACKAGE_<name>), so a
# consumer that needed more than Eigen fails to configure.
file(REMOVE_RECURSE ${WORK_DIR})
set(no_extras)
foreach(p doctest CLI11 nlohmann_json PkgConfig Threads MRPT)
  list(APPEND no_extras -DCMAKE_DISABLE_FIND_PACKAGE_${p}=ON)
endforeach()

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
endfunction()

set(consumer_args)
if(MODE STREQUAL "find_package")
  # A fresh geojcbb configure (tools and tests off, as a packager would) installed to a prefix.
  run("geojcbb configure" ${CMAKE_COMMAND} -S ${GEOJCBB_SOURCE_DIR} -B ${WORK_DIR}/geojcbb-build -G Ninja
      -DGEOJCBB_BUILD_TOOLS=OFF -DGEOJCBB_BUILD_TESTS=OFF ${no_extras})
  run("install" ${CMAKE_COMMAND} --install ${WORK_DIR}/geojcbb-build --prefix ${WORK_DIR}/prefix)
  if(NOT EXISTS ${WORK_DIR}/prefix/lib/cmake/geojcbb/geojcbbConfigVersion.cmake)
    message(FATAL_ERROR "no geojcbbConfigVersion.cmake in the installed package")
  endif()
  file(READ ${WORK_DIR}/prefix/lib/cmake/geojcbb/geojcbbConfigVersion.cmake version_file)
  if(NOT version_file MATCHES "set\\(PACKAGE_VERSION \"[0-9]+\\.[0-9]+\\.[0-9]+\"\\)")
    message(FATAL_ERROR "the package config carries no version")
  endif()
  list(APPEND consumer_args -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
else()
  list(APPEND consumer_args -DGEOJCBB_SOURCE_DIR=${GEOJCBB_SOURCE_DIR})
endif()
run("consumer configure (${MODE})" ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G Ninja
    -DGEOJCBB_CONSUME=${MODE} ${consumer_args} ${no_extras})
# Only what the consumer links (a vendored geojcbb also defines its float pipeline library).
run("consumer build (${MODE})" ${CMAKE_COMMAND} --build ${WORK_DIR}/build --target consumer)
run("consumer run (${MODE})" ${WORK_DIR}/build/consumer)
message(STATUS "${MODE}: a consumer of geojcbb::firmware configured, built and ran with only Eigen")
