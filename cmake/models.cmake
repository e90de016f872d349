# One model = one folder fmu_src/models/<name>/ with a model.cmake, plus its entry in DFO_MODELS.
# model.cmake sets (paths under fmu_src/):
#   MODEL_ID             the modelIdentifier (the FMUs' file names and their shared libraries)
#   MODEL_DESCRIPTION    the model's description (absolute; FMI 2.0 syntax), the one variable source
#   MODEL_FMI            the FMI versions to build (2, 3)
#   MODEL_PHYSICS        ONE list: the physics sources and headers (no FMI types), numerics included
#   MODEL_CORE           the instance core (core/instance.h's model API)
#   MODEL_FMI2_SIZE      empty: the FMI 2.0 FMU ships MODEL_DESCRIPTION; a size: the model has
#                        structural parameters, fixed to it in FMI 2.0 (a description generated for it)
#   MODEL_CONFIG_HEADER  empty, or the build configuration header generated per FMI version
#                        (gen_model_vars.py --config [SIZE]), shipped in sources/
#   MODEL_SETTINGS       the model's own cache variables (forwarded to the cross sub-builds)
# For each model, dfo_add_model sets DFO_<name>_ID, DFO_<name>_GEN (its generated folder, with
# model_vars.h) and the target <name>_generated, and builds for each FMI version v the shared library
# and .fmu of dfo_fmu() (cmake/fmu.cmake): FMI 2.0 target <ID> in the build folder, FMI 3.0 target
# <ID>_fmi3 in build/fmi3/. The sources/ of an FMU are flat: file names are unique across folders.

# What every FMU holds besides its model: the life cycle and the FMU-state format (core/), the glue.
# Model Exchange: a model whose description declares <ModelExchange> (DFO_MODEL_EXCHANGE in its
# model_vars.h) and whose core provides core/instance_me.h; the glue fmi/fmi<v>_me.c of every model.
set(DFO_CORE_FILES core/instance.h core/instance_common.c core/instance_common.h core/fmu_state.c core/fmu_state.h)
set(DFO_GEN_SCRIPT ${CMAKE_SOURCE_DIR}/fmu_src/gen_model_vars.py)
# the generator loads the package's model-description reader (one parser of the effect table)
set(DFO_GEN_READER ${CMAKE_SOURCE_DIR}/src/dryfriction/model.py)

# Read models/<name>/model.cmake into DFO_<name>_<field>.
macro(dfo_read_model name)
  foreach(f ID DESCRIPTION FMI PHYSICS CORE FMI2_SIZE CONFIG_HEADER SETTINGS)
    unset(MODEL_${f})
  endforeach()
  include(${CMAKE_SOURCE_DIR}/fmu_src/models/${name}/model.cmake)
  foreach(f ID DESCRIPTION FMI PHYSICS CORE FMI2_SIZE CONFIG_HEADER SETTINGS)
    set(DFO_${name}_${f} ${MODEL_${f}})
  endforeach()
  set(DFO_${name}_GEN ${CMAKE_BINARY_DIR}/generated/${name})
  list(APPEND DFO_MODEL_SETTINGS ${MODEL_SETTINGS})
endmacro()

# The include folders of a list of fmu_src/ paths: their folders, once each.
function(dfo_dirs_of out)
  set(dirs "")
  foreach(f ${ARGN})
    get_filename_component(d ${CMAKE_SOURCE_DIR}/fmu_src/${f} DIRECTORY)
    list(APPEND dirs ${d})
  endforeach()
  list(REMOVE_DUPLICATES dirs)
  set(${out} ${dirs} PARENT_SCOPE)
endfunction()

