/* The DryFrictionOscillator instance core (osc_instance.h), its Model Exchange (core/instance_me.h):
 * the host integrates the continuous states (x, v) and handles the events; the core gives their
 * derivatives, the event indicators and the new mode at an event. No FMI types.
 *
 * The physics is the schemes': the sliding acceleration is dfo_acceleration with the friction force
 * of dfo_friction_force (newmark.h: Coulomb or Stribeck, on the velocity relative to the belt), the
 * static force and the rest rule are friction.h's. The discrete state is the mode (-1, 0, +1):
 *   sliding: x' = v, v' = the acceleration in the mode;
 *   stuck:   x' = v (= v_belt), v' = 0, the friction the holding force, the static force clamped.
 * Two event indicators, continuous distances (never signs), a fixed number in every mode:
 *   sliding: z0 = mode (v - v_belt) + DBL_MIN (the relative speed; a stop where it reaches 0),
 *            z1 = 1 (unused);
 *   stuck:   z0 = Fb - F_static, z1 = Fb + F_static (the margins to the breakaway limit
 *            Fb = max(mu_s, mu_k) N, one per direction: a breakaway where one reaches 0).
 * Hysteresis (as Reference-FMUs' BouncingBall places its ball DBL_MIN above the floor): a slide
 * starts at v = v_belt, where its z0 is DBL_MIN > 0, so no indicator is 0 right after the switch it
 * caused; the rest rule's tie |F_static| = Fb (a stick on the limit, whose margin would be 0) slides.
 * At an event the new mode comes from the rest rule once (no event iteration): a stop sets v to the
 * belt's speed and sticks or slides on (a reversal is one switch); a breakaway slides in the
 * direction of the static force. valuesOfContinuousStatesChanged at every switch: at a stop v was
 * set, at a breakaway the derivatives jump and a host's integrator must restart (fmusim restarts
 * CVODE only when told; without it the slide after a breakaway is lost). */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_instance.h"
#include "instance_me.h"

#include <float.h>
#include <math.h>

#define ME_STATES 2
#define ME_INDICATORS 2

size_t dfo_inst_me_n_states(const dfo_lifecycle *lc)
{
    (void)lc;
    return ME_STATES;
}
size_t dfo_inst_me_n_indicators(const dfo_lifecycle *lc)
{
    (void)lc;
    return ME_INDICATORS;
}

void dfo_inst_me_start(dfo_lifecycle *lc) { osc(lc)->me = 1; }

/* ---- the physics at the current state (the loads, the static force, the acceleration and the
 * indicators: osc_inst_vars.c, which reads them as outputs too) ------------------------------------- */

/* The new mode of a block at rest on the belt: the rest rule, its tie (|F_static| = Fb, where the
 * margin is 0) sliding. */
static int me_rest_mode(const osc_values *v, const dfo_loads *L)
{
    const double Fs = osc_inst_static_force(v, L);
    const int mode = dfo_rest_mode(L, Fs);
    return (mode == 0 && fabs(Fs) >= L->Fb) ? dfo_sign(Fs) : mode;
}

/* After the state, the time or the mode changed: the friction force and acceleration the outputs
 * read, for the current inputs. */
static void me_refresh(osc_values *v)
{
    v->s.A = osc_inst_me_acceleration(v, &v->s.F);
    v->s.hA = 0.0;
    v->u_used = v->u;
}

/* The values with the started model (during initialisation a copy derived on the fly). */
static const osc_values *me_values(const osc_instance *in, osc_values *tmp) { return osc_inst_computed(in, tmp); }

/* A wrong array size: the sentence naming the argument and its one valid value. */
static dfo_inst_status bad_size(osc_instance *in, const char *fn, const char *arg, size_t n, size_t want,
                                const char *what)
{
    return dfo_inst_fail(&in->lc, "%s: %s = %lu, but this FMU has %lu %s: %s must be %lu.", fn, arg, (unsigned long)n,
                         (unsigned long)want, what, arg, (unsigned long)want);
}

static int need_me(osc_instance *in, const char *fn)
{
    if (in->me) return 1;
    dfo_inst_fail(&in->lc, "%s: the instance was made for co-simulation; Model Exchange needs an instance made for "
                  "it.", fn);
    return 0;
}

/* The states' scales (a host's absolute tolerances are its relative one times these): the static
 * deflection F / k of the largest force F = max(|P0|, max(mu_s, mu_k) N, k |x0|, sqrt(k m) |v0|) and
 * the velocity sqrt(k / m) F / k of a motion that size; 1 where they are not positive numbers (no
 * spring, no force). */
static void me_nominals(const dfo_params *p, double nominal[2])
{
    const double F = osc_inst_force_scale(p);
    const double x = F / p->k, v = sqrt(p->k / p->m) * x;
    nominal[0] = isfinite(x) && x > 0.0 ? x : 1.0;
    nominal[1] = isfinite(v) && v > 0.0 ? v : 1.0;
}

/* The start of a call with an array of n values: the instance made for Model Exchange, n the size
 * (the argument arg, its one valid value want, what it counts). NULL (logged) when not. */
static osc_instance *me_array(dfo_lifecycle *lc, const char *fn, const char *arg, size_t n, size_t want,
                              const char *what)
{
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return NULL;
    if (n == want) return in;
    bad_size(in, fn, arg, n, want, what);
    return NULL;
}
#define ME_STATES_ARRAY(lc, fn, nx) me_array(lc, fn, "nx", nx, ME_STATES, "continuous states (x, v)")

