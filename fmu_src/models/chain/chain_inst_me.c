/* The DryFrictionChain instance core (chain_instance.h), its Model Exchange (core/instance_me.h):
 * the host integrates the continuous states (x and v of every block) and handles the events; the
 * core gives their derivatives, the event indicators and the new modes at an event. No FMI types.
 *
 * The physics is the schemes': the accelerations are the friction engine's (chain_accelerations:
 * eng_accelerations through the chain's operators, its held solve with every stuck block held, a
 * sliding block's force its kinetic one, Coulomb or Stribeck on the velocity relative to its belt),
 * the loads, the static force and the rest rule are friction.h's. The discrete state is each
 * block's mode (-1, 0, +1):
 *   sliding: x_i' = v_i, v_i' = the engine's acceleration in the modes;
 *   stuck:   x_i' = v_i (= v_belt_i), v_i' = 0, the friction the holding force.
 * The mass matrix is diagonal and the blocks are coupled through x and v only (springs, dampers),
 * so the engine's held solve (M a = r + f_H, a_H = 0) gives each stuck block its own static force,
 * F_static_i = P_i(t) + F_ext_i - (K x)_i - (C v)_i, and the holding force -F_static_i: the
 * constrained equations of several stuck neighbours decouple, and so does the rest rule (a block
 * switched to sliding changes no other block's static force at that instant: the engine's cascade,
 * "the one most beyond its limit slides, the rest solved again", decides each block alone).
 * Two event indicators per block, continuous distances (never signs), 2 n in every mode: block i's
 * z_i and z_{n+i},
 *   sliding: z_i = mode (v_i - v_belt_i) + DBL_MIN (the relative speed; a stop where it reaches 0),
 *            z_{n+i} = 1 (unused);
 *   stuck:   z_i = Fb_i - F_static_i, z_{n+i} = Fb_i + F_static_i (the margins to the breakaway
 *            limit Fb = max(mu_s, mu_k) N, one per direction: a breakaway where one reaches 0);
 *   without friction (Fb = 0): 1 and 1.
 * Hysteresis as the oscillator's (osc_inst_me.c): a slide starts at v = v_belt, where its z is
 * DBL_MIN > 0; the rest rule's tie |F_static| = Fb slides. At an event, once (no event iteration):
 * every block whose relative velocity reached 0 is set on its belt, then every block at rest takes
 * the rest rule (a stop sticks or slides on, a reversal being one switch; a breakaway slides the way
 * its static force drives it); valuesOfContinuousStatesChanged at every switch, as the oscillator. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_instance.h"
#include "chain_internal.h"
#include "instance_me.h"

#include <float.h>
#include <math.h>
#include <string.h>

size_t dfo_inst_me_n_states(const dfo_lifecycle *lc) { return 2 * cchn(lc)->v.n; }
size_t dfo_inst_me_n_indicators(const dfo_lifecycle *lc) { return 2 * cchn(lc)->v.n; }

void dfo_inst_me_start(dfo_lifecycle *lc) { chn(lc)->v.me = 1; }

/* ---- the physics at the current state ------------------------------------------------------- */

/* Block i's loads (friction.h) under the model's current loads (chain_loads_init). */
static dfo_loads block_loads(const chain_model *M, size_t i)
{
    const dfo_loads L = {M->u[i], M->Nn[i], M->mukN[i], M->Fb[i]};
    return L;
}

/* The excitation's phase at the state's time: cos and sin of omega t + phi0 (once per call). */
static void phase_now(const chain_model *M, const chain_state *s, double ph[2])
{
    chain_phase_of(M, s, s->t, &ph[0], &ph[1]);
}

/* Block i's static force at the phase ph: the net applied force on it at the state, the one its
 * friction holds while it is stuck (the engine's held solve: M diagonal, so -(its holding force)). */
static double static_force(const chain_model *M, const chain_state *s, const double ph[2], size_t i)
{
    return chain_P_at(M, i, ph[0], ph[1]) + M->u[i] - chain_Kx(M, s->X, i) - chain_Cv(M, s->V, i);
}

/* The rest rule of a block at rest on its belt (friction.h's dfo_rest_mode), its tie
 * (|F_static| = Fb, where a margin is 0) sliding. */
static int rest_mode(const chain_model *M, const chain_state *s, const double ph[2], size_t i)
{
    const dfo_loads L = block_loads(M, i);
    const double Fs = static_force(M, s, ph, i);
    const int mode = dfo_rest_mode(&L, Fs);
    return (mode == 0 && fabs(Fs) >= L.Fb) ? dfo_sign(Fs) : mode;
}

/* The model's loads for the current inputs; the inputs now are those the state is on. Returns the
 * belts (NULL: none). */
