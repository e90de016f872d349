/* Shared by the FMI 3.0 C hosts: checks, a logger that keeps the switches reported in logEvents
 * ("t = ...: stick -> forward slip at x = ..."), instantiation with the event options, parameters
 * set by name, and the schemes of the Scheme enumeration (from the generated variable table). */
#ifndef DFO_HOST3_H
#define DFO_HOST3_H

#include "fmi3Functions.h"
#include "model_vars.h"
#include "../check.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


#define MAX_SWITCHES 512
typedef struct {
    double t[MAX_SWITCHES];
    int from[MAX_SWITCHES], to[MAX_SWITCHES];
    int n;
    int errors; /* error messages logged */
    char last[512];
} host_env;

static inline int mode_of(const char *name)
{
    return !strncmp(name, "backward", 8) ? -1 : !strncmp(name, "stick", 5) ? 0 : 1;
}

static inline void host_logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    host_env *E = (host_env *)env;
    if (!E) return;
    if (status == fmi3Error) E->errors++;
    snprintf(E->last, sizeof E->last, "%s", message);
    if (strcmp(category, "logEvents") != 0 || E->n >= MAX_SWITCHES) return;
    double t = 0.0;
    char a[32], b[32];
    /* "t = %.17g: %s -> %s at x = %.17g." with two-word mode names */
    const char *p = strstr(message, "t = ");
    if (!p || sscanf(p, "t = %lf:", &t) != 1) return;
    const char *colon = strchr(p, ':'), *arrow = strstr(p, " -> ");
    if (!colon || !arrow) return;
    snprintf(a, sizeof a, "%.*s", (int)(arrow - colon - 2), colon + 2);
    snprintf(b, sizeof b, "%s", arrow + 4);
    E->t[E->n] = t;
    E->from[E->n] = mode_of(a);
    E->to[E->n] = mode_of(b);
    E->n++;
}

static inline fmi3Instance host_instantiate(host_env *E, int event_mode, int early_return, int log_events,
                                     fmi3IntermediateUpdateCallback update)
{
    fmi3Instance in = fmi3InstantiateCoSimulation("host3", MODEL_GUID, NULL, fmi3False, fmi3False,
                                                  event_mode ? fmi3True : fmi3False,
                                                  early_return ? fmi3True : fmi3False, NULL, 0, E, host_logger,
                                                  update);
    if (in && log_events) {
        const fmi3String cat[1] = {"logEvents"};
        fmi3SetDebugLogging(in, fmi3True, 1, cat);
    }
    return in;
}

/* Enter initialisation at t = 0, set the scheme and h, exit. */
static inline fmi3Status host_start(fmi3Instance in, int scheme, double h)
{
    fmi3Status st = fmi3EnterInitializationMode(in, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    const fmi3ValueReference vr_scheme[1] = {VR_scheme}, vr_h[1] = {VR_h};
    const fmi3Int64 sc[1] = {scheme};
    const fmi3Float64 hv[1] = {h};
    if (st == fmi3OK) st = fmi3SetInt64(in, vr_scheme, 1, sc, 1);
    if (st == fmi3OK) st = fmi3SetFloat64(in, vr_h, 1, hv, 1);
    if (st == fmi3OK) st = fmi3ExitInitializationMode(in);
    return st;
}

static inline double get_real(fmi3Instance in, fmi3ValueReference vr)
{
    fmi3Float64 v = NAN;
    fmi3GetFloat64(in, &vr, 1, &v, 1);
    return v;
}

static inline int get_mode(fmi3Instance in)
{
    const fmi3ValueReference vr = VR_mode;
    fmi3Int32 m = 99;
    fmi3GetInt32(in, &vr, 1, &m, 1);
    return m;
}

/* The values of the Scheme enumeration (the table's item list of the variable scheme). */
static inline int host_schemes(int out[], int max)
{
    for (int i = 0; i < DFO_NUM_VARS; i++)
        if (DFO_VARS[i].vr == VR_scheme) {
            int n = DFO_VARS[i].n_items < max ? DFO_VARS[i].n_items : max;
            for (int k = 0; k < n; k++) out[k] = (int)DFO_VARS[i].items[k];
            return n;
        }
    return 0;
}

/* The default model: excitation period 2 pi / 5; the host runs four periods on a grid of 0.1 s. */
#define HOST_T (2.0 * 3.14159265358979323846 / 5.0)
#define HOST_T_END (4.0 * HOST_T)
#define HOST_DT 0.1

/* A plain run (no early return) with logEvents on: the reference switches. */
/* A switch time t of a run split at its switches (early return: one grid step per call) is the plain
 * run's ref: its calls end elsewhere, so the times agree to rounding amplified by the motion (a few
 * to tens of ulps), far below the scheme's error and a grid step (what a wrong return point is off) */
static inline int same_switch_time(double t, double ref) { return fabs(t - ref) <= 1e-12 * fabs(ref); }

static inline int reference_switches(int scheme, double h, host_env *E)
{
    memset(E, 0, sizeof *E);
    fmi3Instance in = host_instantiate(E, 0, 0, 1, NULL);
    if (!in || host_start(in, scheme, h) != fmi3OK) return 0;
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    double t = 0.0;
    for (int k = 1; t < HOST_T_END; k++) {
        const double target = fmin(k * HOST_DT, HOST_T_END);
        if (fmi3DoStep(in, t, target - t, fmi3True, &ev, &term, &early, &last) != fmi3OK) break;
        t = target;
    }
    fmi3Terminate(in);
    fmi3FreeInstance(in);
    return 1;
}

#endif
