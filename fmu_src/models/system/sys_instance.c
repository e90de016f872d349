/* The instance core of the DryFrictionSystem FMUs (the model API of core/instance.h for the model of
 * fmu_src/models/system/modelDescription.xml), its part for memory, the values' layout, start values,
 * the model built from the values, the life cycle, configuration mode and variable access (the other
 * part: sys_instance.h). The physics is system.h's over the friction engine. No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "sys_instance.h"
#include "sys_inst_resources.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The model description's scheme values are those of the physics. */
typedef char dfo_static_assert_schemes[((int)DFO_MD_SCHEME_PAPER == (int)DFO_SCHEME_PAPER &&
                                        (int)DFO_MD_SCHEME_CONSISTENT == (int)DFO_SCHEME_CONSISTENT &&
                                        (int)DFO_MD_SCHEME_LOCATED == (int)DFO_SCHEME_LOCATED) ? 1 : -1];
#if defined(DFO_SYSTEM_FIXED_N)
typedef char dfo_static_assert_fixed_n[(DFO_SYSTEM_FIXED_N >= 1 && DFO_SYSTEM_FIXED_N <= MAX_n &&
                                        DFO_SYSTEM_FIXED_NC >= 0 && DFO_SYSTEM_FIXED_NC <= MAX_nc) ? 1 : -1];
#endif

#define WARNED_SLIP 1u    /* lc.warned: the sentence on s was logged */
#define WARNED_OBSERVE 2u /* lc.warned: the sentence on an observable not computed was logged */
#define WARNED_JACOBIAN 4u /* lc.warned: the sentence on the Jacobian not computed was logged */

/* ---- parameters, inputs, the model ------------------------------------------------------------ */

sys_params sys_params_of(const double *vals, const sys_layout *L)
{
    sys_params p;
    memset(&p, 0, sizeof p);
    p.n = L->n;
    p.nc = L->nc;
    p.M = vals + L->ap[DFO_AP_M];
    p.C = vals + L->ap[DFO_AP_C];
    p.K = vals + L->ap[DFO_AP_K];
    p.F_c = vals + L->ap[DFO_AP_F_c];
    p.F_s = vals + L->ap[DFO_AP_F_s];
    p.x0 = vals + L->ap[DFO_AP_x0];
    p.v0 = vals + L->ap[DFO_AP_v0];
    p.W = vals + L->ap[DFO_AP_W];
    p.N = vals + L->ap[DFO_AP_N];
    p.mu_s = vals + L->ap[DFO_AP_mu_s];
    p.mu_k = vals + L->ap[DFO_AP_mu_k];
    p.k_t = vals + L->ap[DFO_AP_k_t];
    p.law = vals + L->ap[DFO_AP_friction_law];
    p.v_s = vals + L->ap[DFO_AP_v_s];
    p.delta = vals + L->ap[DFO_AP_delta];
    p.omega = vals[L->sp + DFO_SP_omega];
    p.h = vals[L->sp + DFO_SP_h];
    p.alpha = vals[L->sp + DFO_SP_alpha];
    p.scheme = (int)vals[L->sp + DFO_SP_scheme];
    p.frictionUpdates = (int)vals[L->sp + DFO_SP_frictionUpdates];
    p.sensitivity = vals[L->sp + DFO_SP_sensitivity] != 0.0;
    p.f0 = vals + L->ap[DFO_AP_f0];
    p.slide0 = vals + L->ap[DFO_AP_slide0];
    return p;
}

eng_inputs sys_inputs_of(const double *vals, const sys_layout *L, int used)
{
    const size_t *off = used ? L->ai_used : L->ai;
    const double *set = vals + (used ? SYS_H_SET_USED : SYS_H_SET);
    eng_inputs e;
    memset(&e, 0, sizeof e);
    e.F_ext = set[DFO_AI_F_ext] != 0.0 ? vals + off[DFO_AI_F_ext] : NULL;
    e.N_ext = set[DFO_AI_N_ext] != 0.0 ? vals + off[DFO_AI_N_ext] : NULL;
    e.v_belt = set[DFO_AI_v_belt] != 0.0 ? vals + off[DFO_AI_v_belt] : NULL;
    return e;
}

const char *sys_build(sys_instance *in, char *buf, size_t len)
{
    sys_free_model(in);
    const eng_alloc al = sys_allocator(in);
    sys_params p = sys_params_of(in->vals, &in->L);
    p.on_rest = sys_on_rest; /* (the rest rule's choice in the event log) */
    p.rest_ctx = in;
    const char *err = NULL;
    if (!sys_model_init(&in->m, &p, &al, 1, buf, len, &err)) return err;
    if (!eng_state_init(in->m.E, &in->s, 0)) {
        sys_free_model(in);
        return "out of memory";
    }
    in->s_ready = 1;
    return NULL;
}

void sys_snap_of(const eng_state *s, double *vals, const sys_layout *L)
{
    size_t k = L->snap;
    const size_t n = L->n, nc = L->nc;
    vals[k++] = s->t0;
    vals[k++] = s->t;
    vals[k++] = (double)s->n_grid;
    vals[k++] = s->t_switch;
    vals[k++] = s->stick_tb;
    vals[k++] = (double)s->steps;
    vals[k++] = (double)s->solves;
    vals[k++] = (double)s->pivot_steps;
    vals[k++] = (double)s->switches;
    vals[k++] = s->W_applied;
    vals[k++] = s->W_friction;
    vals[k++] = s->D_damping;
    vals[k++] = (double)s->exc_n;
    vals[k++] = s->exc_c;
    vals[k++] = s->exc_s;
    const double *arr[SYS_SNAP_NA_N] = {s->X, s->V, s->A, s->hA};
    for (int a = 0; a < SYS_SNAP_NA_N; a++, k += n) memcpy(vals + k, arr[a], n * sizeof(double));
    const double *carr[3] = {s->F, s->t_stick, s->t_break};
    for (int a = 0; a < 3; a++, k += nc)
        if (nc) memcpy(vals + k, carr[a], nc * sizeof(double));
    for (size_t j = 0; j < nc; j++) vals[k + j] = (double)s->mode[j];
    k += nc;
    for (size_t j = 0; j < nc; j++) vals[k + j] = (double)s->break_dir[j];
    k += nc;
    if (nc) memcpy(vals + k, s->slider, nc * sizeof(double));
}

