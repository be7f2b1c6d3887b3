# The firmware library and its ways in link nothing beyond the C and C++ runtime: an allow-list, read
# from each program's dynamic dependencies (ldd), so that none of the host tools' libraries (Ceres and
# SuiteSparse, parts of which are GPL; libserialport; glog), and nothing added later, reaches them
# unseen. Eigen is header-only and does not show. README.md, "Licence"; docs/cmake.md, "What links what".
#   CLEAN   the programs on the firmware library and the protocol alone (its example, the C API's
#           example and test, the fuzz corpus runners): the runtime only
#   PYTHON  the Python module: the runtime and libpython (when it links it at all)
#   LINKED  a program that links a host library (geojcbb_eval: Debian's Ceres is a static library
#           there, its SuiteSparse shared), so the check is seen to see one
# Usage: cmake "-DCLEAN=a;b" [-DPYTHON=m] -DLINKED=c -P link_closure.cmake
# The C and C++ runtime (glibc's parts, libstdc++, libgcc), and the sanitizers' runtimes of the
# host-debug-asan preset.
set(runtime "linux-vdso|linux-gate|ld-linux[-_a-z0-9.]*|libc|libm|libmvec|libdl|libpthread|librt|libstdc\\+\\+|libgcc_s|libasan|libubsan|liblsan")
set(python "libpython[0-9.]*")

# The libraries a program links beyond ${allowed} (a regex of names), into ${out}.
function(extra_libraries file allowed out)
  execute_process(COMMAND ldd ${file} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "ldd ${file} failed")
  endif()
  string(REPLACE "\n" ";" lines "${text}")
  set(extra)
  foreach(line IN LISTS lines)
    if(line MATCHES "^[ \t]*([^ \t]+)")
      set(lib ${CMAKE_MATCH_1})
      get_filename_component(name ${lib} NAME)      # /lib64/ld-linux-x86-64.so.2 -> ld-linux-x86-64.so.2
      string(REGEX REPLACE "\\.so.*$" "" name ${name})  # libstdc++.so.6 -> libstdc++
      if(NOT name MATCHES "^(${allowed})$")
        list(APPEND extra ${lib})
      endif()
    endif()
  endforeach()
  set(${out} "${extra}" PARENT_SCOPE)
endfunction()

# Each of `files` links nothing beyond `allowed`, named `what` in the messages.
function(check_only files allowed what)
  foreach(f IN LISTS files)
    extra_libraries(${f} "${allowed}" extra)
    if(extra)
      message(FATAL_ERROR "${f} links beyond ${what}: ${extra}")
    endif()
    message(STATUS "${f}: ${what} only")
  endforeach()
endfunction()
check_only("${CLEAN}" "${runtime}" "the C/C++ runtime")
check_only("${PYTHON}" "${runtime}|${python}" "the C/C++ runtime and libpython")
extra_libraries(${LINKED} "${runtime}" extra)
if(NOT extra MATCHES "libcholmod")  # Debian's Ceres is linked statically, its SuiteSparse dynamically
  message(FATAL_ERROR "${LINKED} shows no libcholmod beyond the runtime: the check would not see it")
endif()
message(STATUS "${LINKED} links SuiteSparse's libcholmod, as the host's mapping does: the allow-list sees it")
