/* The instance API every model's core provides to the FMI glues (fmi2_cs.c, fmi3_cs.c), and the
 * life cycle every model's instance starts with. Generic: no model header, no FMI types.
 *
 * A model's core (models/<name>/: the oscillator's osc_instance.c, the chain's chain_instance.c)
 * defines every dfo_inst_* function declared under "what every model core provides" below, over
 * its own instance struct, whose FIRST member is a dfo_lifecycle: the glues and instance_common.c
 * see only that (a dfo_lifecycle * is the model's instance). The glue checks its arguments and the
 * phase in which each of its functions may be called, calls the core, and maps dfo_inst_status to
 * its own status codes. The host's memory and logger reach the core through dfo_host.
 *
 * Time: the life cycle keeps the host's time (start time, then the end of every successful doStep)
 * apart from the physics state's own time; after a good step the stepper's time is the target or a
 * grid point within a snap tolerance of it (dfo_snap, instance_common.h). The host's time is the
 * one doStep checks the communication point against, the last successful time, and the one an FMU
 * state is checked against. */
#ifndef DFO_INSTANCE_H
#define DFO_INSTANCE_H

#include <stddef.h>

typedef enum { DFO_INST_OK = 0, DFO_INST_WARNING = 1, DFO_INST_ERROR = 3 } dfo_inst_status;

/* Life-cycle phases, as bits so that a set of phases is a mask. */
typedef enum {
    DFO_PHASE_INSTANTIATED = 1 << 0,
    DFO_PHASE_INIT = 1 << 1,       /* initialisation mode */
    DFO_PHASE_STEP = 1 << 2,       /* stepping */
    DFO_PHASE_TERMINATED = 1 << 3,
    DFO_PHASE_ERROR = 1 << 4,      /* a step failed: only reset or an FMU state recovers */
    DFO_PHASE_EVENT = 1 << 5,      /* FMI 3.0 event mode (never reached through FMI 2.0) */
    DFO_PHASE_CONFIG = 1 << 6      /* FMI 3.0 configuration mode (models with structural parameters) */
} dfo_phase;
#define DFO_PHASE_ANY 127
/* the phases after initialisation, in which the model is started */
#define DFO_PHASES_STARTED (DFO_PHASE_STEP | DFO_PHASE_EVENT | DFO_PHASE_TERMINATED | DFO_PHASE_ERROR)

/* What the host provides. alloc returns zeroed memory (calloc-like) or NULL; log may be NULL. */
typedef struct {
    void *ctx;
    void *(*alloc)(void *ctx, size_t n, size_t size);
    void (*free)(void *ctx, void *p);
    void (*log)(void *ctx, dfo_inst_status status, const char *category, const char *message);
} dfo_host;

/* Where a run is, the same for every model: plain values, saved in every FMU state (and serialised
 * by core/fmu_state.c). */
typedef struct {
    double time;                /* the host's time */
    double start_time, stop_time;
    int stop_defined;
    dfo_phase phase;
    /* FMI 3.0 events: a switch the host has not yet handled in event mode. While pending, the
     * switching block's outputs are the left limits (mode event_from); the state is already the
     * right limit. */
    int event_pending, event_from;
} dfo_run;

#define DFO_MAX_LOG_CATEGORIES 32

/* The life cycle: the first member of every model's instance. */
typedef struct dfo_lifecycle_s {
    dfo_run run;
    dfo_host host;
    const char *name;                      /* owned by the glue */
    int log_on[DFO_MAX_LOG_CATEGORIES];    /* by the model's log category (model_vars.h) */
    unsigned warned;                       /* a value not computed has been noted in this run */
    int switched;                          /* the last step met a stick/slip switch (see dfo_inst_do_step) */
    int work_by_events;                    /* a doStep's work is bounded by the model's events (the exact
                                            * scheme), not by DFO_MAX_STEPS_PER_CALL steps of h
                                            * (dfo_inst_check_step) */
    /* A model whose FMU may carry its start values in its resources folder (the system) sets this
     * hook in dfo_inst_new; the glue calls it through dfo_inst_resources (DFO_RES_LOAD once
     * instantiated, DFO_RES_APPLY after every reset, DFO_RES_FREE before dfo_inst_delete). What it
     * read is kept in res, through the host's allocator. NULL for the other models. */
    dfo_inst_status (*resources)(struct dfo_lifecycle_s *lc, const char *dir, int op);
    void *res;
} dfo_lifecycle;

/* ---- the life cycle alone (instance_common.c) ---- */

/* The operations of the resources hook (dfo_lifecycle.resources). */
enum { DFO_RES_LOAD = 0, DFO_RES_APPLY = 1, DFO_RES_FREE = 2 };
/* Call the model's resources hook, if it has one: DFO_INST_OK when it has none. dir: the FMU's
 * resources folder as a native path (NULL: none given), read by DFO_RES_LOAD only. */