void sys_state_of(const double *vals, const sys_layout *L, eng_state *s)
{
    size_t k = L->snap;
    const size_t n = L->n, nc = L->nc;
    s->t0 = vals[k++];
    s->t = vals[k++];
    s->n_grid = (long long)vals[k++];
    s->t_switch = vals[k++];
    s->stick_tb = vals[k++];
    s->steps = (long long)vals[k++];
    s->solves = (long long)vals[k++];
    s->pivot_steps = (long long)vals[k++];
    s->switches = (long long)vals[k++];
    s->W_applied = vals[k++];
    s->W_friction = vals[k++];
    s->D_damping = vals[k++];
    s->exc_n = (long long)vals[k++];
    s->exc_c = vals[k++];
    s->exc_s = vals[k++];
    double *arr[SYS_SNAP_NA_N] = {s->X, s->V, s->A, s->hA};
    for (int a = 0; a < SYS_SNAP_NA_N; a++, k += n) memcpy(arr[a], vals + k, n * sizeof(double));
    double *carr[3] = {s->F, s->t_stick, s->t_break};
    for (int a = 0; a < 3; a++, k += nc)
        if (nc) memcpy(carr[a], vals + k, nc * sizeof(double));
    for (size_t j = 0; j < nc; j++) s->mode[j] = (int)vals[k + j];
    k += nc;
    for (size_t j = 0; j < nc; j++) s->break_dir[j] = (int)vals[k + j];
    k += nc;
    if (nc) memcpy(s->slider, vals + k, nc * sizeof(double));
    s->tan_lost = 1; /* (the map's Jacobian is not in the snapshot: not computed from here on) */
}

void sys_sync_inputs(double *vals, const sys_layout *L)
{
    memcpy(vals + SYS_H_SET_USED, vals + SYS_H_SET, DFO_NUM_AI * sizeof(double));
    memcpy(vals + L->ai_used[0], vals + L->ai[0], (L->ai_used[0] - L->ai[0]) * sizeof(double));
}

int sys_inputs_changed(const double *vals, const sys_layout *L)
{
    return memcmp(vals + SYS_H_SET_USED, vals + SYS_H_SET, DFO_NUM_AI * sizeof(double)) != 0 ||
           memcmp(vals + L->ai_used[0], vals + L->ai[0], (L->ai_used[0] - L->ai[0]) * sizeof(double)) != 0;
}

const char *sys_belt_refused(const double *vals, const sys_layout *L)
{
    if ((int)vals[L->sp + DFO_SP_scheme] != DFO_MD_SCHEME_PAPER || vals[SYS_H_SET + DFO_AI_v_belt] == 0.0) return NULL;
    const double *vb = vals + L->ai[DFO_AI_v_belt];
    for (size_t j = 0; j < L->nc; j++)
        if (vb[j] != 0.0)
            return "v_belt is set but the paper scheme has no moving belt (its stuck contacts creep with Bossak's "
                   "acceleration); use scheme consistent or located";
    return NULL;
}

/* ---- the observables -------------------------------------------------------------------------- */

/* The part of [a, b] inside the window [w0, w1]. */
static double in_window(double w0, double w1, double a, double b)
{
    const double lo = (a > w0) ? a : w0, hi = (b < w1) ? b : w1;
    return (hi > lo) ? hi - lo : 0.0;
}

/* The turn of the cubic through (0, x0) and (H, x1) with the slopes v0 and v1 (Hermite's), v0 and v1
 * of opposite signs or v1 = 0: the cubic's extreme inside [0, H], where its slope vanishes: a smooth
 * phase's position at its turn between the steps' ends (their error the scheme's, not the step's
 * sampling of the peak). */
static double hermite_turn(double H, double x0, double v0, double x1, double v1)
{
    /* p'(s) H = a s^2 + b s + c over s = t / H in [0, 1]: c = H v0, a + b + c = H v1, one root between */
    const double d = x1 - x0, a = 3.0 * H * (v0 + v1) - 6.0 * d, b = 6.0 * d - 2.0 * H * (2.0 * v0 + v1),
                 c = H * v0;
    double s;
    if (a == 0.0) {
        s = (b != 0.0) ? -c / b : 1.0;
    } else {
        const double q = -0.5 * (b + copysign(sqrt(fmax(b * b - 4.0 * a * c, 0.0)), b));
        const double r1 = q / a, r2 = (q != 0.0) ? c / q : r1;
        s = (r1 >= 0.0 && r1 <= 1.0) ? r1 : r2;
    }
    s = fmin(fmax(s, 0.0), 1.0); /* (NaN: 0) */
    const double s2 = s * s, s3 = s2 * s;
    return (2.0 * s3 - 3.0 * s2 + 1.0) * x0 + (s3 - 2.0 * s2 + s) * H * v0 + (3.0 * s2 - 2.0 * s3) * x1 +
           (s3 - s2) * H * v1;
}

/* One phase [ta, tb] that overlaps the window (the engine calls no other), as the oscillator keeps its
 * observables (osc_engine_ops.h): each contact's stuck stretch opened or closed at the phase's start
 * (its part inside the window added in one piece when the contact leaves rest, so that the stuck time
 * is the same however the steps are taken), and where the phase ends inside the window every x
 * sampled. */