function(dfo_add_model name)
  set(id ${DFO_${name}_ID})
  set(md ${DFO_${name}_DESCRIPTION})
  set(gen ${DFO_${name}_GEN})
  set(size ${DFO_${name}_FMI2_SIZE})
  set(cfg ${DFO_${name}_CONFIG_HEADER})
  set(GEN ${Python3_EXECUTABLE} ${DFO_GEN_SCRIPT} ${md})
  file(MAKE_DIRECTORY ${gen}/fmi2 ${gen}/fmi3)

  # generated: model_vars.h, the FMI 3.0 model and build descriptions, the FMI 2.0 description
  # for a fixed size, the build configuration headers
  set(outputs ${gen}/model_vars.h)
  set(cmds COMMAND ${GEN} ${gen}/model_vars.h)
  if("3" IN_LIST DFO_${name}_FMI)
    list(APPEND outputs ${gen}/fmi3/modelDescription.xml ${gen}/fmi3/buildDescription.xml)
    list(APPEND cmds COMMAND ${GEN} ${gen}/fmi3/modelDescription.xml --fmi3
                     COMMAND ${GEN} ${gen}/fmi3/buildDescription.xml --fmi3-build)
  endif()
  if("2" IN_LIST DFO_${name}_FMI AND NOT "${size}" STREQUAL "")
    list(APPEND outputs ${gen}/fmi2/modelDescription.xml)
    list(APPEND cmds COMMAND ${GEN} ${gen}/fmi2/modelDescription.xml --fmi2 ${size})
  endif()
  if(NOT "${cfg}" STREQUAL "")
    list(APPEND outputs ${gen}/fmi2/${cfg} ${gen}/fmi3/${cfg})
    list(APPEND cmds COMMAND ${GEN} ${gen}/fmi2/${cfg} --config ${size} COMMAND ${GEN} ${gen}/fmi3/${cfg} --config)
  endif()
  add_custom_command(
    OUTPUT ${outputs}
    ${cmds}
    COMMAND ${CMAKE_COMMAND} -E touch ${outputs}
    DEPENDS ${md} ${DFO_GEN_SCRIPT} ${DFO_GEN_READER}
    COMMENT "Generating ${id}'s model_vars.h and descriptions from ${md}")
  add_custom_target(${name}_generated DEPENDS ${outputs})

  # the physics of this model alone, with its own folders
  set(physics ${DFO_${name}_PHYSICS})
  set(physics_c ${physics})
  list(FILTER physics_c INCLUDE REGEX "[.]c$")
  list(TRANSFORM physics_c PREPEND ${CMAKE_SOURCE_DIR}/fmu_src/)
  dfo_dirs_of(physics_dirs ${physics})
  add_library(${name}_physics STATIC ${physics_c})
  target_include_directories(${name}_physics PUBLIC ${physics_dirs})
  set_target_properties(${name}_physics PROPERTIES C_VISIBILITY_PRESET hidden)
  target_link_libraries(${name}_physics PUBLIC m)
  if(DFO_LIBM)
    target_compile_definitions(${name}_physics PUBLIC DFO_USE_LIBM)
  endif()
  dfo_flags(${name}_physics)

  set(core ${DFO_${name}_CORE} ${DFO_CORE_FILES})
  set(core_c ${core})
  list(FILTER core_c INCLUDE REGEX "[.]c$")
  list(TRANSFORM core_c PREPEND ${CMAKE_SOURCE_DIR}/fmu_src/)
  dfo_dirs_of(core_dirs ${core} fmi/fmi2_cs.c)
  set(sources ${physics} ${core})
  list(TRANSFORM sources PREPEND fmu_src/)
  foreach(v ${DFO_${name}_FMI})
    if(v STREQUAL "2")
      set(target ${id})
      set(dir ${CMAKE_BINARY_DIR})
      set(lib_dir ${CMAKE_BINARY_DIR})
      set(headers ${FMI2_HEADERS})
      if("${size}" STREQUAL "")
        set(fmu_md ${md})
      else()
        set(fmu_md ${gen}/fmi2/modelDescription.xml)
      endif()
      set(extra "")
    else()
      set(target ${id}_fmi3)
      set(dir ${CMAKE_BINARY_DIR}/fmi3)
      set(lib_dir ${dir}/lib)
      set(headers ${FMI3_HEADERS})
      set(fmu_md ${gen}/fmi3/modelDescription.xml)
      set(extra ${gen}/fmi3/buildDescription.xml)
    endif()
    if(NOT "${cfg}" STREQUAL "")
      list(APPEND extra ${gen}/fmi${v}/${cfg})
    endif()
    # the glue: co-simulation and Model Exchange (errors for a model without it: DFO_MODEL_EXCHANGE)
    set(glue fmu_src/fmi/fmi${v}_cs.c fmu_src/fmi/fmi${v}_me.c fmu_src/fmi/fmi${v}_glue.h fmu_src/core/instance_me.h)
    set(glue_c ${glue})
    list(FILTER glue_c INCLUDE REGEX "[.]c$")
    list(TRANSFORM glue_c PREPEND ${CMAKE_SOURCE_DIR}/)
    dfo_fmu(${target} FMI ${v} ID ${id} DIR ${dir} LIB_DIR ${lib_dir}
            LIB_SOURCES ${core_c} ${glue_c} LIBS ${name}_physics
            GEN_DIR ${gen} INCLUDE_DIRS ${gen}/fmi${v} ${core_dirs}
            MODEL_DESCRIPTION ${fmu_md}
            SOURCES ${sources} ${glue} ${gen}/model_vars.h ${headers} ${extra}
            DEPENDS ${name}_generated)
  endforeach()
endfunction()
