/* The instance core of the DryFrictionOscillator FMU, independent of any FMI version: life-cycle
 * phase, start values, get/set through the variable table generated from modelDescription.xml
 * (model_vars.h), initialisation, doStep, FMU states and their serialisation, logging.
 *
 * No FMI types here. An FMI glue (fmi2_cs.c, fmi3_cs.c) checks its arguments and
 * the phase in which each of its functions may be called, calls the core, and maps dfo_inst_status
 * to its own status codes. The host's memory and logger reach the core through dfo_host.
 *
 * Time: the core keeps the host's time (start time, then the end of every successful doStep) apart
 * from the physics state's own time; after a good step the stepper's time is the target or a grid
 * point within a snap tolerance of it. The host's time is the one doStep checks the communication
 * point against, the last successful time, and the one an FMU state is checked against. */
#ifndef DFO_INSTANCE_H
#define DFO_INSTANCE_H

#include "model_vars.h"

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

/* What the host provides. alloc returns zeroed memory (calloc-like) or NULL; log may be NULL. */
typedef struct {
    void *ctx;
    void *(*alloc)(void *ctx, size_t n, size_t size);
    void (*free)(void *ctx, void *p);
    void (*log)(void *ctx, dfo_inst_status status, const char *category, const char *message);
} dfo_host;

#if defined(DFO_MODEL_INDEXED)
/* A model with arrays sized by a structural parameter (the chain): its values (chain_instance.h). */
#include "chain_instance.h"
#else
#include "newmark.h"
#include "oscillator.h"

/* Everything that defines where a simulation is: plain values, no pointers, so that an FMU state is
 * a copy and its serialisation the bytes. */
typedef struct {
    dfo_params p;
    dfo_inputs u;
    dfo_inputs u_used;        /* the inputs of the last step (or of initialisation) */
    dfo_model M;
    dfo_state s;
    double time;              /* the host's time */
    double start_time, stop_time;
    int stop_defined;
    int effects;
    dfo_phase phase;
    /* FMI 3.0 events: a switch the host has not yet handled in event mode. While pending, the
     * outputs are the left limits (mode event_from, its friction force and acceleration); the state
     * s is already the right limit. */
    int event_pending, event_from;
} dfo_values;
#endif

typedef struct {
    dfo_values v;
    dfo_host host;
    const char *name;                      /* owned by the glue */
    int log_on[DFO_NUM_LOG_CATEGORIES];
    unsigned warned;                       /* a value not computed has been noted in this run */
    int stop_at_switch, switched;          /* doStep option and its outcome (see dfo_inst_do_step) */
    int work_by_events;                    /* a doStep's work is bounded by the model's events (the exact
                                            * scheme: DFO_EXACT_MAX_EVENTS), not by DFO_MAX_STEPS_PER_CALL
                                            * steps of h (dfo_inst_check_step) */
} dfo_instance;

/* Start values, phase instantiated; errors, warnings and notes of values not computed always logged,
 * the other categories as logging_on says. DFO_INST_ERROR (logged) when memory for the start values
 * could not be had; then dfo_inst_free is still to be called. */
dfo_inst_status dfo_inst_init(dfo_instance *in, const dfo_host *host, const char *name, int logging_on);
/* Release what the instance holds (not the instance itself). */
void dfo_inst_free(dfo_instance *in);

/* ---- what an FMI glue asks of every model ---- */
/* The number of values the variables vr[] hold (1 per scalar, n per array; 1 for an unknown
 * reference, which the get/set call then names). */
size_t dfo_inst_n_values(const dfo_instance *in, const unsigned int vr[], size_t nvr);
/* Log (logEvents) that a pending event was handled. */
void dfo_inst_log_event_handled(const dfo_instance *in);
/* The serialised size of an FMU state (0 when state is not one of this FMU's). */
size_t dfo_inst_state_size(const dfo_instance *in, const void *state);
#if defined(DFO_MODEL_INDEXED)
/* Configuration mode (FMI 3.0): structural parameters may be set; leaving it sizes the arrays. */
dfo_inst_status dfo_inst_enter_config(dfo_instance *in, const char *fn);
dfo_inst_status dfo_inst_exit_config(dfo_instance *in, const char *fn);
/* Structural parameters (UInt64). */
dfo_inst_status dfo_inst_get_uint64(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                    unsigned long long value[]);
dfo_inst_status dfo_inst_set_uint64(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                    const unsigned long long value[]);
#endif

