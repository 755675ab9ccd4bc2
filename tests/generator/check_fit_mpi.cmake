# `fit --starts N` under MPI with 2 ranks gives the same estimates, minima and costs as one
# process (issue 42): each start's solve is deterministic, wherever it runs.
#   cmake -DMBSGEN=… -DMPIEXEC=… -DSOURCE=… -DOUT=… -P check_fit_mpi.cmake
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
set(ENV{MBSGEN_CACHE_DIR} ${OUT}/cache)
set(_fit run ${SOURCE}/models/middle_ear/middle_ear.yaml -- fit --data ${SOURCE}/examples/fitting/middle_ear_points.csv
    --input P --output v_stapes --parameter kr_aml_x=1e-9:1e9:x3 --parameter k_al_z=1e-9:1e9:x3
    --parameter d_cochlea_z=1e-9:1e9:x3 --starts 6 --threads 1 --format json)
execute_process(COMMAND ${MBSGEN} ${_fit} RESULT_VARIABLE rc1 OUTPUT_VARIABLE out1 ERROR_VARIABLE err1)
if(NOT rc1 EQUAL 0)
  message(FATAL_ERROR "one process failed (${rc1}): ${out1}${err1}")
endif()
execute_process(COMMAND ${MPIEXEC} -n 2 --oversubscribe ${MBSGEN} ${_fit}
                RESULT_VARIABLE rc2 OUTPUT_VARIABLE out2 ERROR_VARIABLE err2)
if(NOT rc2 EQUAL 0)
  message(FATAL_ERROR "mpirun -n 2 failed (${rc2}): ${out2}${err2}")
endif()
if(NOT out2 MATCHES "the starts on MPI, 2 ranks")
  message(FATAL_ERROR "the fit under mpirun did not run on 2 ranks:\n${out2}")
endif()
foreach(_part "\"parameters\": \\[[^]]*\\]" "\"minima\": \\[[^\n]*" "\"cost\": [^,]*")
  string(REGEX MATCH "${_part}" a "${out1}")
  string(REGEX MATCH "${_part}" b "${out2}")
  if(a STREQUAL "" OR NOT a STREQUAL b)
    message(FATAL_ERROR "one process and 2 ranks differ in ${_part}:\n${a}\n${b}")
  endif()
endforeach()
message(STATUS "2 ranks gave the same fit as 1 process")