static void observe_phase(void *ctx, const eng_phase *ph, const eng_state *es)
{
    sys_instance *in = (sys_instance *)ctx;
    const size_t n = in->L.n, nc = in->L.nc;
    double *o = in->vals + in->L.obs, *x_max = o, *x_min = o + n, *t_stuck = o + 2 * n, *from = t_stuck + nc;
    const double w0 = in->obs.t_start, w1 = in->obs.t_stop;
    (void)es;
    for (size_t j = 0; j < nc; j++) {
        if (ph->mode0[j] == 0) {
            if (isnan(from[j])) from[j] = ph->ta;
        } else if (!isnan(from[j])) {
            t_stuck[j] += in_window(w0, w1, from[j], ph->ta);
            from[j] = NAN;
        }
    }
    if (ph->tb < w0 || ph->tb > w1) return;
    double *observed = from + nc;
    if (*observed == 0.0) {
        memcpy(x_max, ph->X1, n * sizeof(double));
        memcpy(x_min, ph->X1, n * sizeof(double));
        *observed = 1.0;
        return;
    }
    const int turns = ph->V0 && ph->V1 && ph->ta >= w0;
    for (size_t i = 0; i < n; i++) {
        double x = ph->X1[i];
        x_max[i] = (x > x_max[i]) ? x : x_max[i];
        x_min[i] = (x < x_min[i]) ? x : x_min[i];
        /* a turn inside the phase (the velocity's sign changes): the extreme of its cubic */
        if (turns && ((ph->V0[i] > 0.0 && !(ph->V1[i] > 0.0)) || (ph->V0[i] < 0.0 && !(ph->V1[i] < 0.0)))) {
            x = hermite_turn(ph->tb - ph->ta, ph->X0[i], ph->V0[i], ph->X1[i], ph->V1[i]);
            x_max[i] = (x > x_max[i]) ? x : x_max[i];
            x_min[i] = (x < x_min[i]) ? x : x_min[i];
        }
    }
}

static int observing(const sys_instance *in) { return in->vals[in->L.sp + DFO_SP_observe] != 0.0; }

const eng_observer *sys_observer(sys_instance *in)
{
    if (!observing(in)) return NULL;
    in->obs.t_start = in->vals[in->L.sp + DFO_SP_t_obs_start];
    in->obs.t_stop = in->vals[in->L.sp + DFO_SP_t_obs_stop];
    in->obs.on_phase = observe_phase;
    in->obs.velocities = 1; /* (the turns inside a step: observe_phase) */
    in->obs.ctx = in;
    return &in->obs;
}

void sys_obs_start(sys_instance *in)
{
    const size_t n = in->L.n, nc = in->L.nc;
    double *o = in->vals + in->L.obs;
    memset(o, 0, SYS_OBS_SIZE(n, nc) * sizeof(double));
    for (size_t j = 0; j < nc; j++) o[2 * n + nc + j] = NAN;
    const double t0 = in->s.t, w0 = in->vals[in->L.sp + DFO_SP_t_obs_start], w1 = in->vals[in->L.sp + DFO_SP_t_obs_stop];
    if (observing(in) && t0 >= w0 && t0 <= w1) {
        memcpy(o, in->s.X, n * sizeof(double));
        memcpy(o + n, in->s.X, n * sizeof(double));
        o[2 * n + 2 * nc] = 1.0;
    }
}

/* ---- input derivatives ------------------------------------------------------------------------ */

int dfo_inst_max_input_order(void) { return 2; }

static int ramped(const double *vals, const sys_layout *L)
{
    const double *ud = vals + L->ud;
    for (size_t i = 0; i < 2 * (L->n + L->nc); i++)
        if (ud[i] != 0.0) return 1;
    return 0;
}

void sys_ramp_of(const double *vals, const sys_layout *L, double t_ref, eng_inputs *e)
{
    if (!ramped(vals, L)) return;
    const size_t n = L->n, nc = L->nc;
    for (int k = 0; k < 2; k++) {
        const double *d = vals + L->ud + (size_t)k * (n + nc);
        if (e->F_ext) e->dF_ext[k] = d;
        if (e->N_ext && nc) e->dN_ext[k] = d + n;
    }
    e->t_ref = t_ref;
}

void sys_ramp_done(double *vals, const sys_layout *L, double t_ref, double t)
{
    if (!ramped(vals, L)) return;
    const size_t n = L->n, nc = L->nc;
    const double dt = t - t_ref;
    double *d1 = vals + L->ud, *d2 = d1 + n + nc;
    const int slots[2] = {DFO_AI_F_ext, DFO_AI_N_ext};
    for (int a = 0; a < 2; a++) {
        const size_t c = a ? nc : n, off = a ? n : 0;
        if (vals[SYS_H_SET + slots[a]] == 0.0) continue;
        double *u = vals + L->ai[slots[a]];
        for (size_t i = 0; i < c; i++) u[i] += d1[off + i] * dt + d2[off + i] * dt * dt / 2.0;
    }
    memset(d1, 0, 2 * (n + nc) * sizeof(double));
    sys_sync_inputs(vals, L); /* (the values at t: the inputs used from here on) */
}

/* ---- the rest rule's log ------------------------------------------------------------------------ */

/* The 1-based numbers of the contacts j with rest[j] and (modes NULL, or (modes[j] == 0) == held) into
 * buf: "1, 3, 4" ("none"; cut with "..." when long). */
static void contact_list(size_t nc, const int *rest, const int *modes, int held, char *buf, size_t len)
{
    size_t k = 0;
    buf[0] = '\0';
    for (size_t j = 0; j < nc; j++) {
        if (!rest[j] || (modes && (modes[j] == 0) != held)) continue;
        if (k + 24 >= len) {
            snprintf(buf + k, len - k, ", ...");
            return;
        }
        k += (size_t)snprintf(buf + k, len - k, "%s%lu", k ? ", " : "", (unsigned long)j + 1);
    }
    if (!k) snprintf(buf, len, "none");
}

