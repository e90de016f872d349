# FMU packaging over platforms: an FMU is one dfo_fmu() call, whatever its FMI version; the
# platforms are the native one plus every cross target of DFO_CROSS_TARGETS whose toolchain
# (cmake/toolchains/<tuple>.cmake) is usable.

# <arch>-<os> (the FMI 3.0 platform tuple) of a CMAKE_SYSTEM_PROCESSOR and CMAKE_SYSTEM_NAME.
function(dfo_platform_of processor system out)
  string(TOLOWER "${processor}" p)
  if(p MATCHES "^(x86_64|amd64|x64)$")
    set(arch x86_64)
  elseif(p MATCHES "^(aarch64|arm64)$")
    set(arch aarch64)
  elseif(p MATCHES "^(i[3-6]86|x86)$")
    set(arch x86)
  else()
    set(arch ${p})
  endif()
  if(system STREQUAL "Windows")
    set(os windows)
  elseif(system STREQUAL "Darwin")
    set(os darwin)
  else()
    string(TOLOWER "${system}" os)
  endif()
  set(${out} ${arch}-${os} PARENT_SCOPE)
endfunction()

# The FMI 2.0 binaries folder of a tuple (FMI 2.0 names only 32/64-bit Windows, Linux, macOS on
# x86): linux64, win64, darwin64, linux32, win32; empty where FMI 2.0 has no name (aarch64).
function(dfo_fmi2_folder tuple out)
  set(map x86_64-linux=linux64 x86_64-windows=win64 x86_64-darwin=darwin64 x86-linux=linux32
          x86-windows=win32)
  set(folder "")
  foreach(pair ${map})
    string(REPLACE "=" ";" kv ${pair})
    list(GET kv 0 k)
    list(GET kv 1 v)
    if(k STREQUAL tuple)
      set(folder ${v})
    endif()
  endforeach()
  set(${out} "${folder}" PARENT_SCOPE)
endfunction()

function(dfo_shared_suffix tuple out)
  if(tuple MATCHES "-windows$")
    set(${out} .dll PARENT_SCOPE)
  elseif(tuple MATCHES "-darwin$")
    set(${out} .dylib PARENT_SCOPE)
  else()
    set(${out} .so PARENT_SCOPE)
  endif()
endfunction()

# The cross targets to build: DFO_CROSS OFF none; AUTO those whose C compiler is installed (none in
# sanitizer and fuzzer builds); ON all (an error naming the missing compiler otherwise). Not in a cross sub-build. Sets DFO_CROSS_ENABLED.
macro(dfo_cross_detect)
set(DFO_CROSS_ENABLED "")
if(DFO_CROSS STREQUAL "AUTO" AND (DFO_SANITIZE OR DFO_FUZZ))
  message(STATUS "Cross targets: none (AUTO skips them in sanitizer and fuzzer builds)")
elseif(NOT DFO_BINARIES_ONLY AND NOT DFO_CROSS STREQUAL "OFF" AND NOT CMAKE_CROSSCOMPILING)
  set(_dfo_cc_x86_64-windows x86_64-w64-mingw32-gcc-win32 x86_64-w64-mingw32-gcc)
  set(_dfo_cc_aarch64-linux aarch64-linux-gnu-gcc)
  foreach(t ${DFO_CROSS_TARGETS})
    if(t STREQUAL DFO_TUPLE)
      continue()
    endif()
    if(NOT EXISTS ${CMAKE_SOURCE_DIR}/cmake/toolchains/${t}.cmake)
      message(FATAL_ERROR "DFO_CROSS_TARGETS: no toolchain file cmake/toolchains/${t}.cmake")
    endif()
    find_program(_dfo_cc_found_${t} NAMES ${_dfo_cc_${t}})
    if(_dfo_cc_found_${t})
      list(APPEND DFO_CROSS_ENABLED ${t})
    elseif(DFO_CROSS STREQUAL "ON")
      message(FATAL_ERROR "DFO_CROSS=ON: the C compiler for ${t} (${_dfo_cc_${t}}) is not installed")
    else()
      message(STATUS "Cross target ${t} skipped: ${_dfo_cc_${t}} not installed")
    endif()
  endforeach()
  message(STATUS "Cross targets: ${DFO_CROSS_ENABLED}")
