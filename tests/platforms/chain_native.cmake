# ctest chain_harness (and system_harness, WHAT=systems): run the harness on the native libraries of
# a model with structural sizes; fail unless (1) no call failed, (2) every set resumed from its
# serialised state prints the second half of its run bit for bit (FMI 3.0: into an instance of the
# default sizes), (3) FMI 2.0 and FMI 3.0 print the same outputs and states for the sets of the FMI
# 2.0 build's sizes.
include(${CMAKE_CURRENT_LIST_DIR}/harness_common.cmake)
file(MAKE_DIRECTORY ${WORK})
harness_run(run2 fmi2 ${LIB2} ${WORK}/states_run2.txt ${WORK}/run2.txt)
harness_run(run3 fmi3 ${LIB3} ${WORK}/states_run3.txt ${WORK}/run3.txt)
harness_run(fixed3 fmi3 ${LIB3} ${WORK}/states_fixed3.txt ${WORK}/fixed3.txt fixed)
harness_check(run2 fmi2 ${LIB2} ${WORK}/states_run2.txt "${run2}")
harness_check(run3 fmi3 ${LIB3} ${WORK}/states_run3.txt "${run3}")
if(NOT DEFINED WHAT)
  set(WHAT chains)
endif()
if(NOT run2 STREQUAL fixed3)
  message(FATAL_ERROR "the FMI 2.0 and FMI 3.0 ${WHAT} print different outputs or states")
endif()
message(STATUS "FMI 2.0 and 3.0 ${WHAT}: identical outputs and states")