void sys_on_rest(void *ctx, double t, int stage, size_t contact, int mode, double excess, const int *rest,
                 const int *modes)
{
    sys_instance *in = (sys_instance *)ctx;
    const dfo_lifecycle *lc = &in->lc;
    if (!lc->host.log || !lc->log_on[DFO_LOG_EVENTS]) return;
    const size_t nc = in->L.nc;
    char a[200], b[200];
    switch (stage) {
    case ENG_REST_OPEN:
        contact_list(nc, rest, NULL, 0, a, sizeof a);
        dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS,
                     "t = %.17g: the rest rule decides the rigid contacts at rest together (contacts %s); where "
                     "more than one mode set is consistent, the causal cascade from \"all at rest held\" picks one: "
                     "their holding forces solved together, the contact most beyond its limit released first, the "
                     "forces solved again, until every held one is within its limit.", t, a);
        break;
    case ENG_REST_RELEASE:
        dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS,
                     "t = %.17g: rest rule: contact %lu released (its holding force beyond its limit by %.17g, the "
                     "most of the held ones), to slide %s (mode %+d); the others solved again.", t,
                     (unsigned long)contact + 1, excess, mode > 0 ? "forward" : "backward", mode);
        break;
    default:
        contact_list(nc, rest, modes, 1, a, sizeof a);
        contact_list(nc, rest, modes, 0, b, sizeof b);
        dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS,
                     "t = %.17g: rest rule settled: contacts held %s; released %s.", t, a, b);
        break;
    }
}

/* ---- life cycle ------------------------------------------------------------------------------- */

static void set_start_values(sys_instance *in)
{
    const dfo_run run0 = {0};
    sys_value_starts(in->vals, &in->L);
    in->n_config = in->L.n;
    in->nc_config = in->L.nc;
    in->lc.run = run0;
    in->lc.run.phase = DFO_PHASE_INSTANTIATED;
}

dfo_lifecycle *dfo_inst_new(const dfo_host *host, const char *name, int logging_on)
{
    sys_instance *in = (sys_instance *)dfo_lifecycle_new(host, sizeof(sys_instance), name, logging_on);
    if (!in) return NULL;
    if (sys_resize(in, "instantiate", SYS_N_START, SYS_NC_START) != DFO_INST_OK) {
        host->free(host->ctx, in);
        return NULL;
    }
    set_start_values(in);
    in->lc.resources = sys_inst_resources; /* a structure's FMU: its start values from resources/ */
    return &in->lc;
}

void dfo_inst_delete(dfo_lifecycle *lc)
{
    if (!lc) return;
    sys_instance *in = sysi(lc);
    sys_free_model(in);
    sys_free_values(in);
    lc->host.free(lc->host.ctx, lc);
}

dfo_inst_status dfo_inst_exit_init(dfo_lifecycle *lc, const char *fn)
{
    sys_instance *in = sysi(lc);
    char buf[320];
    const char *why = sys_belt_refused(in->vals, &in->L);
    const double w0 = in->vals[in->L.sp + DFO_SP_t_obs_start], w1 = in->vals[in->L.sp + DFO_SP_t_obs_stop];
    if (!why && !(w1 >= w0)) {
        snprintf(buf, sizeof buf, "invalid observation window: t_obs_stop = %.17g is below t_obs_start = %.17g; "
                 "valid range: t_obs_stop >= t_obs_start", w1, w0);
        why = buf;
    }
    if (!why) why = sys_build(in, buf, sizeof buf);
    if (why) return dfo_inst_fail(lc, "%s: %s.", fn, why);
    double *vals = in->vals;
    const sys_layout *L = &in->L;
    sys_sync_inputs(vals, L);
    const eng_inputs e = sys_inputs_of(vals, L, 1);
    const sys_params p = sys_params_of(vals, L);
    eng_start(in->m.E, &e, in->lc.run.start_time, p.x0, p.v0, &in->s);
    int preloaded = 0; /* a Jenkins spring with an initial force or slide: its slider where they put it */
    for (size_t j = 0; j < L->nc; j++) preloaded |= p.k_t[j] > 0.0 && (p.f0[j] != 0.0 || p.slide0[j] != 0.0);
    if (preloaded) {
        double *s0 = in->scratch + L->n;
        int *slide = (int *)(void *)(in->scratch + L->n + L->nc); /* (nc doubles' room) */
        for (size_t j = 0; j < L->nc; j++) slide[j] = (int)p.slide0[j];
        for (size_t j = 0; j < L->nc; j++) {
            double g = 0.0;
            for (size_t i = 0; i < L->n; i++) g += p.W[j * L->n + i] * p.x0[i];
            s0[j] = (p.k_t[j] > 0.0) ? g + p.f0[j] / p.k_t[j] : 0.0;
        }
        if (!eng_set_sliders(in->m.E, &e, &in->s, s0, slide))
            return dfo_inst_fail(lc, "%s: f0 is beyond a Jenkins contact's breakaway limit max(mu_s, mu_k) (N + N_ext) "
                                 "with the inputs at the start (valid: |f0[j]| within it, its slider stuck).", fn);
    }
    sys_obs_start(in);
    vals[SYS_H_STARTED] = 1.0;
    in->lc.run.time = in->lc.run.start_time;
    in->lc.run.phase = DFO_PHASE_STEP;
    char how[96] = "by dense Cholesky"; /* (system.h's backends) */
    if (in->m.modal || !isnan(in->m.c_offdiag))
        snprintf(how, sizeof how, "%s (C's off-diagonal share in the modal basis %.3g)",
                 in->m.modal ? "modal" : "by dense Cholesky", in->m.c_offdiag);
    dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS, "start at t = %.17g: n = %lu, nc = %lu, h = %.17g, solves %s.",
                 in->s.t, (unsigned long)L->n, (unsigned long)L->nc, in->m.h, how);
    return DFO_INST_OK;
}

void dfo_inst_reset(dfo_lifecycle *lc)
{
    sys_instance *in = sysi(lc);
    sys_free_model(in);
    (void)sys_resize(in, "reset", SYS_N_START, SYS_NC_START); /* on failure the values keep their size */
    set_start_values(in);
    in->lc.warned = 0;
}

void dfo_inst_log_event_handled(const dfo_lifecycle *lc)
{
    dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: event handled.", dfo_inst_time(lc));
}

int dfo_inst_has_structural(void) { return 1; }

dfo_inst_status dfo_inst_enter_config(dfo_lifecycle *lc, const char *fn)
{
    sys_instance *in = sysi(lc);
    (void)fn;
    in->n_config = in->L.n;
    in->nc_config = in->L.nc;
    in->lc.run.phase = DFO_PHASE_CONFIG;
    return DFO_INST_OK;
}

