# `cmake --install` of the build into a fresh prefix, then the installed package imported and used
# with the installed mbsgen command (issue 41: "import mbsgen" works after cmake --install).
# -DBUILD=the build tree -DPREFIX=a directory to install into -DPYTHON=the interpreter
# -DMODEL=a model file -DPYDIR=the package directory relative to the prefix
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${PREFIX} RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
set(ENV{PYTHONPATH} ${PREFIX}/${PYDIR})
unset(ENV{MBSGEN})
set(ENV{MBSGEN_CACHE_DIR} ${PREFIX}/cache)
execute_process(
  COMMAND ${PYTHON} -c "import mbsgen, os, sys
assert mbsgen.__file__.startswith(sys.argv[1]), mbsgen.__file__
assert mbsgen.tool() == os.path.join(sys.argv[1], 'bin', 'mbsgen'), mbsgen.tool()
print(mbsgen.Model(sys.argv[2]).modes().natural_frequency_hz)" ${PREFIX} ${MODEL}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the installed package failed:\n${out}${err}")
endif()
message(STATUS "installed package: ${out}")
