/* The instance of the DryFrictionChain FMUs and the private interface of its core, split by
 * concern (the model API of core/instance.h):
 *   chain_instance.c    memory, start values, the chain model built from the values, life cycle and
 *                       configuration mode
 *   chain_inst_vars.c   variable access: value references (FMI 3.0 arrays, FMI 2.0 elements),
 *                       get/set, outputs, the structural parameter n
 *   chain_inst_step.c   doStep, with and without FMI 3.0 events
 *   chain_inst_state.c  FMU-state copies and their serialisation (core/fmu_state.h's format)
 *   chain_inst_me.c     Model Exchange (core/instance_me.h): derivatives, event indicators, events
 *
 * The values: the structural parameter n, the scalar parameters, the per-block parameter and input
 * arrays (n values each, through the host's allocator), the chain model built from them at the end
 * of initialisation, and its state. An FMU state copies all of it and the run. No FMI types.
 *
 * n is set in FMI 3.0's configuration mode, fixed by the build in FMI 2.0 where DFO_CHAIN_FIXED_N is
 * defined: by chain_config.h, the build's configuration generated from the model description into
 * the FMU's sources/, so that a plain compile of the listed sources builds the right FMU. */
#ifndef DFO_CHAIN_INSTANCE_H
#define DFO_CHAIN_INSTANCE_H

#include "chain.h"
#include "chain_config.h" /* DFO_CHAIN_FIXED_N in an FMI 2.0 build */
#include "instance_common.h"
#include "model_vars.h"

#include <stddef.h>

#if defined(DFO_CHAIN_FIXED_N)
#define CHAIN_N_START ((size_t)(DFO_CHAIN_FIXED_N))
#else
#define CHAIN_N_START ((size_t)START_n)
#endif

typedef struct {
    size_t n;                   /* blocks: the arrays' size */
    size_t n_config;            /* n as set in configuration mode, applied when leaving it */
    double sp[DFO_NUM_SP];      /* scalar parameters (an enumeration as its value) */
    double *pa;                 /* array parameters: pa[slot * n + i] */
    double *ua, *ua_used;       /* array inputs now and of the last step: ua[slot * n + i] */
    int u_set[DFO_NUM_AI];      /* the input has been set (an input never set is never read) */
    int u_set_used[DFO_NUM_AI];
    /* input derivatives for the next step only (core/instance.h): order k = 1, 2 of input slot j,
     * element i at ud[((k - 1) DFO_NUM_AI + j) n + i]; ud_set: some of them has been set (else all 0) */
    double *ud;
    int ud_set;
    /* the last stick/slip switch of the run: its time and block (-1: none), for output derivatives */
    double sw_t;
    long long sw_block;
    chain_model *M;             /* built at the end of initialisation (NULL before) */
    chain_state s;              /* the state (arrays of n, allocated with the instance) */
    chain_state s0;             /* the state at the start of a step (restored when it fails) */
    double *scratch;            /* n doubles: the accelerations of the state and inputs */
    int acc_valid;              /* scratch holds them (cleared by every change of state or inputs) */
    int belts_unsynced;         /* the state is on the belts of ua, taken at the start of a step that has not
                                 * copied them to ua_used yet (else on those of ua_used) */
    size_t event_block;         /* the block of a pending event (the run's event_pending, event_from) */
    int me;                     /* made for Model Exchange (chain_inst_me.c): the host integrates x, v */
    int me_fresh;               /* Model Exchange: the state's forces and scratch's accelerations are those of
                                 * the state, time and inputs (cleared by every change of them) */
} chain_values;

typedef struct {
    dfo_lifecycle lc;           /* first: the glues see the instance as its life cycle */
    chain_values v;
} chain_instance;

static inline chain_instance *chn(dfo_lifecycle *lc) { return (chain_instance *)lc; }
static inline const chain_instance *cchn(const dfo_lifecycle *lc) { return (const chain_instance *)lc; }

/* ---- chain_instance.c ---- */
chain_alloc chain_inst_allocator(chain_instance *in);
/* Arrays for n blocks into v (v's own pointers untouched on failure: 0 returned). */
int chain_inst_alloc_arrays(chain_instance *in, chain_values *v, size_t n);
/* The arrays of v (not the model). */
void chain_inst_free_arrays(chain_instance *in, chain_values *v);
void chain_inst_free_model(chain_values *v);
/* Size the arrays for n blocks (start values); DFO_INST_ERROR when out of memory (nothing changed). */
dfo_inst_status chain_inst_resize(chain_instance *in, const char *fn, size_t n);
/* Where a stored value of element i lives. */
double *chain_inst_stored(chain_values *v, const dfo_var_info *var, size_t i);
chain_params chain_inst_params_of(const chain_values *v);
/* The internal step of the run (h_used). */
double chain_inst_step_h(const chain_values *v);
/* The inputs now (used: those of the last step); an input never set is NULL (never read). */
chain_inputs chain_inst_inputs_of(const chain_values *v, int used);
/* The belt speeds v_belt (the ones used, or the current ones): NULL when never set or all 0. */
const double *chain_inst_belt_of(const chain_values *v, int used);
/* The belts the state is on (those of the last start, step or belt change; NULL: none): the
 * Stribeck law's relative speed of the outputs. */
const double *chain_inst_state_belt(const chain_values *v);
/* Block i's kinetic coefficient at the state: mu_k, or (friction_law = stribeck) mu(|v - v_belt|). */
double chain_inst_kinetic_mu(const chain_values *v, size_t i);
/* The input derivatives of the next step (NULL arrays when none is set; t_ref: the state's time,
 * which the steps replace by the host's). */
chain_ramp chain_inst_ramp_of(const chain_values *v);
/* After a step with input derivatives from t_ref: the inputs take their polynomials' values at the
 * state's time, the derivatives are 0 again. */
void chain_inst_ramp_done(chain_values *v, double t_ref);
/* Build the model from the parameters and start the state at the start time (NULL on success, else why). */
const char *chain_inst_prepare(chain_instance *in, char *buf, size_t len);
/* The model is built and the run started. */
int chain_inst_started(const chain_instance *in);

/* ---- chain_inst_vars.c ---- */
/* A value reference resolved: the variable and, for an FMI 2.0 element, its index (0-based). */
typedef struct {
    const dfo_var_info *var;
    long elem; /* -1: the whole variable (a scalar, or every element of an array) */
    char name[48];
} chain_ref;
/* Resolve vr (0, with an error logged naming fn, when unknown). */
int chain_inst_lookup_any(const chain_instance *in, const char *fn, unsigned int vr, chain_ref *r);
/* Values a resolved variable holds (n for a whole array). */
size_t chain_inst_count(const chain_instance *in, const chain_ref *r);
/* The output F_friction of block i under the current inputs (the state's force, or its response to
 * inputs set since the last step: a sliding block's kinetic force, a stuck block's held force taking
 * the change of its external force, clamped to its breakaway limit). */
double chain_inst_friction_out(const chain_values *v, size_t i);
/* The output a of every block into v->scratch (chain_accelerations; the paper scheme's stuck blocks
 * with the held force of chain_inst_friction_out). */
void chain_inst_accelerations(chain_values *v);

/* ---- chain_inst_me.c ---- */
/* The output event_indicator_0 (which = 0) or event_indicator_1 (1) of block i: Model Exchange's
 * event indicators at the state under the current inputs (the model built). */
double chain_inst_me_indicator(chain_values *v, int which, size_t i);
/* Model Exchange: the forces and accelerations of the state, time and inputs (into the state and
 * scratch) unless they are (me_fresh). */
void chain_inst_me_refresh(chain_values *v);

#endif