/* Leaving configuration mode with new sizes: every value at its start. */
dfo_inst_status dfo_inst_exit_config(dfo_lifecycle *lc, const char *fn)
{
    sys_instance *in = sysi(lc);
    if (sys_resize(in, fn, in->n_config, in->nc_config) != DFO_INST_OK) return DFO_INST_ERROR;
    in->n_config = in->L.n;
    in->nc_config = in->L.nc;
    in->lc.run.phase = DFO_PHASE_INSTANTIATED;
    return DFO_INST_OK;
}

/* ---- the variable table ----------------------------------------------------------------------- */

/* A value reference resolved: the variable and, for an FMI 2.0 element, its index (0-based). */
typedef struct {
    const dfo_var_info *var;
    long elem; /* -1: the whole variable (a scalar, or every element of an array) */
} sys_ref;

/* FMI 2.0: the flattened elements' value references follow the layout of the structure file when it
 * gives one (any n, nc: resources/structure.bin), the build's otherwise (DFO_FMI2_ARRAYS, its own
 * sizes); array a's elements are first .. first + count - 1 for the instance's sizes. */
static int resolve(const sys_instance *in, unsigned int vr, sys_ref *r)
{
    const dfo_var_info *var = dfo_find_var(vr);
    r->var = NULL;
    r->elem = -1;
#if defined(DFO_SYSTEM_FIXED_N)
    if (var && !var->array) {
        r->var = var;
        r->elem = -1;
        return 1;
    }
    for (size_t a = 0; a < DFO_FMI2_NUM_ARRAYS; a++) {
        const unsigned int first = sys_res_fmi2_first(&in->lc, a);
        const dfo_var_info *A = dfo_find_var(DFO_FMI2_ARRAYS[a].vr);
        if (vr < first || vr - first >= sys_var_count(A, in->L.n, in->L.nc)) continue;
        r->var = A;
        r->elem = (long)(vr - first);
        return 1;
    }
    return 0;
#else
    (void)in;
    if (!var) return 0;
    r->var = var;
    r->elem = -1;
    return 1;
#endif
}

/* The name of element i of var (0-based, row-major): M[2,3], N[1], or the variable's for a scalar. */
static void element_name(const sys_instance *in, const dfo_var_info *var, size_t i, char *buf, size_t len)
{
    if (!var->array) snprintf(buf, len, "%s", var->name);
    else if (var->ndims == 2) {
        const size_t cols = var->dims[1] == DFO_STRUCT_n ? in->L.n : in->L.nc;
        snprintf(buf, len, "%s[%lu,%lu]", var->name, (unsigned long)(i / cols + 1), (unsigned long)(i % cols + 1));
    } else snprintf(buf, len, "%s[%lu]", var->name, (unsigned long)i + 1);
}

static size_t count(const sys_instance *in, const sys_ref *r)
{
    return (r->var->array && r->elem < 0) ? sys_var_count(r->var, in->L.n, in->L.nc) : 1;
}

size_t dfo_inst_n_values(const dfo_lifecycle *lc, const unsigned int vr[], size_t nvr)
{
    const sys_instance *in = csysi(lc);
    size_t total = 0;
    for (size_t i = 0; i < nvr; i++) {
        sys_ref r;
        total += resolve(in, vr[i], &r) ? count(in, &r) : 1;
    }
    return total;
}

static int lookup(const sys_instance *in, const char *fn, unsigned int vr, dfo_var_type type, sys_ref *r)
{
    if (!resolve(in, vr, r)) {
#if defined(DFO_SYSTEM_FIXED_N)
        /* the array whose elements would come just before vr: the nearest valid range */
        long best = -1;
        for (size_t a = 0; a < DFO_FMI2_NUM_ARRAYS; a++) {
            const unsigned int first = sys_res_fmi2_first(&in->lc, a);
            if (first <= vr && (best < 0 || first > sys_res_fmi2_first(&in->lc, (size_t)best))) best = (long)a;
        }
        if (best >= 0) {
            const dfo_var_info *A = dfo_find_var(DFO_FMI2_ARRAYS[best].vr);
            const unsigned int first = sys_res_fmi2_first(&in->lc, (size_t)best);
            const size_t c = sys_var_count(A, in->L.n, in->L.nc);
            char lo[48], hi[48];
            element_name(in, A, 0, lo, sizeof lo);
            element_name(in, A, c ? c - 1 : 0, hi, sizeof hi);
            if (c)
                dfo_inst_fail(&in->lc, "%s: value reference %u is no variable of this FMU: beyond the elements of %s, "
                              "%s to %s at value references %u to %lu (n = %lu, nc = %lu).", fn, vr, A->name, lo, hi,
                              first, (unsigned long)(first + c - 1), (unsigned long)in->L.n, (unsigned long)in->L.nc);
            else
                dfo_inst_fail(&in->lc, "%s: value reference %u is no variable of this FMU: %s has no elements with "
                              "n = %lu, nc = %lu.", fn, vr, A->name, (unsigned long)in->L.n, (unsigned long)in->L.nc);
            return 0;
        }
        char lo[48];
        const dfo_var_info *A0 = dfo_find_var(DFO_FMI2_ARRAYS[0].vr);
        element_name(in, A0, 0, lo, sizeof lo);
        dfo_inst_fail(&in->lc, "%s: value reference %u is no variable of this FMU: no scalar has it and the array "
                      "elements begin at %u (%s).", fn, vr, sys_res_fmi2_first(&in->lc, 0), lo);
        return 0;
#else
        dfo_inst_fail(&in->lc, "%s: unknown value reference %u.", fn, vr);
        return 0;
#endif
    }
    if (r->var->type != type) {
        dfo_inst_fail(&in->lc, "%s: variable %s (value reference %u) is of type %s, not %s.", fn, r->var->name, vr,
                      dfo_type_name(r->var->type), dfo_type_name(type));
        return 0;
    }
    return 1;
}

