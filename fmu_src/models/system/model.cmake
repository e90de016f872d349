# The DryFrictionSystem (any linear structure M x'' + C x' + K x = ... + W' f with rigid friction
# contacts), stepped by the friction engine through its generic instance: read by cmake/models.cmake
# (dfo_add_model). Paths are under fmu_src/.
set(DFO_SYSTEM_SIZE "n=2,nc=1" CACHE STRING "Sizes of the FMI 2.0 DryFrictionSystem FMU (fixed when building: n=N,nc=NC)")
set(MODEL_ID DryFrictionSystem)
set(MODEL_DESCRIPTION ${CMAKE_CURRENT_LIST_DIR}/modelDescription.xml)
set(MODEL_FMI 2 3)
# the physics: plain C, no FMI types (the engine and the numerics it uses included)
set(MODEL_PHYSICS numerics/dfo_fp.h numerics/dfo_inline.h numerics/dmath.c numerics/dmath.h numerics/lcp.c numerics/lcp.h
    numerics/friction.c numerics/friction.h numerics/bossak.h numerics/excitation.h numerics/symeig.c numerics/symeig.h
    numerics/roots.c numerics/roots.h engine/engine.c engine/engine_generic.c engine/engine.h
    engine/engine_private.h engine/engine_step.h engine/engine_tangent.h
    models/system/system.c models/system/system.h engine/eng_one_dof.h)
# the instance core (core/instance.h's model API), split by concern (sys_instance.h)
set(MODEL_CORE models/system/sys_instance.c models/system/sys_instance.h models/system/sys_inst_values.c
    models/system/sys_inst_state.c
    models/system/sys_inst_resources.c models/system/sys_inst_resources.h)
# n and nc are structural parameters: FMI 3.0 sets them in configuration mode; an FMI 2.0 build fixes
# them, with its description generated for those sizes and system_config.h saying them
set(MODEL_FMI2_SIZE ${DFO_SYSTEM_SIZE})
set(MODEL_CONFIG_HEADER system_config.h)
set(MODEL_SETTINGS DFO_SYSTEM_SIZE)
