/* The exact scheme's event loop (private), one for every phase: the spring's (exact_spring.c) and the
 * free mass's (exact_free.c), held and polynomial inputs, on a support at rest or on a belt. A call is
 * a walk through phases: at each event the block is at rest without friction (it starts along the
 * force), stuck (the phase ends at the breakaway) or sliding (the phase ends at the first stop, where
 * the rule at a stop below decides the next mode). The loop holds what every walk shares: the work
 * bound (DFO_EXACT_MAX_EVENTS, exact.h), the stall bound (events in a row at one instant), the choice
 * of the phase, the rule at a stop and its saltation of the sensitivity; the phase's file supplies
 * its walk (time, state, caches) and its three phases.
 *
 * Header only: the loop is compiled into each phase's file, once for each kind of inputs (held,
 * polynomial: a constant in each), so that the loop of held inputs carries none of the polynomial
 * inputs' code. Plain C, no FMI types. */
#ifndef DFO_EXACT_LOOP_H
#define DFO_EXACT_LOOP_H

#include "exact_private.h"
#include "exact_sens.h"

#define DFO_EXACT_MAX_STALL 64 /* events in a row at one instant before it is an error */

/* What a phase returns besides an error status (dfo_status): the walk goes on, or has reached its target. */
#define DFO_EXACT_NEXT (-1)
#define DFO_EXACT_DONE (-2)

/* A walk's own parts (w: the walk): its time is before the target (running); its time is the one at the
 * last event (same_time; mark_time makes it so); the phase from rest without friction, a stick phase and a
 * slip phase from the walk's state, each DFO_EXACT_NEXT, DFO_EXACT_DONE or an error status. */
typedef struct {
    int (*running)(const void *w);
    int (*same_time)(const void *w);
    void (*mark_time)(void *w);
    int (*start_free)(void *w);
    int (*stick)(void *w);
    int (*slide)(void *w);
} dfo_exact_walk_fns;

/* The loop: s the walk's state (its mode read at each event), *events the walk's event count, fric the
 * friction acts (else a block at rest starts along the force). DFO_OK when the walk reached its target. */
static DFO_EXACT_INLINE dfo_status dfo_exact_event_loop(void *w, const dfo_exact_walk_fns *f, const dfo_state *s,
                                                        const long long *events, int fric)
{
    int stall = 0;
    while (f->running(w)) {
        if (*events >= DFO_EXACT_MAX_EVENTS) return DFO_ERR_EVENTS; /* the work bound */
        if (f->same_time(w)) {
            if (++stall > DFO_EXACT_MAX_STALL) return DFO_ERR_NO_PROGRESS;
        } else {
            stall = 0;
            f->mark_time(w);
        }
        const int r = (s->mode == 0 && !fric) ? f->start_free(w) : (s->mode == 0) ? f->stick(w) : f->slide(w);
        if (r == DFO_EXACT_DONE) break;
        if (r != DFO_EXACT_NEXT) return (dfo_status)r;
    }
    return DFO_OK;
}

/* The rule at a stop of a slide in direction sd: the rest rule of friction.h with the static force Fs
 * and the loads L there; without friction (fric 0) never stuck: at a zero force the velocity, falling
 * through 0, reverses. null: the slide could not start (a slide from rest that never left the rounding
 * band): with friction the block stays at rest, and a breakaway right now is passed over (*skip set). */
static inline int dfo_exact_stop_mode(const dfo_loads *L, double Fs, int sd, int null, int fric, int *skip)
{
    int next = dfo_rest_mode(L, Fs);
    if (!fric) {
        if (next == 0 || (null && next == sd)) next = -sd;
    } else if (null && next != -sd) {
        next = 0;
        *skip = 1;
    }
    return next;
}

/* The sensitivity's saltation at that stop (exact_sens.h): stick (rank one), or a reversal (a- = (Fs - sd
 * mu_k N) / m before, a+ = (Fs + sd mu_k N) / m after, the kinetic force there); a touch that slides on,
 * or a reversal without friction (a+ = a-), leaves J as it is. */
static inline void dfo_exact_stop_saltation(double J[4], const dfo_loads *L, double Fs, int sd, int null, int next)
{
    if (next == 0 || null) dfo_sens_stick(J);
    else if (next == -sd && L->muk_N > 0.0) dfo_sens_reversal(J, (Fs + sd * L->muk_N) / (Fs - sd * L->muk_N));
}

#endif
