# The DryFrictionChain (n blocks in a row, springs and dampers between them, dry friction on each):
# read by cmake/models.cmake (dfo_add_model). Paths are under fmu_src/.
set(DFO_CHAIN_N 2 CACHE STRING "Blocks of the FMI 2.0 DryFrictionChain FMU (fixed when building, 1 ... 4096)")
set(MODEL_ID DryFrictionChain)
set(MODEL_DESCRIPTION ${CMAKE_CURRENT_LIST_DIR}/modelDescription.xml)
set(MODEL_FMI 2 3)
# the physics: plain C, no FMI types (the numerics it uses included)
set(MODEL_PHYSICS numerics/dfo_fp.h numerics/dfo_inline.h numerics/dmath.c numerics/dmath.h numerics/lcp.c numerics/lcp.h
    numerics/friction.c numerics/friction.h numerics/bossak.h numerics/excitation.h numerics/roots.c numerics/roots.h
    engine/engine.h engine/engine_private.h engine/engine_step.h engine/engine_tangent.h engine/engine.c
    models/chain/chain.h models/chain/chain_internal.h models/chain/chain_engine_ops.h models/chain/chain_setup.c
    models/chain/chain_forces.c models/chain/chain_engine.c)
# the instance core (core/instance.h's model API), split by concern (chain_instance.h)
set(MODEL_CORE models/chain/chain_instance.c models/chain/chain_instance.h models/chain/chain_inst_vars.c
    models/chain/chain_inst_step.c models/chain/chain_inst_state.c models/chain/chain_inst_deriv.c models/chain/chain_inst_me.c)
# n is a structural parameter: FMI 3.0 sets it in configuration mode; an FMI 2.0 build fixes it,
# with its description generated for that n (arrays as m[1] ...) and chain_config.h saying it
set(MODEL_FMI2_SIZE ${DFO_CHAIN_N})
set(MODEL_CONFIG_HEADER chain_config.h)
set(MODEL_SETTINGS DFO_CHAIN_N)
