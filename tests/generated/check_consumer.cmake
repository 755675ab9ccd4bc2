# cmake --install into WORK/prefix, then configure, build and run examples/consumer against it
# (with CONSUMER_CXX_FLAGS and CONSUMER_LINKER_FLAGS when given: the sanitizers of the build).
file(REMOVE_RECURSE ${WORK})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  if(NOT _rc EQUAL 0)
    string(REPLACE ";" " " _cmd "${ARGN}")
    message(FATAL_ERROR "failed (${_rc}): ${_cmd}\n${_out}")
  endif()
  set(_last_output "${_out}" PARENT_SCOPE)
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK}/prefix)
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/consumer -B ${WORK}/build
    -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release
    "-DCMAKE_CXX_FLAGS=${CONSUMER_CXX_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${CONSUMER_LINKER_FLAGS}")
run(${CMAKE_COMMAND} --build ${WORK}/build -j2)
run(${WORK}/build/pendulum_consumer)
message("${_last_output}")
if(NOT _last_output MATCHES "ok")
  message(FATAL_ERROR "examples/consumer did not report ok")
endif()
run(${WORK}/build/pendulum-solve modes --format csv)
message("${_last_output}")
# Incremental: a second build does nothing (no regeneration).
run(${CMAKE_COMMAND} --build ${WORK}/build -j2)
if(_last_output MATCHES "mbsgen: generating")
  message(FATAL_ERROR "a second build regenerated the model:\n${_last_output}")
endif()
