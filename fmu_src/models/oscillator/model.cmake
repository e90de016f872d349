# The DryFrictionOscillator (one block, dry friction, harmonic excitation): read by cmake/models.cmake
# (dfo_add_model), which builds its FMUs for every FMI version of MODEL_FMI. Paths are under fmu_src/.
set(MODEL_ID DryFrictionOscillator)
# its description stays at the top of the repository (the project's card puts it there)
set(MODEL_DESCRIPTION ${CMAKE_SOURCE_DIR}/modelDescription.xml)
set(MODEL_FMI 2 3)
# the physics: plain C, no FMI types (the numerics it uses included)
set(MODEL_PHYSICS numerics/dfo_fp.h numerics/dfo_inline.h numerics/dmath.c numerics/dmath.h numerics/ddouble.h numerics/lcp.c
    numerics/lcp.h numerics/friction.c numerics/friction.h numerics/bossak.h numerics/excitation.h
    numerics/roots.c numerics/roots.h engine/engine.c engine/engine.h engine/engine_private.h engine/engine_step.h engine/engine_tangent.h
    models/oscillator/oscillator.c models/oscillator/oscillator.h models/oscillator/scheme_state.h
    models/oscillator/scheme.c models/oscillator/scheme.h models/oscillator/newmark.c
    models/oscillator/newmark.h models/oscillator/osc_bossak.c models/oscillator/osc_bossak.h models/oscillator/osc_engine.c
    models/oscillator/osc_engine.h models/oscillator/osc_engine_ops.h engine/eng_one_dof.h models/oscillator/exact.c models/oscillator/exact.h
    models/oscillator/exact_private.h models/oscillator/exact_loop.h models/oscillator/exact_spring.c
    models/oscillator/exact_spring.h models/oscillator/exact_free.c models/oscillator/exact_free.h
    models/oscillator/exact_belt.c models/oscillator/exact_belt.h models/oscillator/exact_poly.c
    models/oscillator/exact_poly.h models/oscillator/exact_observe.c models/oscillator/exact_observe.h
    models/oscillator/exact_sens.c models/oscillator/exact_sens.h)
# the instance core (core/instance.h's model API)
set(MODEL_CORE models/oscillator/osc_instance.c models/oscillator/osc_instance.h models/oscillator/osc_inst_vars.c
    models/oscillator/osc_inst_step.c models/oscillator/osc_inst_events.c models/oscillator/osc_inst_state.c
    models/oscillator/osc_inst_deriv.c models/oscillator/osc_inst_me.c)
# FMI 2.0: the description as written (no structural parameters), no build configuration header
set(MODEL_FMI2_SIZE "")
set(MODEL_CONFIG_HEADER "")
