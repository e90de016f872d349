/* The instance of the DryFrictionSystem FMUs and the private interface of its core, split by concern
 * (the model API of core/instance.h):
 *   sys_instance.c    memory and the values' layout, start values, the model built from the values,
 *                     life cycle and configuration mode, variable access (get/set, outputs)
 *   sys_inst_state.c  doStep (with FMI 3.0's early return at a switch), FMU states and their
 *                     serialisation (core/fmu_state.h's format), the derivatives it does not provide
 *
 * The values live in ONE array of doubles (vals, through the host's allocator), laid out for the
 * sizes n, nc (sys_layout): a head (the sizes, the start flag, the inputs' set flags), the scalar
 * parameters, the array parameters, the array inputs now and as the last step used them, and the
 * engine state's snapshot (its scalars and arrays); an FMU state is a copy of that array and the run.
 * The engine's live state (eng_state) and the model (system.h) are built at the end of initialisation.
 *
 * n and nc are set in FMI 3.0's configuration mode, fixed by the build in FMI 2.0 where
 * DFO_SYSTEM_FIXED_N and DFO_SYSTEM_FIXED_NC are defined (system_config.h, generated from the model
 * description). No FMI types. */
#ifndef DFO_SYS_INSTANCE_H
#define DFO_SYS_INSTANCE_H

#include "engine.h"
#include "instance_common.h"
#include "model_vars.h"
#include "system.h"
#include "system_config.h" /* DFO_SYSTEM_FIXED_N, _NC in an FMI 2.0 build */

#include <stddef.h>

#if defined(DFO_SYSTEM_FIXED_N)
#define SYS_N_START ((size_t)(DFO_SYSTEM_FIXED_N))
#define SYS_NC_START ((size_t)(DFO_SYSTEM_FIXED_NC))
#else
#define SYS_N_START ((size_t)START_n)
#define SYS_NC_START ((size_t)START_nc)
#endif

/* The head of vals. */
enum {
    SYS_H_N = 0,          /* n */
    SYS_H_NC = 1,         /* nc */
    SYS_H_STARTED = 2,    /* 1: the model is built and the state started */
    SYS_H_SET = 3,        /* DFO_NUM_AI flags: the input has been set (an input never set is never read) */
    SYS_H_SET_USED = SYS_H_SET + DFO_NUM_AI, /* the flags of the inputs the last step used */
    SYS_H_TOTAL = SYS_H_SET_USED + DFO_NUM_AI, /* the number of doubles in vals */
    SYS_HEAD
};

/* The engine state's scalars in the snapshot, in this order. */
#define SYS_SNAP_SCALARS(DO) DO(t0) DO(t) DO(n_grid) DO(t_switch) DO(stick_tb) DO(steps) DO(solves) DO(pivot_steps) \
    DO(switches) DO(W_applied) DO(W_friction) DO(D_damping) DO(exc_n) DO(exc_c) DO(exc_s)
#define SYS_SNAP_NS 15
/* and its arrays: X, V, A, hA (n each), F, t_stick, t_break, mode, break_dir, slider (nc each) */
#define SYS_SNAP_NA_N 4
#define SYS_SNAP_NA_NC 6

/* The observables' state in vals from L.obs: x_max, x_min (n each), the stuck time inside the window
 * and the start of the open stuck stretch (NaN: none) of each contact (nc each), the flag "x sampled",
 * then each contact's mode changes inside the window (nc). */
#define SYS_OBS_SIZE(n, nc) (2 * (n) + 3 * (nc) + 1)
#define SYS_OBS_TRANSITIONS(n, nc) (2 * (n) + 2 * (nc) + 1)

/* Where each part of vals begins for sizes n, nc (in doubles). */
typedef struct {
    size_t n, nc;
    size_t sp;                   /* scalar parameters */
    size_t ap[DFO_NUM_AP];       /* array parameters, each its own size */
    size_t ai[DFO_NUM_AI];       /* array inputs now */
    size_t ai_used[DFO_NUM_AI];  /* array inputs of the last step */
    size_t snap;                 /* the engine state's snapshot */
    size_t obs;                  /* the observables' state (SYS_OBS_*) */
    size_t ud;                   /* the input derivatives: orders 1, 2 of F_ext (n) then N_ext (nc) */
    size_t total;
} sys_layout;

