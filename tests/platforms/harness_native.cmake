# ctest platform_harness: run fmu_harness on the native FMI 2.0 and 3.0 libraries; fail unless
# (1) no call failed, (2) the two glues print the same outputs and states, (3) every set resumed
# from its serialised state prints the second half of its run bit for bit.
include(${CMAKE_CURRENT_LIST_DIR}/harness_common.cmake)
file(MAKE_DIRECTORY ${WORK})
foreach(v 2 3)
  harness_run(run${v} fmi${v} ${LIB${v}} ${WORK}/states${v}.txt ${WORK}/run${v}.txt)
  harness_check(fmi${v} fmi${v} ${LIB${v}} ${WORK}/states${v}.txt "${run${v}}")
endforeach()
if(NOT run2 STREQUAL run3)
  message(FATAL_ERROR "the FMI 2.0 and FMI 3.0 libraries print different outputs or states")
endif()
message(STATUS "FMI 2.0 and 3.0: identical outputs and states")