endif()
endmacro()

# dfo_fmu(<target> FMI <2|3> ID <modelIdentifier> DIR <dir of the .fmu> [LIB_DIR <dir>]
#         LIB_SOURCES <c files> LIBS <libraries> MODEL_DESCRIPTION <xml>
#         SOURCES <files for sources/> DEPENDS <targets> GEN_DIR <dir of its model_vars.h>
#         [DEFINES <compile definitions>] [INCLUDE_DIRS <dirs>])
# The shared library <target> (file <ID>.so/.dll, only the FMI functions exported, no runtime
# DLL beyond the system's) and, unless DFO_BINARIES_ONLY, <DIR>/<ID>.fmu holding the binaries of
# the native platform and of every enabled cross target (FMI 2.0: only those FMI 2.0 names).
function(dfo_fmu target)
  cmake_parse_arguments(F "" "FMI;ID;DIR;LIB_DIR;MODEL_DESCRIPTION;GEN_DIR"
                        "LIB_SOURCES;LIBS;SOURCES;DEPENDS;DEFINES;INCLUDE_DIRS" ${ARGN})
  if(NOT F_GEN_DIR)
    message(FATAL_ERROR "dfo_fmu(${target}): GEN_DIR (the folder of its model_vars.h) is required")
  endif()
  if(NOT F_LIB_DIR)
    set(F_LIB_DIR ${F_DIR}/lib)
  endif()
  add_library(${target} SHARED ${F_LIB_SOURCES})
  if(F_DEPENDS)
    add_dependencies(${target} ${F_DEPENDS})
  endif()
  target_include_directories(${target} PRIVATE ${F_GEN_DIR} ${F_INCLUDE_DIRS} ${FMI2_HEADERS_DIR})
  if(F_DEFINES)
    target_compile_definitions(${target} PRIVATE ${F_DEFINES})
  endif()
  target_link_libraries(${target} PRIVATE ${F_LIBS})
  set_target_properties(${target} PROPERTIES PREFIX "" OUTPUT_NAME ${F_ID} C_VISIBILITY_PRESET hidden
                        LIBRARY_OUTPUT_DIRECTORY ${F_LIB_DIR} RUNTIME_OUTPUT_DIRECTORY ${F_LIB_DIR}
                        ARCHIVE_OUTPUT_DIRECTORY ${F_LIB_DIR})  # MinGW import libraries: one per folder (Ninja)
  target_link_options(${target} PRIVATE -static-libgcc -Wl,--no-undefined)
  if(WIN32)
    # no import library, no lib prefix; only the dllexport'ed FMI functions are exported
    target_link_options(${target} PRIVATE -Wl,--exclude-all-symbols)
  endif()
  dfo_flags(${target})
  if(DFO_BINARIES_ONLY)
    return()
  endif()

  set(platforms ${DFO_TUPLE} ${DFO_CROSS_ENABLED})
  set(stage ${F_DIR}/stage-${target})
  set(fmu_file ${F_DIR}/${F_ID}.fmu)
  file(RELATIVE_PATH lib_rel ${CMAKE_BINARY_DIR} ${F_LIB_DIR})
  set(copy_cmds "")
  set(lib_deps "")
  foreach(t ${platforms})
    if(F_FMI STREQUAL "2")
      dfo_fmi2_folder(${t} folder)
    else()
      set(folder ${t})
    endif()
    if(folder STREQUAL "")
      continue()
    endif()
    if(t STREQUAL DFO_TUPLE)
      set(lib $<TARGET_FILE:${target}>)
    else()
      dfo_shared_suffix(${t} sfx)
      set(lib ${CMAKE_BINARY_DIR}/cross/${t}/${lib_rel}/${F_ID}${sfx})
      list(APPEND lib_deps ${lib})
      set_property(GLOBAL APPEND PROPERTY DFO_CROSS_BYPRODUCTS_${t} ${lib})
      set_property(GLOBAL APPEND PROPERTY DFO_CROSS_USERS_${t} ${target}_pack)
    endif()
    list(APPEND copy_cmds COMMAND ${CMAKE_COMMAND} -E make_directory ${stage}/binaries/${folder}
                          COMMAND ${CMAKE_COMMAND} -E copy ${lib} ${stage}/binaries/${folder}/)
  endforeach()
  list(TRANSFORM F_SOURCES PREPEND ${CMAKE_SOURCE_DIR}/ REGEX "^fmu_src/" OUTPUT_VARIABLE sources_abs)
  add_custom_command(
    OUTPUT ${fmu_file}
    COMMAND ${CMAKE_COMMAND} -E rm -rf ${stage}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${stage}/sources ${stage}/documentation
    COMMAND ${CMAKE_COMMAND} -E copy ${CMAKE_SOURCE_DIR}/LICENSE ${stage}/documentation/
    COMMAND ${CMAKE_COMMAND} -E copy ${F_MODEL_DESCRIPTION} ${stage}/modelDescription.xml
    ${copy_cmds}
    COMMAND ${CMAKE_COMMAND} -E copy ${sources_abs} ${stage}/sources/
    COMMAND ${CMAKE_COMMAND} -E rm -f ${fmu_file}
    COMMAND ${CMAKE_COMMAND} -E chdir ${stage} ${CMAKE_COMMAND} -E tar cf ${fmu_file} --format=zip
            modelDescription.xml binaries sources documentation
    DEPENDS ${target} ${F_MODEL_DESCRIPTION} ${sources_abs} ${CMAKE_SOURCE_DIR}/LICENSE ${lib_deps}
    COMMENT "Zipping ${fmu_file} (${platforms})"
    VERBATIM)
  add_custom_target(${target}_pack ALL DEPENDS ${fmu_file})
  if(DFO_PYTHON_PACKAGE)
    # the package data: <package>/fmus/ mirrors the build tree (fmi3/ for the FMI 3.0 FMUs)
    file(RELATIVE_PATH fmu_rel ${CMAKE_BINARY_DIR} ${F_DIR})
    install(FILES ${fmu_file} DESTINATION ${DFO_PACKAGE_DIR}/fmus/${fmu_rel})
  endif()