dfo_inst_status dfo_inst_resources(dfo_lifecycle *lc, const char *dir, int op);
/* The native path of an FMI 2.0 fmuResourceLocation URI (file:///C:/a%20b/resources,
 * file:/home/u/resources, file://localhost/...: percent-decoded, a Windows drive letter without its
 * leading slash) in out (len bytes); 0 when it is not a local file URI or does not fit. */
int dfo_path_of_file_uri(const char *uri, char *out, size_t len);

/* host, name, phase instantiated, the experiment's times 0; every log category as logging_on says,
 * errors and warnings always on. Enough to log through (the glues' messages before an instance). */
void dfo_lifecycle_init(dfo_lifecycle *lc, const dfo_host *host, const char *name, int logging_on);
/* A model's instance of size bytes (its dfo_lifecycle the first member) from the host's allocator,
 * zeroed, its life cycle started (dfo_lifecycle_init); NULL, logged, when out of memory. */
dfo_lifecycle *dfo_lifecycle_new(const dfo_host *host, size_t size, const char *name, int logging_on);

#if defined(__GNUC__)
#define DFO_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define DFO_PRINTF(f, a)
#endif
void dfo_inst_log(const dfo_lifecycle *lc, dfo_inst_status status, int category, const char *fmt, ...)
    DFO_PRINTF(4, 5);
/* Log an error sentence (category logStatusError) and return DFO_INST_ERROR. */
dfo_inst_status dfo_inst_fail(const dfo_lifecycle *lc, const char *fmt, ...) DFO_PRINTF(2, 3);
/* Index of a log category by name, -1 when unknown. */
int dfo_inst_log_category(const char *name);
/* category -1: all of them. */
void dfo_inst_set_logging(dfo_lifecycle *lc, int category, int on);
const char *dfo_phase_name(dfo_phase phase);

/* Life cycle steps that touch only the run (the glue has checked the phase). */
dfo_inst_status dfo_inst_setup(dfo_lifecycle *lc, const char *fn, double start_time, int stop_defined,
                               double stop_time);
dfo_inst_status dfo_inst_enter_init(dfo_lifecycle *lc);
dfo_inst_status dfo_inst_terminate(dfo_lifecycle *lc);
/* Handle a pending event: the outputs become the right limits. Returns whether one was pending. */
int dfo_inst_update_events(dfo_lifecycle *lc);
/* The host's time: start time, then the end of the last successful step. */
double dfo_inst_time(const dfo_lifecycle *lc);

/* ---- what every model core provides ---- */

/* A new instance (through host->alloc): start values, phase instantiated; errors, warnings (and the
 * model's notes of values not computed) always logged, the other categories as logging_on says.
 * NULL (logged) when memory could not be had. */
dfo_lifecycle *dfo_inst_new(const dfo_host *host, const char *name, int logging_on);
/* Release the instance and all it holds. */
void dfo_inst_delete(dfo_lifecycle *lc);

/* The number of values the variables vr[] hold (1 per scalar, n per array; 1 for an unknown
 * reference, which the get/set call then names). */
size_t dfo_inst_n_values(const dfo_lifecycle *lc, const unsigned int vr[], size_t nvr);
/* Log (logEvents) that a pending event was handled. */
void dfo_inst_log_event_handled(const dfo_lifecycle *lc);

dfo_inst_status dfo_inst_exit_init(dfo_lifecycle *lc, const char *fn);
void dfo_inst_reset(dfo_lifecycle *lc);

/* Structural parameters (FMI 3.0): whether the model has any; configuration mode, in which they
 * may be set (leaving it sizes the arrays); their values (UInt64). A model without them says so
 * (0) and its four functions fail with "the FMU has no structural parameters". */
int dfo_inst_has_structural(void);
dfo_inst_status dfo_inst_enter_config(dfo_lifecycle *lc, const char *fn);
dfo_inst_status dfo_inst_exit_config(dfo_lifecycle *lc, const char *fn);
dfo_inst_status dfo_inst_get_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    unsigned long long value[]);
dfo_inst_status dfo_inst_set_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    const unsigned long long value[]);

/* Variables. fn names the calling function in messages. Set: every value is checked (type,
 * causality and phase permission, range) before any is stored, so a rejected call changes nothing.
 * Get: a value the run has not computed reads NaN (an Integer -1) with DFO_INST_OK and one sentence
 * per run under the model's logNotComputed. */
dfo_inst_status dfo_inst_get_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, double value[]);
dfo_inst_status dfo_inst_get_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[]);
dfo_inst_status dfo_inst_get_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[]);
dfo_inst_status dfo_inst_set_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[]);
dfo_inst_status dfo_inst_set_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                 const int value[]);
dfo_inst_status dfo_inst_set_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const int value[]);

