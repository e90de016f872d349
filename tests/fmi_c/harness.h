/* Helpers for the C tests of the FMI API: counting memory callbacks, a logger that keeps the last
 * message, the checks of tests/check.h (tally, EXPECT). Test code only: the counters are process-wide
 * (the FMI memory callbacks get no environment pointer), guarded by a mutex so that threads may
 * share them. */
#ifndef DFO_FMI_HARNESS_H
#define DFO_FMI_HARNESS_H

#include "fmi2Functions.h"
#include "model_vars.h"
#include "../check.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


/* ---- memory callbacks that count ---- */

typedef struct {
    pthread_mutex_t lock;
    long allocs, frees;
} mem_counts;

static mem_counts g_mem = {PTHREAD_MUTEX_INITIALIZER, 0, 0};

static inline void *count_alloc(size_t n, size_t size)
{
    void *p = calloc(n, size);
    if (p) {
        pthread_mutex_lock(&g_mem.lock);
        g_mem.allocs++;
        pthread_mutex_unlock(&g_mem.lock);
    }
    return p;
}

static inline void count_free(void *p)
{
    if (p) {
        pthread_mutex_lock(&g_mem.lock);
        g_mem.frees++;
        pthread_mutex_unlock(&g_mem.lock);
    }
    free(p);
}

static inline long mem_outstanding(void)
{
    pthread_mutex_lock(&g_mem.lock);
    const long d = g_mem.allocs - g_mem.frees;
    pthread_mutex_unlock(&g_mem.lock);
    return d;
}

/* ---- logger ---- */

typedef struct {
    char last[1024];        /* last message of status >= fmi2Discard */
    int n_errors, n_all;
} log_sink;

static inline void sink_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                        fmi2String message, ...)
{
    (void)name;
    (void)category;
    log_sink *s = (log_sink *)env;
    if (!s) return;
    s->n_all++;
    if (status >= fmi2Discard) {
        s->n_errors++;
        snprintf(s->last, sizeof s->last, "%s", message ? message : "");
    }
}

static inline fmi2CallbackFunctions callbacks_for(log_sink *sink)
{
    fmi2CallbackFunctions cb;
    cb.logger = sink_logger;
    cb.allocateMemory = count_alloc;
    cb.freeMemory = count_free;
    cb.stepFinished = NULL;
    cb.componentEnvironment = sink;
    return cb;
}

/* The callbacks struct must outlive the instance: callers keep it next to the component. */
static inline fmi2Component new_instance(const char *name, fmi2CallbackFunctions *cb)
{
    return fmi2Instantiate(name, fmi2CoSimulation, MODEL_GUID, "", cb, fmi2False, fmi2False);
}

/* Set up, set h and any real parameters (vr/value pairs), initialise. */
static inline fmi2Status start_run(fmi2Component c, double h, size_t n, const fmi2ValueReference *vr,
                                   const double *val)
{
    const fmi2ValueReference vh = VR_h;
    fmi2Status st = fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    if (st == fmi2OK) st = fmi2SetReal(c, &vh, 1, &h);
    if (st == fmi2OK && n) st = fmi2SetReal(c, vr, n, val);
    if (st == fmi2OK) st = fmi2EnterInitializationMode(c);
    if (st == fmi2OK) st = fmi2ExitInitializationMode(c);
    return st;
}

/* Count of the variables of a kind (uses the generated table). */
static inline int count_vars(dfo_var_type type)
{
    int n = 0;
    for (int i = 0; i < DFO_NUM_VARS; i++) n += DFO_VARS[i].type == type;
    return n;
}

#endif