/* ---- life cycle ----------------------------------------------------------------------------- */

dfo_inst_status dfo_inst_me_exit_init(dfo_lifecycle *lc, const char *fn)
{
    osc_instance *in = osc(lc);
    const dfo_inst_status st = dfo_inst_exit_init(lc, fn);
    if (st == DFO_INST_ERROR) return st;
    dfo_forget_caches(&in->v.s); /* the excitation in closed form at any time */
    me_refresh(&in->v);
    in->lc.run.phase = DFO_PHASE_EVENT;
    return st;
}

dfo_inst_status dfo_inst_me_update(dfo_lifecycle *lc, const char *fn, dfo_me_event_info *info)
{
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    osc_values *v = &in->v;
    dfo_state *s = &v->s;
    const dfo_me_event_info none = {0, 0, 0, 0, 0, 0.0};
    *info = none;
    dfo_loads L;
    if (!osc_inst_loads(v, &L)) return DFO_INST_OK; /* no friction: no events */
    const double vb = dfo_belt_speed(&v->u);
    const int from = s->mode;
    int to = from;
    double z[ME_INDICATORS];
    osc_inst_indicators(v, z);
    if (from != 0) {
        if (z[0] <= 0.0) { /* the relative velocity reached 0: a stop */
            s->V = vb;
            info->values_changed = 1;
            to = me_rest_mode(v, &L);
        }
    } else if (s->V != vb) { /* the belt's speed changed under a stuck block: it slides at its own speed */
        to = dfo_sign(s->V - vb);
    } else if (z[0] <= 0.0 || z[1] <= 0.0) { /* a margin reached 0: the breakaway limit */
        to = me_rest_mode(v, &L);
    }
    if (to != from) {
        /* a breakaway leaves x and v as they are, but their derivatives jump: an integrator that
         * keeps its history across the jump unless told (fmusim's CVODE) must restart */
        info->values_changed = 1;
        s->mode = to;
        s->t_switch = s->t;
        osc_inst_on_switch(in, s->t, s->X, from, to);
    }
    me_refresh(v);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_completed_step(dfo_lifecycle *lc, const char *fn, int *enter_event_mode, int *terminate)
{
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    const osc_values *v = &in->v;
    dfo_loads L;
    /* a stuck block whose belt's speed was changed by the host slides: an event to switch it */
    *enter_event_mode = osc_inst_loads(v, &L) && v->s.mode == 0 && v->s.V != dfo_belt_speed(&v->u);
    *terminate = 0;
    return DFO_INST_OK;
}

/* ---- the continuous state ------------------------------------------------------------------- */

dfo_inst_status dfo_inst_me_set_time(dfo_lifecycle *lc, const char *fn, double t)
{
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    if (!isfinite(t))
        return dfo_inst_fail(lc, "%s: time %g is not finite; it must be a finite number >= the start time %.17g.",
                             fn, t, lc->run.start_time);
    dfo_state *s = &in->v.s;
    s->t = t;
    /* the grid interval the time lies in (an FMU state's plausibility reads it) */
    const double k = floor((t - s->t0) / in->v.M.p.h);
    s->n = k > 0.0 && k < 9e18 ? (long long)k : 0;
    lc->run.time = t;
    me_refresh(&in->v);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_set_states(dfo_lifecycle *lc, const char *fn, const double x[], size_t nx)
{
    osc_instance *in = ME_STATES_ARRAY(lc, fn, nx);
    if (!in) return DFO_INST_ERROR;
    if (!isfinite(x[0]) || !isfinite(x[1]))
        return dfo_inst_fail(lc, "%s: the state x = %g, v = %g is not finite; x and v must be finite numbers.", fn,
                             x[0], x[1]);
    in->v.s.X = x[0];
    in->v.s.V = x[1];
    me_refresh(&in->v);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_get_states(dfo_lifecycle *lc, const char *fn, double x[], size_t nx)
{
    osc_instance *in = ME_STATES_ARRAY(lc, fn, nx);
    if (!in) return DFO_INST_ERROR;
    osc_values tmp;
    const osc_values *v = me_values(in, &tmp);
    x[0] = v->s.X;
    x[1] = v->s.V;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_nominals(dfo_lifecycle *lc, const char *fn, double x_nominal[], size_t nx)
{
    osc_instance *in = ME_STATES_ARRAY(lc, fn, nx);
    if (!in) return DFO_INST_ERROR;
    me_nominals(&in->v.p, x_nominal);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_derivatives(dfo_lifecycle *lc, const char *fn, double dx[], size_t nx)
{
    osc_instance *in = ME_STATES_ARRAY(lc, fn, nx);
    if (!in) return DFO_INST_ERROR;
    osc_values tmp;
    const osc_values *v = me_values(in, &tmp);
    dx[0] = v->s.V;
    dx[1] = osc_inst_me_acceleration(v, NULL);
    if (!isfinite(dx[1]))
        return dfo_inst_fail(lc, "%s: the acceleration at t = %.17g (x = %.17g, v = %.17g) is not representable in "
                             "double precision.", fn, v->s.t, v->s.X, v->s.V);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_indicators(dfo_lifecycle *lc, const char *fn, double z[], size_t nz)
{
    osc_instance *in = me_array(lc, fn, "ni", nz, ME_INDICATORS, "event indicators");
    if (!in) return DFO_INST_ERROR;
    osc_values tmp;
    osc_inst_indicators(me_values(in, &tmp), z);
    return DFO_INST_OK;
}