/* Where element i of a stored variable lives. */
static double *stored(sys_instance *in, const dfo_var_info *var, size_t i)
{
    switch (var->home) {
    case DFO_IN_PARAMS: return &in->vals[in->L.sp + (size_t)var->slot];
    case DFO_IN_ARRAYS: return &in->vals[in->L.ap[var->slot] + i];
    case DFO_IN_INPUTS: return &in->vals[in->L.ai[var->slot] + i];
    default: return NULL;
    }
}

static int started(const sys_instance *in) { return in->vals[SYS_H_STARTED] != 0.0 && in->s_ready; }

/* ---- outputs ---------------------------------------------------------------------------------- */

static void note_slip(sys_instance *in, const char *fn)
{
    if (in->lc.warned & WARNED_SLIP) return;
    in->lc.warned |= WARNED_SLIP;
    dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                 "%s: variable s (value reference %u) is not computed for a rigid contact (k_t = 0: no slider), so "
                 "its entry reads NaN; logged once per run.", fn, VR_s);
}

/* An observable not computed (observe false, or x_max, x_min before the window's first sample): NaN,
 * with one sentence per run under logNotComputed. */
static void note_observable(sys_instance *in, const char *fn, const dfo_var_info *var)
{
    if (in->lc.warned & WARNED_OBSERVE) return;
    in->lc.warned |= WARNED_OBSERVE;
    if (!observing(in))
        dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                     "%s: variable %s (value reference %u) is not computed while observe is false: the observables "
                     "x_max, x_min, stick_fraction read NaN and transitions -1 in this run; set observe = true "
                     "(before initialisation) to compute them; logged once per run.", fn, var->name, var->vr);
    else
        dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                     "%s: variable %s (value reference %u) reads NaN: the observation window [%.17g, %.17g] has not "
                     "taken a sample yet (t = %.17g); logged once per run.", fn, var->name, var->vr,
                     in->vals[in->L.sp + DFO_SP_t_obs_start], in->vals[in->L.sp + DFO_SP_t_obs_stop], in->s.t);
}

/* The located map's Jacobian block var (dx_dx0 ... ds_ds0), elements i0 ... i0 + c - 1, from the
 * engine state's tangent (eng_state.tan: column k the derivatives with respect to start value k of
 * x0, v0, s0; rows x, v at 0, n, the sliders at 4 n); NaN with one sentence per run where it is not
 * computed (sensitivity false) or was lost. */
static void get_jacobian(sys_instance *in, const char *fn, const dfo_var_info *var, size_t i0, size_t c, double *dout)
{
    const size_t n = in->L.n, nc = in->L.nc, L = 4 * n + nc + 1;
    const eng_state *s = &in->s;
    if (!s->tan || s->tan_lost) {
        for (size_t i = 0; i < c; i++) dout[i] = NAN;
        if (in->lc.warned & WARNED_JACOBIAN) return;
        in->lc.warned |= WARNED_JACOBIAN;
        if (!s->tan)
            dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                         "%s: variable %s (value reference %u) is not computed while sensitivity is false: the map's "
                         "Jacobian dx_dx0 ... ds_ds0 reads NaN in this run; set sensitivity = true (before "
                         "initialisation) to compute it; logged once per run.", fn, var->name, var->vr);
        else
            dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                         "%s: variable %s (value reference %u) is not computed from t = %.17g on: the map's Jacobian "
                         "was lost (the inputs changed, an FMU state was restored, a step too long for the located "
                         "scheme, or a switch whose margin's rate is 0: a grazing); it reads NaN; logged once per "
                         "run.", fn, var->name, var->vr, s->t);
        return;
    }
    const int id = var->slot;
    const int row_v = id == DFO_OUT_dv_dx0 || id == DFO_OUT_dv_dv0 || id == DFO_OUT_dv_ds0;
    const int row_s = id == DFO_OUT_ds_dx0 || id == DFO_OUT_ds_dv0 || id == DFO_OUT_ds_ds0;
    const int col_v = id == DFO_OUT_dx_dv0 || id == DFO_OUT_dv_dv0 || id == DFO_OUT_ds_dv0;
    const int col_s = id == DFO_OUT_dx_ds0 || id == DFO_OUT_dv_ds0 || id == DFO_OUT_ds_ds0;
    const size_t row0 = row_s ? 4 * n : row_v ? n : 0, col0 = col_s ? 2 * n : col_v ? n : 0;
    const size_t cols = col_s ? nc : n;
    for (size_t i = 0; i < c; i++) {
        const size_t e = i0 + i, r = e / cols, q = e % cols;
        dout[i] = s->tan[(col0 + q) * L + row0 + r];
    }
}

/* The observables x_max, x_min (elements i0 ... i0 + c - 1) or stick_fraction, of a started run. */
static void get_observables(sys_instance *in, const char *fn, const dfo_var_info *var, size_t i0, size_t c,
                            double *dout)
{
    const size_t n = in->L.n, nc = in->L.nc;
    const double *o = in->vals + in->L.obs, *t_stuck = o + 2 * n, *from = t_stuck + nc;
    const int id = var->slot;
    if (!observing(in) || (id != DFO_OUT_stick_fraction && o[2 * n + 2 * nc] == 0.0)) {
        for (size_t i = 0; i < c; i++) dout[i] = NAN;
        note_observable(in, fn, var);
        return;
    }
    if (id != DFO_OUT_stick_fraction) {
        memcpy(dout, o + (id == DFO_OUT_x_max ? 0 : n) + i0, c * sizeof(double));
        return;
    }
    /* the stuck time over the part of the window already run (0 before the window opens) */
    const double w0 = in->vals[in->L.sp + DFO_SP_t_obs_start], w1 = in->vals[in->L.sp + DFO_SP_t_obs_stop];
    const double t = in->s.t, span = ((t < w1) ? t : w1) - w0;
    for (size_t i = 0; i < c; i++) {
        const size_t j = i0 + i;
        const double stuck = t_stuck[j] + (isnan(from[j]) ? 0.0 : in_window(w0, w1, from[j], t));
        dout[i] = span > 0.0 ? stuck / span : 0.0;
    }
}

