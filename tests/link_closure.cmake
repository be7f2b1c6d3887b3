# The firmware library's ways in link nothing beyond Eigen and the C++ runtime: none of the host
# tools' libraries (Ceres and SuiteSparse, parts of which are GPL; libserialport; glog), read from
# each program's dynamic dependencies (ldd). CLEAN: the programs that must not link them (the C API's
# example, the Python module); LINKED: one that does (geojcbb_eval: Debian's Ceres is a static
# library there, its SuiteSparse shared), so the check is seen to see them.
# Usage: cmake "-DCLEAN=a;b" -DLINKED=c -P link_closure.cmake
set(forbidden "ceres|cholmod|suitesparse|spqr|umfpack|glog|gflags|serialport|lapack|blas")
function(deps file out)
  execute_process(COMMAND ldd ${file} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "ldd ${file} failed")
  endif()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()
foreach(f IN LISTS CLEAN)
  deps(${f} text)
  string(REGEX MATCHALL "lib(${forbidden})[^ \n]*" found "${text}")
  if(found)
    message(FATAL_ERROR "${f} links ${found}")
  endif()
  message(STATUS "${f}: none of ${forbidden}")
endforeach()
deps(${LINKED} text)
if(NOT text MATCHES "libcholmod")  # Debian's Ceres is linked statically, its SuiteSparse dynamically
  message(FATAL_ERROR "${LINKED} shows no libcholmod: the check would not see it")
endif()
message(STATUS "${LINKED} links SuiteSparse's libcholmod, as the host's mapping does")
