/* Bossak-Newmark time stepping in velocity form with the friction LCP (method.md sections 2-4, 8).
 *
 * Three variants (dfo_scheme): the paper's literal scheme, the consistent stick test (first order)
 * and the located scheme (default; every stick/slip switch placed inside its step, second order).
 * The internal grid is t0 + n h; dfo_advance ends exactly on any requested time with a shortened
 * step whose Bossak acceleration is corrected for the new length (method.md section 8).
 *
 * Plain C, no FMI types. */
#ifndef DFO_NEWMARK_H
#define DFO_NEWMARK_H

#include "oscillator.h"

typedef enum {
    DFO_OK = 0,
    DFO_ERR_LCP = 1,          /* Lemke reported failure */
    DFO_ERR_NO_PROGRESS = 2,  /* too many switches inside one internal step */
    DFO_ERR_NONFINITE = 3,    /* the state overflowed */
    DFO_ERR_RESOLUTION = 4    /* a step would not advance time (h below the resolution of t) */
} dfo_status;

typedef struct {
    /* time: the last internal grid point reached is t0 + n h; t is the current time */
    double t0, t;
    long long n;
    /* kinematics: position, velocity, Bossak acceleration variable, and the step length that
     * produced A (0 when A is a physical acceleration: start-up, stick, consistent restart) */
    double X, V, A, hA;
    double F;      /* friction force at t */
    int mode;      /* -1 backward slip, 0 stuck, +1 forward slip */
    /* in-FMU observables over [t_obs_start, t_obs_stop] (only updated when observe is on) */
    double x_max, x_min, t_stuck, E_friction;
    long long transitions;
    int observed;  /* a sample has been taken */
    /* the stick phase's next breakaway: time and side, computed at its first step for the static
     * force offset stick_C = u - k X and the limit stick_Fb (NaN: to be computed) */
    double stick_C, stick_Fb, stick_tb;
    int stick_dir;
    /* excitation cache: cos and sin of the excitation phase omega (t0 + exc_n h) + phi at the grid
     * point exc_n (-1: empty). A pure function of exc_n: exact at every multiple of DFO_EXC_ANCHOR,
     * advanced by rotations by omega h in between. */
    long long exc_n;
    double exc_c, exc_s;
    /* counters */
    long long steps, lcp_solves;
} dfo_state;

/* Consistent start-up at t0 from x0, v0 (method.md section 4, "Start-up"). */
void dfo_start(const dfo_model *M, const dfo_inputs *u, double t0, dfo_state *s);

/* Empty the excitation cache of a state (it is rebuilt on demand, to the same bits). */
void dfo_forget_caches(dfo_state *s);

/* For a state that was not produced by this instance (e.g. a deserialised one): keep its excitation
 * cache only if it equals its recomputation, else empty it; a breakaway side out of range makes the
 * next breakaway be computed anew. */
void dfo_check_caches(const dfo_model *M, dfo_state *s);

/* Called at every change of mode (stick/slip switch) with its time and position. */
typedef void (*dfo_switch_fn)(void *ctx, double t, double x, int from_mode, int to_mode);

/* Advance to t_target > s->t, with the inputs held constant. on_switch may be NULL. */
dfo_status dfo_advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                       dfo_switch_fn on_switch, void *switch_ctx);

/* Physical acceleration at the current state (0 while stuck for consistent and located). */
double dfo_acceleration(const dfo_model *M, const dfo_inputs *u, const dfo_state *s);

/* Share of the observed time spent stuck (0 before the window opens). */
double dfo_stick_fraction(const dfo_model *M, const dfo_state *s);

const char *dfo_status_text(dfo_status st);

#endif
