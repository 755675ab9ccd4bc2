# A study under MPI with 2 ranks gives the same files as one process (issue 20 §2): the samples
# (every evaluation's parameters and quantities) and the bands, byte for byte.
#   cmake -DSOLVER=… -DMPIEXEC=… -DOUT=… -P check_study_mpi.cmake
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
set(_study study --parameter k_al_z=lognormal:891:2 --parameter m_stapes=lognormal:3e-6:1.3
    --parameter k_eardrum_z=lognormal:1000:1.5 --design latin-hypercube --samples 301 --seed 5
    --input P --output v_stapes --from 100 --to 10000 --points 40 --at 500,1000,4000)
execute_process(COMMAND ${SOLVER} ${_study} --write-samples ${OUT}/one.csv --bands ${OUT}/one_bands.csv
                RESULT_VARIABLE rc1 OUTPUT_VARIABLE out1 ERROR_VARIABLE err1)
if(NOT rc1 EQUAL 0)
  message(FATAL_ERROR "one process failed (${rc1}): ${out1}${err1}")
endif()
execute_process(COMMAND ${MPIEXEC} -n 2 --oversubscribe ${SOLVER} ${_study} --write-samples ${OUT}/two.csv
                        --bands ${OUT}/two_bands.csv
                RESULT_VARIABLE rc2 OUTPUT_VARIABLE out2 ERROR_VARIABLE err2)
if(NOT rc2 EQUAL 0)
  message(FATAL_ERROR "mpirun -n 2 failed (${rc2}): ${out2}${err2}")
endif()
if(NOT out2 MATCHES "MPI, 2 ranks")
  message(FATAL_ERROR "the run under mpirun did not run on 2 ranks:\n${out2}")
endif()
foreach(_f "" _bands)
  file(READ ${OUT}/one${_f}.csv a)
  file(READ ${OUT}/two${_f}.csv b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "one${_f}.csv and two${_f}.csv differ (in ${OUT})")
  endif()
endforeach()
string(REGEX MATCHALL "\n" _lines "${a}")
message(STATUS "2 ranks gave the same samples and bands as 1 process")