static const double *me_loads(chain_values *v, chain_inputs *ci)
{
    memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    memcpy(v->u_set_used, v->u_set, sizeof v->u_set);
    v->belts_unsynced = 0;
    *ci = chain_inst_inputs_of(v, 0);
    chain_loads_init(v->M, ci);
    return chain_inst_belt_of(v, 0);
}

/* After the state, the time, the inputs or the modes changed: the friction forces (a slide's
 * kinetic force at its relative speed, a stuck block's holding force clamped to its limit) into the
 * state, the accelerations (output a, the derivatives) into scratch. */
static void me_refresh(chain_values *v)
{
    v->me_fresh = 1;
    chain_inputs ci;
    const double *vb = me_loads(v, &ci);
    chain_model *M = v->M;
    chain_state *s = &v->s;
    double ph[2];
    phase_now(M, s, ph);
    for (size_t i = 0; i < v->n; i++) {
        if (!chain_has_friction(M, i)) s->F[i] = 0.0;
        else if (s->mode[i] != 0) s->F[i] = -s->mode[i] * chain_slide_mag(M, vb, s, i);
        else {
            const dfo_loads L = block_loads(M, i);
            s->F[i] = dfo_stick_force(&L, static_force(M, s, ph, i));
        }
    }
    chain_accelerations(M, &ci, vb, s, v->scratch);
    for (size_t i = 0; i < v->n; i++) {
        s->A[i] = v->scratch[i];
        s->hA[i] = 0.0;
    }
    v->acc_valid = 1;
}

void chain_inst_me_refresh(chain_values *v)
{
    if (!v->me_fresh) me_refresh(v);
}

/* Block i's two event indicators at the state on the belts vb (NULL: none), the model's loads
 * those of the inputs. */
static void block_indicators(const chain_model *M, const chain_state *s, const double *vb, const double ph[2], size_t i,
                             double z[2])
{
    z[0] = z[1] = 1.0;
    if (!chain_has_friction(M, i)) return;
    if (s->mode[i] != 0) {
        z[0] = s->mode[i] * (s->V[i] - (vb ? vb[i] : 0.0)) + DBL_MIN;
        return;
    }
    const double Fs = static_force(M, s, ph, i);
    z[0] = M->Fb[i] - Fs;
    z[1] = M->Fb[i] + Fs;
}

/* The modes of the blocks without friction: their slip's direction (as the engine's). */
static void free_modes(chain_values *v, const double *vb)
{
    for (size_t i = 0; i < v->n; i++)
        if (!chain_has_friction(v->M, i)) v->s.mode[i] = chain_sgn(v->s.V[i] - (vb ? vb[i] : 0.0));
}

/* ---- checks ----------------------------------------------------------------------------------- */

static int need_me(chain_instance *in, const char *fn)
{
    if (in->v.me) return 1;
    dfo_inst_fail(&in->lc, "%s: the instance was made for co-simulation; Model Exchange needs an instance made for "
                  "it.", fn);
    return 0;
}

/* The start of a call with an array of nx values: the instance made for Model Exchange and started
 * (else the model is built from the values on the fly: during initialisation), nx its size (the
 * argument arg, its one valid value 2 n, what it counts). NULL (logged) when not. */
static chain_instance *me_array(dfo_lifecycle *lc, const char *fn, const char *arg, size_t nx, const char *what)
{
    chain_instance *in = chn(lc);
    if (!need_me(in, fn)) return NULL;
    const size_t want = 2 * in->v.n;
    if (nx != want) {
        dfo_inst_fail(lc, "%s: %s = %lu, but this FMU has %lu %s (n = %lu blocks): %s must be %lu.", fn, arg,
                      (unsigned long)nx, (unsigned long)want, what, (unsigned long)in->v.n, arg, (unsigned long)want);
        return NULL;
    }
    if (!chain_inst_started(in)) {
        char buf[640];
        const char *msg = chain_inst_prepare(in, buf, sizeof buf);
        if (msg) {
            dfo_inst_fail(lc, "%s: the model cannot be started: %s.", fn, msg);
            return NULL;
        }
        in->v.s.exc_n = -1; /* the excitation in closed form at any time */
        me_refresh(&in->v);
    }
    return in;
}
#define ME_STATES_ARRAY(lc, fn, nx) me_array(lc, fn, "nx", nx, "continuous states (x and v of each block)")

/* After a call that built the model on the fly (during initialisation): the model released. */
static void me_done(chain_instance *in)
{
    if (!chain_inst_started(in)) chain_inst_free_model(&in->v);
}

/* ---- life cycle ----------------------------------------------------------------------------- */

dfo_inst_status dfo_inst_me_exit_init(dfo_lifecycle *lc, const char *fn)
{
    chain_instance *in = chn(lc);
    const dfo_inst_status st = dfo_inst_exit_init(lc, fn);
    if (st == DFO_INST_ERROR) return st;
    in->v.s.exc_n = -1;
    me_refresh(&in->v);
    in->lc.run.phase = DFO_PHASE_EVENT;
    return st;
}