/* ---- logging ---- */
#if defined(__GNUC__)
#define DFO_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define DFO_PRINTF(f, a)
#endif
void dfo_inst_log(const dfo_instance *in, dfo_inst_status status, int category, const char *fmt, ...) DFO_PRINTF(4, 5);
/* Log an error sentence (category logStatusError) and return DFO_INST_ERROR. */
dfo_inst_status dfo_inst_fail(const dfo_instance *in, const char *fmt, ...) DFO_PRINTF(2, 3);
/* Index of a log category by name, -1 when unknown. */
int dfo_inst_log_category(const char *name);
/* category -1: all of them. */
void dfo_inst_set_logging(dfo_instance *in, int category, int on);
const char *dfo_phase_name(dfo_phase phase);

/* ---- life cycle (the glue has checked the phase) ---- */
dfo_inst_status dfo_inst_setup(dfo_instance *in, const char *fn, double start_time, int stop_defined,
                               double stop_time);
dfo_inst_status dfo_inst_enter_init(dfo_instance *in);
dfo_inst_status dfo_inst_exit_init(dfo_instance *in, const char *fn);
dfo_inst_status dfo_inst_terminate(dfo_instance *in);
void dfo_inst_reset(dfo_instance *in);

/* ---- variables. fn names the calling function in messages. Set: every value is checked (type,
 * causality and phase permission, range) before any is stored, so a rejected call changes nothing.
 * Get: a value the run has not computed (an observable while observe is false; x_max, x_min before
 * the observation window's first sample) reads NaN, an Integer -1, with DFO_INST_OK and one sentence
 * per run under logNotComputed. ---- */
dfo_inst_status dfo_inst_get_real(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n, double value[]);
dfo_inst_status dfo_inst_get_int(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n, int value[]);
dfo_inst_status dfo_inst_get_bool(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n, int value[]);
dfo_inst_status dfo_inst_set_real(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[]);
dfo_inst_status dfo_inst_set_int(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                 const int value[]);
dfo_inst_status dfo_inst_set_bool(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  const int value[]);

/* ---- stepping ---- */
enum {
    /* Stop at the end of the internal step in which the first stick/slip switch happens (for an
     * FMI 3.0 early return); *t_reached then tells where. Off: always end on tc + dt. */
    DFO_STEP_STOP_AT_SWITCH = 1
};
dfo_inst_status dfo_inst_do_step(dfo_instance *in, const char *fn, double tc, double dt, unsigned int flags,
                                 double *t_reached);
/* ---- FMI 3.0 stepping with events (see docs/fmi3.md for the semantics) ----
 * early_return: end the step at the first stick/slip switch strictly inside it, the state then being
 * the one just after the switch at the time the scheme places it. event_mode: a switch at which the
 * step ends (early or on the communication point) stays pending: the outputs are its left limits
 * until dfo_inst_update_events. intermediate (may be NULL): called at every switch inside the step
 * with the state at the switch readable (dfo_inst_get_*), returns 1 to request an early return
 * (honoured only with early_return). Without early_return, event_mode and intermediate the step is
 * dfo_inst_do_step's, bit for bit. */
typedef struct {
    int early_return, event_mode;
    int (*intermediate)(void *ctx, double t, int can_return_early);
    void *ctx;
} dfo_event_opts;
typedef struct {
    double t_reached;  /* the host's time after the step */
    int early;         /* returned before tc + dt */
    int event;         /* an event is pending (event_mode only) */
} dfo_step_result;
dfo_inst_status dfo_inst_do_step_events(dfo_instance *in, const char *fn, double tc, double dt,
                                        const dfo_event_opts *opt, dfo_step_result *res);
/* Handle a pending event: the outputs become the right limits. Returns whether one was pending. */
int dfo_inst_update_events(dfo_instance *in);

/* The host's time: start time, then the end of the last successful step. */
double dfo_inst_time(const dfo_instance *in);

/* ---- FMU states: allocated through the host, tagged; serialised with magic, version, size and
 * checksum, validated on load, derived constants rebuilt ---- */
dfo_inst_status dfo_inst_get_state(dfo_instance *in, const char *fn, void **state);
dfo_inst_status dfo_inst_set_state(dfo_instance *in, const char *fn, const void *state);
dfo_inst_status dfo_inst_free_state(dfo_instance *in, const char *fn, void **state);
size_t dfo_inst_serialized_size(void);
dfo_inst_status dfo_inst_serialize(dfo_instance *in, const char *fn, const void *state, unsigned char *buf,
                                   size_t size);
dfo_inst_status dfo_inst_deserialize(dfo_instance *in, const char *fn, const unsigned char *buf, size_t size,
                                     void **state);

#endif
