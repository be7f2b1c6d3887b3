# CTest: the bindings install into a fresh virtual environment offline, as docs/python.md says:
#   python3 -m venv --system-site-packages VENV && VENV/bin/pip install --no-build-isolation --no-index SRC
# then the installed module imports and associates. PYTHON, SRC, VENV (scratch, under the build tree).
file(REMOVE_RECURSE ${VENV})
get_filename_component(parent ${VENV} DIRECTORY)  # not the source folder: its geojcbb/ would shadow
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err WORKING_DIRECTORY ${parent})
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
endfunction()
run("venv" ${PYTHON} -m venv --system-site-packages ${VENV})
run("pip install" ${CMAKE_COMMAND} -E env PIP_NO_INDEX=1 PIP_DISABLE_PIP_VERSION_CHECK=1
    ${VENV}/bin/pip install --no-build-isolation --no-index ${SRC})
run("import" ${VENV}/bin/python -c
    "import geojcbb, numpy as np; r = geojcbb.associate(np.array([[5.0, 0.1]]), 0.01 * np.eye(2)[None], np.array([[5.05, 0.1]]), 0.02 * np.eye(2), np.array([7]), strategy='JCBB'); assert r['feature'][0] == 7, r; assert 'site-packages' in geojcbb.__file__")
file(REMOVE_RECURSE ${VENV})
message(STATUS "pip install --no-build-isolation --no-index: installed, imported, associated")
