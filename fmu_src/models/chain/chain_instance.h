/* The values of a DryFrictionChain instance (included by instance.h when the model is indexed):
 * the structural parameter n, the scalar parameters, the per-block parameter and input arrays (n
 * values each, through the host's allocator), the chain model built from them at the end of
 * initialisation, and its state. An FMU state copies all of it (chain_instance.c). No FMI types. */
#ifndef DFO_CHAIN_INSTANCE_H
#define DFO_CHAIN_INSTANCE_H

#include "chain.h"
#include "model_vars.h"

#include <stddef.h>

typedef struct {
    size_t n;                   /* blocks: the arrays' size */
    size_t n_config;            /* n as set in configuration mode, applied when leaving it */
    double sp[DFO_NUM_SP];      /* scalar parameters (an enumeration as its value) */
    double *pa;                 /* array parameters: pa[slot * n + i] */
    double *ua, *ua_used;       /* array inputs now and of the last step: ua[slot * n + i] */
    int u_set[DFO_NUM_AI];      /* the input has been set (an input never set is never read) */
    int u_set_used[DFO_NUM_AI];
    chain_model *M;             /* built at the end of initialisation (NULL before) */
    chain_state s;              /* the state (arrays of n, allocated with the instance) */
    chain_state s0;             /* the state at the start of a step (restored when it fails) */
    double *scratch;            /* n doubles: the accelerations of the state and inputs */
    int acc_valid;              /* scratch holds them (cleared by every change of state or inputs) */
    double time;                /* the host's time */
    double start_time, stop_time;
    int stop_defined;
    int phase;                  /* dfo_phase */
    /* FMI 3.0 events: a switch the host has not yet handled in event mode. While pending, the
     * switching block's outputs are the left limits (mode event_from); the state is the right limit. */
    int event_pending, event_from;
    size_t event_block;
} dfo_values;

#endif