typedef struct {
    dfo_lifecycle lc;            /* first: the glues see the instance as its life cycle */
    double *vals;                /* the values (sys_layout L) */
    sys_layout L;
    size_t n_config, nc_config;  /* n, nc as set in configuration mode, applied when leaving it */
    sys_model m;                 /* built at the end of initialisation (m.E NULL before) */
    eng_state s;                 /* the engine's live state (arrays through the host) */
    int s_ready;
    double *scratch;             /* n + 2 nc + 1 doubles: outputs a and f; the start's sliders and slides */
    eng_observer obs;            /* the observables' observer (sys_observer) */
} sys_instance;

static inline sys_instance *sysi(dfo_lifecycle *lc) { return (sys_instance *)lc; }
static inline const sys_instance *csysi(const dfo_lifecycle *lc) { return (const sys_instance *)lc; }

/* ---- sys_instance.c ---- */
/* The layout for n, nc. */
sys_layout sys_layout_of(size_t n, size_t nc);
/* The number of values of an array variable for sizes n, nc (1 for a scalar). */
size_t sys_var_count(const dfo_var_info *var, size_t n, size_t nc);
/* The parameters of vals (pointers into it). */
sys_params sys_params_of(const double *vals, const sys_layout *L);
/* The engine's inputs of vals (used: those of the last step); an input never set is NULL. */
eng_inputs sys_inputs_of(const double *vals, const sys_layout *L, int used);
/* The inputs now become the inputs used (the flags too); whether they differ. (The array inputs are
 * contiguous: ai[0] ... ai_used[0].) */
void sys_sync_inputs(double *vals, const sys_layout *L);
int sys_inputs_changed(const double *vals, const sys_layout *L);
/* A moving belt (v_belt set, some element not 0) under the paper scheme: its stuck contacts creep
 * with Bossak's acceleration, which a belt's moving frame does not carry over (the chain's measured
 * 0.053 at every h): refused, as the chain refuses it. The sentence, or NULL. */
const char *sys_belt_refused(const double *vals, const sys_layout *L);
/* Build the model and the state arrays from the values (NULL, or why not, in buf); the state is
 * not started. */
const char *sys_build(sys_instance *in, char *buf, size_t len);
void sys_free_model(sys_instance *in);
/* Size the values for n, nc (start values when the size changes); DFO_INST_ERROR when out of memory
 * (nothing changed). */
/* The values and scratch arrays back to the host (sys_inst_values.c). */
void sys_free_values(sys_instance *in);
/* Every value at its start (the run's flags cleared; sys_inst_values.c). */
void sys_value_starts(double *vals, const sys_layout *L);
dfo_inst_status sys_resize(sys_instance *in, const char *fn, size_t n, size_t nc);
/* The engine state's snapshot in vals from s, and back. */
void sys_snap_of(const eng_state *s, double *vals, const sys_layout *L);
void sys_state_of(const double *vals, const sys_layout *L, eng_state *s);
/* The engine's observer of the observables (t_obs_start, t_obs_stop, observe), or NULL while observe is
 * false; its values live in vals (L.obs), so that an FMU state holds them. */
const eng_observer *sys_observer(sys_instance *in);
/* The observables at the start (the start state sampled where t0 is inside the window). */
void sys_obs_start(sys_instance *in);

/* The input derivatives set for the next step (FMI 2.0's fmi2SetRealInputDerivatives) into e (its
 * polynomials from t_ref), when any is not 0. */
void sys_ramp_of(const double *vals, const sys_layout *L, double t_ref, eng_inputs *e);
/* A step from t_ref ended at t: the inputs with derivatives take their polynomials' values at t and
 * become the inputs used; the derivatives are forgotten (they hold for one step). */
void sys_ramp_done(double *vals, const sys_layout *L, double t_ref, double t);

/* The engine's report of its rest rule (eng_rest_fn; ctx: the instance), logged under logEvents: the
 * rule that picks the mode set where several rigid contacts at rest are decided together. */
void sys_on_rest(void *ctx, double t, int stage, size_t contact, int mode, double excess, const int *rest,
                 const int *modes);

/* The allocator of the engine and the model: the host's. */
eng_alloc sys_allocator(sys_instance *in);

#endif
