/* The state of the oscillator's time stepping and the status of a call, shared by every scheme (the
 * Bossak schemes of newmark.h and the exact scheme of exact.h, peers below the dispatching
 * dfo_advance of scheme.h): the time, the kinematics, the friction's mode, the in-FMU observables,
 * the caches and counters, the sensitivity. Plain values without pointers (an FMU state copies it,
 * its serialisation writes its fields). Types only. Plain C, no FMI types. */
#ifndef DFO_SCHEME_STATE_H
#define DFO_SCHEME_STATE_H

typedef enum {
    DFO_OK = 0,
    DFO_ERR_LCP = 1,          /* Lemke reported failure */
    DFO_ERR_NO_PROGRESS = 2,  /* too many switches inside one internal step */
    DFO_ERR_NONFINITE = 3,    /* the state overflowed */
    DFO_ERR_RESOLUTION = 4,   /* a step would not advance time (h below the resolution of t) */
    DFO_ERR_EVENTS = 5        /* the exact scheme: more than DFO_EXACT_MAX_EVENTS (exact.h) events in one call */
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
    double t_switch; /* the time of the last stick/slip switch of the Bossak schemes (-inf: none), as
                      * reported (a switch on a step's end: its t + h, to rounding) */
    /* in-FMU observables over [t_obs_start, t_obs_stop] (only updated when observe is on) */
    double x_max, x_min, t_stuck, E_friction;
    long long transitions;
    int observed;  /* a sample has been taken */
    /* the Bossak schemes' stuck stretch (consecutive stuck phases) open since stuck_from (NaN: none):
     * its part inside the window is added to t_stuck in one piece when a phase in another mode ends
     * (dfo_stuck_time reads the open part in), so that the stuck time is the same whether the steps
     * are taken one by one or at once, and however the run is split into calls */
    double stuck_from;
    /* the stick phase's next breakaway: time and side, computed at its first step for the constant
     * part of the static force stick_C = F_ext - k X and the limit stick_Fb (NaN: to be computed) */
    double stick_C, stick_Fb, stick_tb;
    int stick_dir;
    /* excitation cache: cos and sin of the excitation phase omega (t0 + exc_n h) + phi at the grid
     * point exc_n (-1: empty). A pure function of exc_n: exact at every multiple of DFO_EXC_ANCHOR,
     * advanced by rotations by omega h in between. */
    long long exc_n;
    double exc_c, exc_s;
    /* counters */
    long long steps, lcp_solves;
    /* the Jacobian d(X, V) / d(X, V)(t_ref), row-major (dX/dX0, dX/dV0, dV/dX0, dV/dV0), t_ref the end of
     * initialisation or the last state restore: propagated by the exact scheme when sensitivity is on */
    double J[4];
} dfo_state;

/* Called at every change of mode (stick/slip switch) with its time and position. */
typedef void (*dfo_switch_fn)(void *ctx, double t, double x, int from_mode, int to_mode);

#endif
