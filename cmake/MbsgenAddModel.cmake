# mbsgen_add_model(<target> MODEL <file> [SCENE <name>] [SOLVER] [OUTPUT_DIR <dir>] [ID <id>]
#                  [PARTS <n>] [DYNAMICS] [SENSITIVITY] [SENSITIVITY_PARAMETERS <name>...])
#
# Generates a model's kernels at build time and compiles them into the static library <target>,
# linked to mbsgen::runtime, with the typed C++ API <id>_model.hpp (namespace <id>: Parameters
# with the model's defaults, enums Coordinate, Input, Output, kernels(), model(), linear_model()).
#
#   MODEL       the model file (YAML); the generator reruns when it (or the mbsgen tool) changes,
#               and only then; unchanged generated files are not rewritten, so not recompiled.
#   SCENE       the scene to generate (default: full)
#   SOLVER      also build the executable <target>-solve (modes, frf, static, matrices, info)
#   OUTPUT_DIR  where the generated files go (default: ${CMAKE_CURRENT_BINARY_DIR}/mbsgen/<target>).
#               Without the mbsgen tool (a build with MBSGEN_BUILD_GENERATOR=OFF), files already
#               present there are compiled as they are, and MODEL may be omitted.
#   ID          C identifier prefix of the kernels and namespace of the API (default: <target>
#               with every character that is not a letter, digit or _ replaced by _)
#   PARTS       for large models (tens of thousands of operations per kernel): the long kernels'
#               parts go to <n> files <id>_part1.cpp … that the build compiles in parallel, at
#               -O1 (faster to compile than -O2, and for large models as fast); default 0
#   DYNAMICS    also emit the kernels of a time step (the solver's `simulate`): <id>_dynamics(y,
#               yd, u, p, M, r), M and k − q in one kernel, and <id>_dynamics_jacobian(y, yd,
#               ydd, u, p, Ky, Kv) (the full model only; not for nonholonomic models)
#   SENSITIVITY also emit the full model's sensitivity kernel (derivatives of the linear matrices
#               by every parameter, for modes/frf --sensitivity); made only when asked (issue 40)
#   SENSITIVITY_PARAMETERS  the sensitivity kernel by these parameters only (implies SENSITIVITY)
#
# Documented in docs/cmake.md.
include_guard(GLOBAL)

function(mbsgen_add_model target)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "SOLVER;DYNAMICS;SENSITIVITY" "MODEL;SCENE;OUTPUT_DIR;ID;PARTS"
                        "SENSITIVITY_PARAMETERS")
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "mbsgen_add_model(${target}): unknown arguments: ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT ARG_SCENE)
    set(ARG_SCENE full)
  endif()
  if(NOT ARG_ID)
    string(MAKE_C_IDENTIFIER "${target}" ARG_ID)
  endif()
  if(NOT ARG_PARTS)
    set(ARG_PARTS 0)
  endif()
  if(NOT ARG_PARTS MATCHES "^[0-9]+$" OR ARG_PARTS GREATER 64)
    message(FATAL_ERROR "mbsgen_add_model(${target}): PARTS must be a number from 0 to 64, not '${ARG_PARTS}'")
  endif()
  if(NOT ARG_OUTPUT_DIR)
    set(ARG_OUTPUT_DIR ${CMAKE_CURRENT_BINARY_DIR}/mbsgen/${target})
  endif()
  get_filename_component(_dir "${ARG_OUTPUT_DIR}" ABSOLUTE BASE_DIR ${CMAKE_CURRENT_BINARY_DIR})
  set(_sources ${_dir}/${ARG_ID}.cpp ${_dir}/${ARG_ID}_model.cpp)
  set(_parts "")
  if(ARG_PARTS GREATER 0)
    foreach(_k RANGE 1 ${ARG_PARTS})
      list(APPEND _parts ${_dir}/${ARG_ID}_part${_k}.cpp)
    endforeach()
    list(APPEND _sources ${_parts})
  endif()
  set(_files ${_sources} ${_dir}/${ARG_ID}.hpp ${_dir}/${ARG_ID}_model.hpp ${_dir}/${ARG_ID}.json)

  if(TARGET mbsgen::mbsgen)
    if(NOT ARG_MODEL)
      message(FATAL_ERROR "mbsgen_add_model(${target}): MODEL <file> is required")
    endif()
    get_filename_component(_model "${ARG_MODEL}" ABSOLUTE)
    if(NOT EXISTS "${_model}")
      message(FATAL_ERROR "mbsgen_add_model(${target}): model file ${_model} does not exist")
    endif()
    # The stamp is the rule's output; the generated files are byproducts that the generator
    # rewrites only when their content changes, so an unchanged kernel is not recompiled.
    set(_stamp ${_dir}/${ARG_ID}.stamp)
    set(_dynamics "")
    if(ARG_DYNAMICS)
      set(_dynamics --dynamics)
    endif()
    if(ARG_SENSITIVITY_PARAMETERS)
      list(JOIN ARG_SENSITIVITY_PARAMETERS "," _names)
      list(APPEND _dynamics --sensitivity-parameters ${_names})
    elseif(ARG_SENSITIVITY)
      list(APPEND _dynamics --sensitivity)
    endif()
    add_custom_command(
      OUTPUT ${_stamp}
      BYPRODUCTS ${_files}
      COMMAND mbsgen::mbsgen generate ${_model} --scene ${ARG_SCENE} --id ${ARG_ID} --parts ${ARG_PARTS}
              --out ${_dir} ${_dynamics}
      COMMAND ${CMAKE_COMMAND} -E touch ${_stamp}
      DEPENDS ${_model} mbsgen::mbsgen
      COMMENT "mbsgen: generating ${ARG_ID} from ${ARG_MODEL} (scene ${ARG_SCENE})"
      VERBATIM)
    add_library(${target} STATIC ${_sources} ${_stamp})
  else()
    foreach(_f IN LISTS _files)
      if(NOT EXISTS ${_f})
        message(FATAL_ERROR "mbsgen_add_model(${target}): no mbsgen tool to generate the model, "
                            "and ${_f} does not exist (build with MBSGEN_BUILD_GENERATOR=ON or "
                            "give OUTPUT_DIR a directory of generated files)")
      endif()
    endforeach()
    add_library(${target} STATIC ${_sources})
  endif()
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${_dir}>)
  target_link_libraries(${target} PUBLIC mbsgen::runtime)
  target_compile_features(${target} PUBLIC cxx_std_17)
  # Generated code is plain arithmetic: optimise it even in debug builds of the consumer.
  target_compile_options(${target} PRIVATE $<$<CXX_COMPILER_ID:GNU,Clang>:-O2>)
  if(_parts)
    set_source_files_properties(${_parts} PROPERTIES
                                COMPILE_OPTIONS $<$<CXX_COMPILER_ID:GNU,Clang>:-O1>)
  endif()
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)

  if(ARG_SOLVER)
    set(_main ${CMAKE_CURRENT_BINARY_DIR}/mbsgen/${target}-solve.cpp)
    file(CONFIGURE OUTPUT ${_main} CONTENT
"// The solver of ${target} (mbsgen_add_model ... SOLVER). Generated: do not edit.
#include \"${ARG_ID}_model.hpp\"
#include \"mbsgen/runtime/cli/solver_cli.hpp\"

int main(int argc, char** argv) { return mbsgen::cli::solver_main(${ARG_ID}::kernels(), argc, argv); }
" @ONLY)
    add_executable(${target}-solve ${_main})
    target_link_libraries(${target}-solve PRIVATE ${target} mbsgen::solver)
  endif()
endfunction()
