# The TwoMass model (two masses, a friction contact between them and one of mass 1 on the ground),
# stepped by the friction engine: read by cmake/models.cmake (dfo_add_model). Paths are under fmu_src/.
set(MODEL_ID TwoMass)
set(MODEL_DESCRIPTION ${CMAKE_CURRENT_LIST_DIR}/modelDescription.xml)
set(MODEL_FMI 2 3)
# the physics: plain C, no FMI types (the engine and the numerics it uses included)
set(MODEL_PHYSICS numerics/dfo_fp.h numerics/dfo_inline.h numerics/dmath.c numerics/dmath.h numerics/lcp.c numerics/lcp.h
    numerics/friction.c numerics/friction.h numerics/bossak.h numerics/excitation.h
    numerics/roots.c numerics/roots.h engine/engine.c engine/engine_generic.c engine/engine.h
    engine/engine_private.h engine/engine_step.h engine/engine_tangent.h
    models/two_mass/two_mass.c models/two_mass/two_mass.h)
# the instance core (core/instance.h's model API)
set(MODEL_CORE models/two_mass/tm_instance.c)
# FMI 2.0: the description as written (no structural parameters), no build configuration header
set(MODEL_FMI2_SIZE "")
set(MODEL_CONFIG_HEADER "")