static double h_used(sys_instance *in)
{
    if (in->m.E) return in->m.h;
    const eng_alloc al = sys_allocator(in);
    const sys_params p = sys_params_of(in->vals, &in->L);
    char buf[320];
    if (sys_check(&p, &al, buf, sizeof buf)) return NAN;
    return sys_step(&p, &al);
}

/* Real (dout) or integer (iout) outputs of r: count(r) values. */
static void get_outputs(sys_instance *in, const char *fn, const sys_ref *r, double *dout, int *iout)
{
    const size_t c = count(in, r), i0 = r->elem < 0 ? 0 : (size_t)r->elem;
    const int id = r->var->slot;
    if (id == DFO_OUT_h_used) {
        dout[0] = h_used(in);
        return;
    }
    if (id == DFO_OUT_s) {
        const double *kt = in->vals + in->L.ap[DFO_AP_k_t];
        int rigid = 0;
        for (size_t i = 0; i < c; i++) {
            const int jenk = kt[i0 + i] > 0.0;
            rigid |= !jenk;
            dout[i] = (started(in) && jenk) ? in->s.slider[i0 + i] : NAN;
        }
        if (rigid) note_slip(in, fn);
        return;
    }
    if (!started(in)) {
        for (size_t i = 0; i < c; i++) {
            if (iout) iout[i] = 0;
            else dout[i] = NAN;
        }
        return;
    }
    const eng_state *s = &in->s;
    const eng_inputs e = sys_inputs_of(in->vals, &in->L, 0);
    const double *src = NULL;
    switch (id) {
    case DFO_OUT_E_friction: dout[0] = 0.0 - s->W_friction; return;
    case DFO_OUT_x: src = s->X; break;
    case DFO_OUT_v: src = s->V; break;
    case DFO_OUT_a: eng_accelerations(in->m.E, &e, s, in->scratch); src = in->scratch; break;
    case DFO_OUT_f:
        /* the paper scheme's stuck contact creeps with the force its step's friction problem found (the
         * oscillator's and the chain's F_friction): that force while the inputs are those of the step;
         * otherwise the force at the state as the schemes whose stuck contacts rest report it */
        if ((int)in->vals[in->L.sp + DFO_SP_scheme] == DFO_MD_SCHEME_PAPER && !sys_inputs_changed(in->vals, &in->L))
            src = s->F;
        else {
            eng_contact_forces(in->m.E, &e, s, in->scratch);
            src = in->scratch;
        }
        break;
    case DFO_OUT_mode:
        for (size_t i = 0; i < c; i++) iout[i] = s->mode[i0 + i];
        return;
    case DFO_OUT_transitions: {
        const double *tr = in->vals + in->L.obs + SYS_OBS_TRANSITIONS(in->L.n, in->L.nc);
        if (!observing(in)) note_observable(in, fn, r->var);
        for (size_t i = 0; i < c; i++) iout[i] = observing(in) ? (int)tr[i0 + i] : -1; /* (not computed: -1, as the oscillator's) */
        return;
    }
    case DFO_OUT_x_max:
    case DFO_OUT_x_min:
    case DFO_OUT_stick_fraction: get_observables(in, fn, r->var, i0, c, dout); return;
    case DFO_OUT_dx_dx0:
    case DFO_OUT_dx_dv0:
    case DFO_OUT_dv_dx0:
    case DFO_OUT_dv_dv0:
    case DFO_OUT_dx_ds0:
    case DFO_OUT_dv_ds0:
    case DFO_OUT_ds_dx0:
    case DFO_OUT_ds_dv0:
    case DFO_OUT_ds_ds0: get_jacobian(in, fn, r->var, i0, c, dout); return;
    default: break;
    }
    for (size_t i = 0; i < c; i++) dout[i] = src ? src[i0 + i] : NAN;
}

/* ---- get / set -------------------------------------------------------------------------------- */

static dfo_inst_status get_values(sys_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  dfo_var_type type, double *dout, int *iout)
{
    size_t k = 0;
    for (size_t j = 0; j < n; j++) {
        sys_ref r;
        if (!lookup(in, fn, vr[j], type, &r)) return DFO_INST_ERROR;
        const size_t c = count(in, &r);
        if (r.var->home == DFO_COMPUTED) {
            get_outputs(in, fn, &r, dout ? dout + k : NULL, iout ? iout + k : NULL);
        } else {
            const size_t i0 = r.elem < 0 ? 0 : (size_t)r.elem;
            for (size_t i = 0; i < c; i++) {
                const double x = *stored(in, r.var, i0 + i);
                if (dout) dout[k + i] = x;
                else iout[k + i] = (int)x;
            }
        }
        k += c;
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, double value[])
{
    return get_values(sysi(lc), fn, vr, n, DFO_REAL, value, NULL);
}

dfo_inst_status dfo_inst_get_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    return get_values(sysi(lc), fn, vr, n, DFO_INTEGER, NULL, value);
}

dfo_inst_status dfo_inst_get_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    return get_values(sysi(lc), fn, vr, n, DFO_BOOLEAN, NULL, value); /* (observe: a scalar parameter) */
}

/* Check every value of every variable (type, causality and phase, range per element), then store:
 * a rejected call changes nothing. */
