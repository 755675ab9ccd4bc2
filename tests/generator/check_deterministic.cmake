# Generates MODEL (or its scene SCENE) three times into separate directories (separate
# processes, so GiNaC's address-seeded hashes differ) and fails unless the files are
# byte-identical.
set(_scene)
if(DEFINED SCENE)
  set(_scene --scene ${SCENE})
endif()
foreach(_run a b c)
  execute_process(COMMAND ${MBSGEN} generate ${MODEL} ${_scene} --id det --out ${OUT}/${_run}
                  RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "mbsgen generate failed (${_rc})")
  endif()
endforeach()
foreach(_ext hpp cpp json)
  file(READ ${OUT}/a/det.${_ext} _a)
  file(READ ${OUT}/b/det.${_ext} _b)
  file(READ ${OUT}/c/det.${_ext} _c)
  if(NOT _a STREQUAL _b OR NOT _a STREQUAL _c)
    message(FATAL_ERROR "det.${_ext} differs between two runs of mbsgen generate")
  endif()
endforeach()