endfunction()

# One custom target per enabled cross target: configure and build the sub-build
# <build>/cross/<tuple> with its toolchain (DFO_BINARIES_ONLY), before the FMUs are zipped.
function(dfo_cross_builds)
  cmake_host_system_information(RESULT ncpu QUERY NUMBER_OF_LOGICAL_CORES)
  set(settings "")
  foreach(var ${DFO_MODEL_SETTINGS}) # the models' own cache settings (MODEL_SETTINGS of model.cmake)
    list(APPEND settings -D${var}=${${var}})
  endforeach()
  foreach(t ${DFO_CROSS_ENABLED})
    get_property(byproducts GLOBAL PROPERTY DFO_CROSS_BYPRODUCTS_${t})
    get_property(users GLOBAL PROPERTY DFO_CROSS_USERS_${t})
    set(dir ${CMAKE_BINARY_DIR}/cross/${t})
    add_custom_target(cross_${t} ALL
      COMMAND ${CMAKE_COMMAND} -S ${CMAKE_SOURCE_DIR} -B ${dir}
              -DCMAKE_TOOLCHAIN_FILE=${CMAKE_SOURCE_DIR}/cmake/toolchains/${t}.cmake
              -DCMAKE_BUILD_TYPE=${CMAKE_BUILD_TYPE} -DDFO_BINARIES_ONLY=ON -DDFO_CROSS=OFF
              -DDFO_TESTS=OFF -DDFO_LIBM=${DFO_LIBM} -DFMI2_HEADERS_DIR=${FMI2_HEADERS_DIR}
              ${settings}
              -DPython3_EXECUTABLE=${Python3_EXECUTABLE} --log-level=WARNING
      COMMAND ${CMAKE_COMMAND} -E env --unset=MAKEFLAGS --unset=MAKELEVEL ${CMAKE_COMMAND} --build ${dir} --parallel ${ncpu}
      BYPRODUCTS ${byproducts}
      COMMENT "Cross-building ${t} in ${dir}"
      VERBATIM)
    foreach(u ${users})
      add_dependencies(${u} cross_${t})
    endforeach()
  endforeach()
endfunction()