/* Stepping. */
enum {
    /* Stop at the end of the internal step in which the first stick/slip switch happens (for an
     * FMI 3.0 early return); *t_reached then tells where. Off: always end on tc + dt. */
    DFO_STEP_STOP_AT_SWITCH = 1
};
dfo_inst_status dfo_inst_do_step(dfo_lifecycle *lc, const char *fn, double tc, double dt, unsigned int flags,
                                 double *t_reached);
/* FMI 3.0 stepping with events (see docs/fmi3.md for the semantics).
 * early_return: end the step at the first stick/slip switch strictly inside it, the state then being
 * the one just after the switch at the time the scheme places it. event_mode: a switch at which the
 * step ends (early or on the communication point) stays pending: the outputs are its left limits
 * until dfo_inst_update_events. intermediate (may be NULL): called at every switch inside the step
 * with the state at the switch readable (dfo_inst_get_*), returns 1 to request an early return
 * (honoured only with early_return). Without early_return, event_mode and intermediate the step is
 * dfo_inst_do_step's, bit for bit. */
typedef struct {
    int early_return, event_mode;
    int (*intermediate)(void *ctx, double t, int can_return_early, int set_requested);
    void *ctx;
    /* input_points: the host may set inputs during the step (FMI 3.0 intermediate update of inputs):
     * the core also calls intermediate(ctx, t, can_return_early, 1) where it reads the inputs inside
     * the step (the end of every internal step of the Bossak schemes); the inputs set there hold from
     * t on. At switches the call has set_requested 0. */
    int input_points;
} dfo_event_opts;
typedef struct {
    double t_reached;  /* the host's time after the step */
    int early;         /* returned before tc + dt */
    int event;         /* an event is pending (event_mode only) */
} dfo_step_result;
dfo_inst_status dfo_inst_do_step_events(dfo_lifecycle *lc, const char *fn, double tc, double dt,
                                        const dfo_event_opts *opt, dfo_step_result *res);

/* Coupling at second order (FMI 2.0 canInterpolateInputs, maxOutputDerivativeOrder,
 * providesDirectionalDerivative; FMI 3.0 output, directional and adjoint derivatives).
 * dfo_inst_max_input_order: the highest order of input derivatives the model takes (0: none);
 * dfo_inst_max_output_order: the highest order of output derivatives it gives (0: none). */
int dfo_inst_max_input_order(void);
int dfo_inst_max_output_order(void);
/* The order[i]-th time derivative (1 .. max input order) of the real input vr[i] at the host's
 * current time: over the next doStep only the input varies as its Taylor polynomial from the
 * current time (after it the derivatives are 0 again: the input is held). Every value is checked
 * (a real input, the order in range, finite) before any is stored: a rejected call changes nothing. */
dfo_inst_status dfo_inst_set_input_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t nvr,
                                               const int order[], const double value[]);
/* The order[i]-th time derivative (1 .. max output order) of the output vr[i] at the host's current
 * time, value[] holding dfo_inst_n_values(vr) values (an array variable's values in order). Where a
 * derivative does not exist (at a stick/slip switch) the call fails with a sentence naming it. */
dfo_inst_status dfo_inst_get_output_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[],
                                                size_t nvr, const int order[], double value[]);
/* Directional derivatives of the unknowns (outputs) with respect to the knowns (inputs) at the
 * current point: sensitivity = J seed, J = d unknown / d known (the direct feed-through, by mode);
 * seed has dfo_inst_n_values(known) values, sensitivity dfo_inst_n_values(unknown). Adjoint:
 * sensitivity = J^T seed, seed over the unknowns, sensitivity over the knowns. */
dfo_inst_status dfo_inst_directional(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                     const unsigned int known[], size_t nk, const double seed[], double sensitivity[]);
dfo_inst_status dfo_inst_adjoint(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                 const unsigned int known[], size_t nk, const double seed[], double sensitivity[]);

/* FMU states: allocated through the host, tagged; serialised in the one format of core/fmu_state.h
 * (header with magic, format version, model hash, size and checksum, then the model's fields),
 * validated on load, derived constants rebuilt. */
dfo_inst_status dfo_inst_get_state(dfo_lifecycle *lc, const char *fn, void **state);
dfo_inst_status dfo_inst_set_state(dfo_lifecycle *lc, const char *fn, const void *state);
dfo_inst_status dfo_inst_free_state(dfo_lifecycle *lc, const char *fn, void **state);
/* The serialised size of an FMU state (0 when state is not one of this FMU's). */
size_t dfo_inst_state_size(const dfo_lifecycle *lc, const void *state);
dfo_inst_status dfo_inst_serialize(dfo_lifecycle *lc, const char *fn, const void *state, unsigned char *buf,
                                   size_t size);
dfo_inst_status dfo_inst_deserialize(dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                                     void **state);

#endif
