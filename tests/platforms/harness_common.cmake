# What the ctest scripts harness_native.cmake and chain_native.cmake share (include() them with
# HARNESS and WORK defined): running a harness and checking a run.

get_filename_component(HARNESS_NAME ${HARNESS} NAME_WE)

# harness_run(VAR FMI LIB STATES OUT [fixed]): run HARNESS FMI LIB run STATES [fixed] into the file
# OUT; its "out", "state" and "err" lines into VAR.
function(harness_run var fmi lib states out)
  execute_process(COMMAND ${HARNESS} ${fmi} ${lib} run ${states} ${ARGN} OUTPUT_FILE ${out} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${HARNESS_NAME} ${fmi} run ${ARGN} failed (${rc})")
  endif()
  file(STRINGS ${out} lines)
  list(FILTER lines INCLUDE REGEX "^(out|state|err) ")
  set(${var} "${lines}" PARENT_SCOPE)
endfunction()

# harness_check(NAME FMI LIB STATES LINES): fail unless the run's LINES hold no failed call and every
# set resumed from its serialised state in STATES prints the second half of its run bit for bit.
function(harness_check name fmi lib states lines)
  set(errs ${lines})
  list(FILTER errs INCLUDE REGEX "^err ")
  if(errs)
    list(GET errs 0 first)
    message(FATAL_ERROR "${name}: failed calls, first: ${first}")
  endif()
  execute_process(COMMAND ${HARNESS} ${fmi} ${lib} resume ${states}
                  OUTPUT_FILE ${WORK}/resume_${name}.txt RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${HARNESS_NAME} ${fmi} resume failed (${rc})")
  endif()
  file(STRINGS ${WORK}/resume_${name}.txt resumed)
  set(second ${lines})
  list(FILTER second INCLUDE REGEX "^out [0-9]+ (9|1[0-6]) ")
  if(NOT second STREQUAL resumed)
    message(FATAL_ERROR "${name}: the runs resumed from serialised states differ from the originals")
  endif()
  list(LENGTH lines n)
  message(STATUS "${name}: ${n} lines, resumed runs identical")
endfunction()