dfo_inst_status dfo_inst_me_update(dfo_lifecycle *lc, const char *fn, dfo_me_event_info *info)
{
    chain_instance *in = chn(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    chain_values *v = &in->v;
    chain_state *s = &v->s;
    const dfo_me_event_info none = {0, 0, 0, 0, 0, 0.0};
    *info = none;
    chain_inputs ci;
    const double *vb = me_loads(v, &ci);
    chain_model *M = v->M;
    const size_t n = v->n;
    /* the stops: a sliding block whose relative velocity reached 0 is set on its belt */
    double *to_mode = v->scratch; /* (the new modes; the accelerations again at the end) */
    for (size_t i = 0; i < n; i++) {
        if (!chain_has_friction(M, i) || s->mode[i] == 0) continue;
        const double b = vb ? vb[i] : 0.0;
        if (s->mode[i] * (s->V[i] - b) + DBL_MIN <= 0.0) {
            s->V[i] = b;
            info->values_changed = 1;
        }
    }
    double ph[2];
    phase_now(M, s, ph);
    /* the new modes: every block at rest on its belt by the rest rule, a stuck block off its belt
     * (the host changed the belt's speed) slides at its own speed */
    for (size_t i = 0; i < n; i++) {
        to_mode[i] = (double)s->mode[i];
        if (!chain_has_friction(M, i)) continue;
        const double b = vb ? vb[i] : 0.0;
        const int from = s->mode[i];
        int to = from;
        if (s->V[i] == b) {
            const double Fs = static_force(M, s, ph, i);
            const int at_limit = from == 0 && (M->Fb[i] - Fs <= 0.0 || M->Fb[i] + Fs <= 0.0);
            if (from != 0 || at_limit) to = rest_mode(M, s, ph, i);
        } else if (from == 0) {
            to = chain_sgn(s->V[i] - b);
        }
        to_mode[i] = (double)to;
    }
    for (size_t i = 0; i < n; i++) {
        if (!chain_has_friction(M, i)) continue;
        const int from = s->mode[i], to = (int)to_mode[i];
        if (to == from) continue;
        /* a breakaway leaves x and v as they are, but the derivatives jump: the host's integrator
         * must restart */
        info->values_changed = 1;
        s->mode[i] = to;
        s->switches++;
        s->t_switch = s->t;
        if (to == 0) s->t_stick[i] = s->t;
        v->sw_t = s->t;
        v->sw_block = (long long)i;
        dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: block %lu %s -> %s at x = %.17g.", s->t,
                     (unsigned long)i + 1, from == 0 ? "stuck" : (from > 0 ? "slip+" : "slip-"),
                     to == 0 ? "stuck" : (to > 0 ? "slip+" : "slip-"), s->X[i]);
    }
    free_modes(v, vb);
    me_refresh(v);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_completed_step(dfo_lifecycle *lc, const char *fn, int *enter_event_mode, int *terminate)
{
    chain_instance *in = chn(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    chain_values *v = &in->v;
    const double *vb = chain_inst_belt_of(v, 0);
    *enter_event_mode = 0;
    *terminate = 0;
    /* a stuck block whose belt's speed the host changed slides: an event to switch it */
    for (size_t i = 0; i < v->n && !*enter_event_mode; i++)
        *enter_event_mode = v->s.mode[i] == 0 && chain_has_friction(v->M, i) && v->s.V[i] != (vb ? vb[i] : 0.0);
    return DFO_INST_OK;
}

/* ---- the continuous state ------------------------------------------------------------------- */

dfo_inst_status dfo_inst_me_set_time(dfo_lifecycle *lc, const char *fn, double t)
{
    chain_instance *in = chn(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    if (!isfinite(t))
        return dfo_inst_fail(lc, "%s: time %g is not finite; it must be a finite number >= the start time %.17g.",
                             fn, t, lc->run.start_time);
    chain_state *s = &in->v.s;
    s->t = t;
    /* the grid interval the time lies in (an FMU state's plausibility reads it) */
    const double k = floor((t - s->t0) / chain_step(in->v.M));
    s->n_grid = k > 0.0 && k < 9e18 ? (long long)k : 0;
    lc->run.time = t;
    in->v.me_fresh = 0;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_set_states(dfo_lifecycle *lc, const char *fn, const double x[], size_t nx)
{
    chain_instance *in = ME_STATES_ARRAY(lc, fn, nx);
    if (!in) return DFO_INST_ERROR;
    const size_t n = in->v.n;
    for (size_t i = 0; i < nx; i++)
        if (!isfinite(x[i])) {
            me_done(in);
            return dfo_inst_fail(lc, "%s: x[%lu] = %g, the %s of block %lu, is not finite; the states must be finite "
                                 "numbers.", fn, (unsigned long)i, x[i], i < n ? "position" : "velocity",
                                 (unsigned long)(i % n) + 1);
        }
    memcpy(in->v.s.X, x, n * sizeof(double));
    memcpy(in->v.s.V, x + n, n * sizeof(double));
    in->v.me_fresh = 0;
    me_done(in);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_get_states(dfo_lifecycle *lc, const char *fn, double x[], size_t nx)
{
    chain_instance *in = ME_STATES_ARRAY(lc, fn, nx);
    if (!in) return DFO_INST_ERROR;
    const size_t n = in->v.n;
    memcpy(x, in->v.s.X, n * sizeof(double));
    memcpy(x + n, in->v.s.V, n * sizeof(double));
    me_done(in);
    return DFO_INST_OK;
}

/* The states' scales (a host's absolute tolerances are its relative one times these): block i's
 * static deflection F / K_i of the largest force F over the blocks (max(|P0|, max(mu_s, mu_k) N,
 * K |x0|, sqrt(K m) |v0|), K_i the springs on block i) and the velocity sqrt(K_i / m_i) times it; 1
 * where they are not positive numbers (no spring, no force). */
dfo_inst_status dfo_inst_me_nominals(dfo_lifecycle *lc, const char *fn, double x_nominal[], size_t nx)
{
    chain_instance *in = chn(lc);
    if (!need_me(in, fn)) return DFO_INST_ERROR;
    const size_t n = in->v.n;
    if (nx != 2 * n)
        return dfo_inst_fail(lc, "%s: nx = %lu, but this FMU has %lu continuous states (x and v of each block, n = "
                             "%lu blocks): nx must be %lu.", fn, (unsigned long)nx, (unsigned long)(2 * n),
                             (unsigned long)n, (unsigned long)(2 * n));
    const chain_params p = chain_inst_params_of(&in->v);
    double F = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double K = p.k[i] + (i + 1 < n ? p.k[i + 1] : p.k_end) + p.k_site[i];
        F = fmax(F, fmax(fmax(fabs(p.P0[i]), fmax(p.mu_s[i], p.chi[i] * p.mu_s[i]) * p.N[i]),
                         fmax(K * fabs(p.x0[i]), sqrt(K * p.m[i]) * fabs(p.v0[i]))));
    }
    for (size_t i = 0; i < n; i++) {
        const double K = p.k[i] + (i + 1 < n ? p.k[i + 1] : p.k_end) + p.k_site[i];
        const double x = F / K, u = sqrt(K / p.m[i]) * x;
        x_nominal[i] = isfinite(x) && x > 0.0 ? x : 1.0;
        x_nominal[n + i] = isfinite(u) && u > 0.0 ? u : 1.0;
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_derivatives(dfo_lifecycle *lc, const char *fn, double dx[], size_t nx)
{
    chain_instance *in = ME_STATES_ARRAY(lc, fn, nx);
    if (!in) return DFO_INST_ERROR;
    chain_values *v = &in->v;
    const size_t n = v->n;
    chain_inst_me_refresh(v);
    memcpy(dx, v->s.V, n * sizeof(double));
    memcpy(dx + n, v->scratch, n * sizeof(double));
    me_done(in);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(dx[n + i]))
            return dfo_inst_fail(lc, "%s: the acceleration of block %lu at t = %.17g is not representable in double "
                                 "precision.", fn, (unsigned long)i + 1, v->s.t);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_me_indicators(dfo_lifecycle *lc, const char *fn, double z[], size_t nz)
{
    chain_instance *in = me_array(lc, fn, "ni", nz, "event indicators (2 per block)");
    if (!in) return DFO_INST_ERROR;
    chain_values *v = &in->v;
    chain_inputs ci;
    const double *vb = me_loads(v, &ci);
    const size_t n = v->n;
    double ph[2];
    phase_now(v->M, &v->s, ph);
    for (size_t i = 0; i < n; i++) {
        double zi[2];
        block_indicators(v->M, &v->s, vb, ph, i, zi);
        z[i] = zi[0];
        z[n + i] = zi[1];
    }
    me_done(in);
    return DFO_INST_OK;
}

/* The output event_indicator_0 (which = 0) or event_indicator_1 (1) of block i (chain_inst_vars.c):
 * the distances at the state under the current inputs (co-simulation too). */
double chain_inst_me_indicator(chain_values *v, int which, size_t i)
{
    const chain_inputs ci = chain_inst_inputs_of(v, 0);
    chain_loads_init(v->M, &ci);
    double z[2], ph[2];
    phase_now(v->M, &v->s, ph);
    block_indicators(v->M, &v->s, chain_inst_belt_of(v, 0), ph, i, z);
    return z[which];
}
