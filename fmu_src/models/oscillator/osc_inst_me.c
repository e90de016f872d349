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
 * belt's speed (valuesOfContinuousStatesChanged) and sticks or slides on (a reversal is one switch);
 * a breakaway slides in the direction of the static force. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_instance.h"
#include "instance_me.h"

#include <float.h>
#include <math.h>

#define ME_STATES 2
#define ME_INDICATORS 2
#define STATES_TEXT "continuous states (x, v)"

size_t dfo_inst_me_n_states(void) { return ME_STATES; }
size_t dfo_inst_me_n_indicators(void) { return ME_INDICATORS; }

void dfo_inst_me_start(dfo_lifecycle *lc) { osc(lc)->me = 1; }

/* ---- the physics at the current state ------------------------------------------------------- */

/* The loads under the current inputs; whether friction acts. */
static int me_loads(const osc_values *v, dfo_loads *L)
{
    dfo_loads_init(L, &v->M, &v->u);
    return L->Fb > 0.0;
}

/* The static force on the block at rest on the belt: friction.h's P + F_ext - k x, less the damper's
 * pull c v_belt, with the excitation as dfo_acceleration evaluates it. */
static double me_static_force(const osc_values *v, const dfo_loads *L)
{
    const dfo_model *M = &v->M;
    const double t = v->s.t;
    const double P = M->p.scheme == DFO_SCHEME_EXACT ? dfo_excitation_exact(M, t) : dfo_excitation(M, t);
    return dfo_static_force(M->p.k, L, P, v->s.X) - M->p.c * dfo_belt_speed(&v->u);
}

/* The new mode of a block at rest on the belt: the rest rule, its tie (|F_static| = Fb, where the
 * margin is 0) sliding. */
static int me_rest_mode(const osc_values *v, const dfo_loads *L)
{
    const double Fs = me_static_force(v, L);
    const int mode = dfo_rest_mode(L, Fs);
    return (mode == 0 && fabs(Fs) >= L->Fb) ? dfo_sign(Fs) : mode;
}

/* The friction force and the acceleration at the current state in its mode (stuck: 0). */
static double me_acceleration(const osc_values *v, double *F)
{
    dfo_state s = v->s;
    s.F = dfo_friction_force(&v->M, &v->u, &s);
    if (F) *F = s.F;
    dfo_loads L;
    if (me_loads(v, &L) && s.mode == 0) return 0.0;
    return dfo_acceleration(&v->M, &v->u, &s);
}

/* After the state, the time or the mode changed: the friction force and acceleration the outputs
 * read, for the current inputs. */
static void me_refresh(osc_values *v)
{
    v->s.A = me_acceleration(v, &v->s.F);
    v->s.hA = 0.0;
    v->u_used = v->u;
}

/* The values with the started model (during initialisation a copy derived on the fly). */
static const osc_values *me_values(const osc_instance *in, osc_values *tmp) { return osc_inst_computed(in, tmp); }

/* A wrong array size: the sentence naming the argument and its one valid value. */
static dfo_inst_status bad_size(osc_instance *in, const char *fn, const char *arg, size_t n, size_t want,
                                const char *what)
{
    return dfo_inst_fail(&in->lc, "%s: %s = %zu, but this FMU has %zu %s: %s must be %zu.", fn, arg, n, want, what, arg,
                         want);
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

dfo_inst_status dfo_inst_me_enter_event_mode(dfo_lifecycle *lc)
{
    lc->run.phase = DFO_PHASE_EVENT;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_enter_continuous(dfo_lifecycle *lc)
{
    lc->run.phase = DFO_PHASE_STEP;
    return DFO_INST_OK;
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
    if (!me_loads(v, &L)) return DFO_INST_OK; /* no friction: no events */
    const double vb = dfo_belt_speed(&v->u);
    const int from = s->mode;
    int to = from;
    if (from != 0) {
        if (from * (s->V - vb) + DBL_MIN <= 0.0) { /* z0 reached 0: stopped */
            s->V = vb;
            info->values_changed = 1;
            to = me_rest_mode(v, &L);
        }
    } else if (s->V != vb) { /* the belt's speed changed under a stuck block: it slides at its own speed */
        to = dfo_sign(s->V - vb);
    } else {
        const double Fs = me_static_force(v, &L);
        if (L.Fb - Fs <= 0.0 || L.Fb + Fs <= 0.0) to = me_rest_mode(v, &L);
    }
    if (to != from) {
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
    *enter_event_mode = me_loads(v, &L) && v->s.mode == 0 && v->s.V != dfo_belt_speed(&v->u);
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
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    if (nx != ME_STATES) return bad_size(in, fn, "nx", nx, ME_STATES, STATES_TEXT);
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
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    if (nx != ME_STATES) return bad_size(in, fn, "nx", nx, ME_STATES, STATES_TEXT);
    osc_values tmp;
    const osc_values *v = me_values(in, &tmp);
    x[0] = v->s.X;
    x[1] = v->s.V;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_nominals(dfo_lifecycle *lc, const char *fn, double x_nominal[], size_t nx)
{
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    if (nx != ME_STATES) return bad_size(in, fn, "nx", nx, ME_STATES, STATES_TEXT);
    me_nominals(&in->v.p, x_nominal);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_derivatives(dfo_lifecycle *lc, const char *fn, double dx[], size_t nx)
{
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    if (nx != ME_STATES) return bad_size(in, fn, "nx", nx, ME_STATES, STATES_TEXT);
    osc_values tmp;
    const osc_values *v = me_values(in, &tmp);
    dx[0] = v->s.V;
    dx[1] = me_acceleration(v, NULL);
    if (!isfinite(dx[1]))
        return dfo_inst_fail(lc, "%s: the acceleration at t = %.17g (x = %.17g, v = %.17g) is not representable in "
                             "double precision.", fn, v->s.t, v->s.X, v->s.V);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_indicators(dfo_lifecycle *lc, const char *fn, double z[], size_t nz)
{
    osc_instance *in = osc(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    if (nz != ME_INDICATORS) return bad_size(in, fn, "ni", nz, ME_INDICATORS, "event indicators");
    osc_values tmp;
    const osc_values *v = me_values(in, &tmp);
    dfo_loads L;
    z[0] = z[1] = 1.0;
    if (!me_loads(v, &L)) return DFO_INST_OK; /* no friction: no events */
    if (v->s.mode != 0) {
        z[0] = v->s.mode * (v->s.V - dfo_belt_speed(&v->u)) + DBL_MIN;
    } else {
        const double Fs = me_static_force(v, &L);
        z[0] = L.Fb - Fs;
        z[1] = L.Fb + Fs;
    }
    return DFO_INST_OK;
}