static dfo_inst_status set_values(sys_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[], dfo_var_type type)
{
    size_t k = 0;
    char name[64];
    for (size_t j = 0; j < n; j++) {
        sys_ref r;
        if (!lookup(in, fn, vr[j], type, &r)) return DFO_INST_ERROR;
        if (r.elem < 0) snprintf(name, sizeof name, "%s", r.var->name);
        else element_name(in, r.var, (size_t)r.elem, name, sizeof name); /* an FMI 2.0 element */
        if (!dfo_inst_settable(&in->lc, fn, r.var, name, vr[j])) return DFO_INST_ERROR;
        const size_t c = count(in, &r), i0 = r.elem < 0 ? 0 : (size_t)r.elem;
        for (size_t i = 0; i < c; i++) {
            const double x = value[k + i];
            const char *range = dfo_inst_invalid(r.var, x);
            if (!range) continue;
            element_name(in, r.var, i0 + i, name, sizeof name);
            if (isnan(x))
                return dfo_inst_fail(&in->lc, "%s: %s (value reference %u) is not a finite number; valid range: %s.",
                                     fn, name, vr[j], range);
            return dfo_inst_fail(&in->lc, "%s: invalid value %.17g for %s (value reference %u); valid range: %s.", fn,
                                 x, name, vr[j], range);
        }
        k += c;
    }
    k = 0;
    for (size_t j = 0; j < n; j++) {
        sys_ref r;
        (void)resolve(in, vr[j], &r);
        const size_t c = count(in, &r), i0 = r.elem < 0 ? 0 : (size_t)r.elem;
        for (size_t i = 0; i < c; i++) *stored(in, r.var, i0 + i) = value[k + i];
        if (r.var->home == DFO_IN_INPUTS) in->vals[SYS_H_SET + (size_t)r.var->slot] = 1.0;
        k += c;
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[])
{
    return set_values(sysi(lc), fn, vr, n, value, DFO_REAL);
}

/* Integer values (the scheme, frictionUpdates: scalars) through doubles, in chunks. */
#define BATCH 64

dfo_inst_status dfo_inst_set_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                 const int value[])
{
    /* (friction_law is an array of nc values: more than a batch goes through the host's memory) */
    const size_t total = dfo_inst_n_values(lc, vr, n);
    double batch[BATCH] = {0.0}, *x = batch;
    if (total > BATCH && !(x = (double *)lc->host.alloc(lc->host.ctx, total, sizeof(double))))
        return dfo_inst_fail(lc, "%s: out of memory for %lu values.", fn, (unsigned long)total);
    for (size_t i = 0; i < total; i++) x[i] = (double)value[i];
    const dfo_inst_status st = set_values(sysi(lc), fn, vr, n, x, DFO_INTEGER);
    if (x != batch) lc->host.free(lc->host.ctx, x);
    return st;
}

dfo_inst_status dfo_inst_set_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const int value[])
{
    double x[BATCH];
    if (n > BATCH) return dfo_inst_fail(lc, "%s: at most %d values per call.", fn, BATCH);
    for (size_t i = 0; i < n; i++) x[i] = value[i] ? 1.0 : 0.0;
    return set_values(sysi(lc), fn, vr, n, x, DFO_BOOLEAN);
}

dfo_inst_status dfo_inst_get_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    unsigned long long value[])
{
    sys_instance *in = sysi(lc);
    const int config = in->lc.run.phase == DFO_PHASE_CONFIG;
    for (size_t j = 0; j < n; j++) {
        sys_ref r;
        if (!lookup(in, fn, vr[j], DFO_UINT64, &r)) return DFO_INST_ERROR;
        const int is_n = r.var->slot == DFO_STRUCT_n;
        value[j] = (unsigned long long)(is_n ? (config ? in->n_config : in->L.n) : (config ? in->nc_config : in->L.nc));
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    const unsigned long long value[])
{
    sys_instance *in = sysi(lc);
    for (size_t j = 0; j < n; j++) {
        sys_ref r;
        if (!lookup(in, fn, vr[j], DFO_UINT64, &r) || !dfo_inst_settable(&in->lc, fn, r.var, r.var->name, vr[j]))
            return DFO_INST_ERROR;
        if (value[j] < (unsigned long long)r.var->min || value[j] > (unsigned long long)r.var->max)
            return dfo_inst_fail(&in->lc, "%s: invalid value %llu for %s (value reference %u); valid range: %s.", fn,
                                 value[j], r.var->name, vr[j], r.var->range);
    }
    for (size_t j = 0; j < n; j++) {
        sys_ref r;
        (void)resolve(in, vr[j], &r);
        if (r.var->slot == DFO_STRUCT_n) in->n_config = (size_t)value[j];
        else in->nc_config = (size_t)value[j];
    }
    return DFO_INST_OK;
}

/* ---- input derivatives (FMI 2.0's fmi2SetRealInputDerivatives: one value per element) ---------- */

dfo_inst_status dfo_inst_set_input_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t nvr,
                                               const int order[], const double value[])
{
    sys_instance *in = sysi(lc);
    const size_t n = in->L.n;
    for (size_t j = 0; j < nvr; j++) {
        sys_ref r;
        if (!resolve(in, vr[j], &r)) return dfo_inst_fail(lc, "%s: unknown value reference %u.", fn, vr[j]);
        const dfo_var_info *var = r.var;
        if (var->home != DFO_IN_INPUTS || var->slot == DFO_AI_v_belt)
            return dfo_inst_fail(lc, "%s: %s (value reference %u) takes no derivatives: only the inputs F_ext and "
                                 "N_ext do (v_belt is held over a communication step).", fn, var->name, vr[j]);
        if (order[j] < 1 || order[j] > 2)
            return dfo_inst_fail(lc, "%s: invalid order %d of the derivative of %s (value reference %u); valid range: "
                                 "1 to 2.", fn, order[j], var->name, vr[j]);
        if (!isfinite(value[j]))
            return dfo_inst_fail(lc, "%s: invalid value %.17g of the order-%d derivative of %s (value reference %u); "
                                 "valid range: finite.", fn, value[j], order[j], var->name, vr[j]);
    }
    for (size_t j = 0; j < nvr; j++) {
        sys_ref r;
        (void)resolve(in, vr[j], &r);
        const size_t c = count(in, &r), i0 = r.elem < 0 ? 0 : (size_t)r.elem;
        double *d = in->vals + in->L.ud + (size_t)(order[j] - 1) * (n + in->L.nc) + (r.var->slot == DFO_AI_F_ext ? 0 : n);
        for (size_t i = 0; i < c; i++) d[i0 + i] = value[j];
        in->vals[SYS_H_SET + (size_t)r.var->slot] = 1.0; /* the input's polynomial starts from its value */
    }
    return DFO_INST_OK;
}
