/* The chain's stepping: chain_start and chain_advance (the grid, the snap of the requested time,
 * the excitation cache), the fast path of whole grid steps of the located scheme (step_fast and
 * fast_run, inlined into the loop: the same bits as the located step, in fused sweeps with the
 * kept factorisation), and the stuck fast path. See chain.h and chain_internal.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_internal.h"

/* cos and sin of omega t + phi0 at the grid point g of the state (excitation.h's dfo_grid_phase,
 * as the oscillator's), kept in the state's cache */
static void grid_phase(const chain_model *M, chain_state *s, long long g, double *cw, double *sw)
{
    double c, sn;
    dfo_grid_phase(M->omega, M->phi0, s->t0, M->h, M->rot_c, M->rot_s, s->exc_n, s->exc_c, s->exc_s, g, &c, &sn);
    s->exc_n = g;
    s->exc_c = c;
    s->exc_s = sn;
    *cw = dfo_clamp1(c);
    *sw = dfo_clamp1(sn);
}

/* What a grid step of the fast path reads, constant over one chain_advance call: taken out of the
 * model once per call, so that the stepping loop keeps it in registers or on its own stack. */
typedef struct {
    size_t n;
    double h, alpha, rate_max, c1, pV, pA, cV, g1;
    fast_row *rows;
    double *xp, *q, *dp, *Vt, *Ft, *l;
    int *st;
} fast_ctx;

static void fast_ctx_init(const chain_model *M, fast_ctx *F)
{
    F->n = M->n;
    F->h = M->h;
    F->alpha = M->alpha;
    F->rate_max = M->rate_max;
    F->c1 = M->kinF.c1;
    F->pV = M->kinF.pred_V;
    F->pA = M->kinF.pred_A;
    F->cV = M->kinF.corr_V;
    F->g1 = M->g1;
    F->rows = M->rows;
    F->xp = M->xp; F->q = M->q; F->dp = M->dp; F->Vt = M->Vt; F->Ft = M->Ft;
    F->l = M->l; F->st = M->st;
}

/* The located step of a whole grid step in the current modes, in fused sweeps: the same arithmetic,
 * in the same order, as trial + solve_modes + finish (so the same bits), without their separate
 * passes, and with the factorisation of M_hat for the step's held rows kept from the last step
 * (rows: a row is refactored, by lcp_box_basis' operations, when its own hold changed or
 * when it is free and the row above was refactored; a held row starts the elimination afresh).
 * Returns 1 when the warm basis solves the LCP: the step is taken (not the time). Returns 0, with
 * nothing done, when A must be re-based (then rebase_whole makes A0 and step_fast goes on with
 * rebased set: trial's A0p). Returns -1 when a block must switch: the state is
 * untouched and the model holds the trial and its solve in the current modes as trial +
 * solve_modes leave them (xp, q, st, l, Vt, Ft, kin, cd, ce, A0p, cw1, sw1), for chain_step_located to
 * go on from. Only for the located scheme on a resolving grid, without energy accounts and with
 * no block frozen. */
static HOT_INLINE int step_fast(chain_model *M, const fast_ctx *C, chain_state *s, double cw1, double sw1,
                                const double *A0, int rebased)
{
    const size_t n = C->n;
    const double hh = C->h, a = rebased ? 0.0 : C->alpha;  /* (a = 0: no test for a re-basing) */
    const double c1 = C->c1, pV = C->pV, pA = C->pA, cV = C->cV, g1 = C->g1;
    /* A0: the state's A, or (rebased) A re-based on h by rebase_whole; A is not restrict, A0 may be it */
    double *restrict X = s->X, *restrict V = s->V, *A = s->A, *restrict hA = s->hA, *restrict F = s->F;
    fast_row *restrict R = C->rows;
    double *restrict xp = C->xp, *restrict q = C->q, *restrict dp = C->dp, *restrict Vt = C->Vt;
    double *restrict Ft = C->Ft, *restrict l = C->l;
    int *restrict st = C->st, *restrict mode = s->mode;
    /* forward: xp one block ahead, p_hat, the modes' rows, elimination with the kept factors */
    double cprev = 0.0, dprev = 0.0, xl = 0.0, xc = X[0] + pV * V[0] + pA * A0[0];
    int refac = 0;
    for (size_t i = 0; i < n; i++) {
        if (hh != hA[i]) {  /* (rare: after a switch) trial's test whether A is re-based */
            if (a != 0.0 && fabs(hh - hA[i]) > 1e-12 * hh + 4.0 * DBL_EPSILON * fabs(s->t) &&
                C->rate_max * (hA[i] > hh ? hA[i] : hh) <= 1.0) {  /* fmax(hh, hA), hh > 0 */
                if (refac) R[i].fh = 0;  /* row i's kept factor no longer follows the row above */
                return 0;
            }
        }
        const double xr = (i + 1 < n) ? X[i + 1] + pV * V[i + 1] + pA * A0[i + 1] : 0.0;
        xp[i] = xc;
        double kx = R[i].Kd * xc;
        if (i > 0) kx += R[i - 1].Ko * xl;
        if (i + 1 < n) kx += R[i].Ko * xr;
        const double p =
            R[i].Pc * cw1 - R[i].Ps * sw1 + R[i].u - R[i].am * A0[i] + R[i].am1 * (V[i] * c1 + g1 * A0[i]) - kx;
        q[i] = -p;
        xl = xc;
        xc = xr;
        const int hold = (mode[i] == 0 && R[i].Fb > 0.0);
        refac = chain_refactor_row(R, i, hold, cprev, refac);
        /* lcp_box_basis' (rhs - lo_e dprev) / den, rhs = -q - the sliding force; on the first row
         * lo_e dprev is +0, and x - +0 is x */
        double dpi = 0.0;
        if (!hold) {
            const double li = (mode[i] == 0) ? R[i].Fb : R[i].mukN;
            double r = p - ((li > 0.0) ? mode[i] * li : 0.0);
            if (i > 0) r -= R[i - 1].e * dprev;
            dpi = r * R[i].inv;
        }
        dp[i] = dpi;
        cprev = R[i].cp;
        dprev = dpi;
    }
    /* back substitution, with the test of every block: a sliding one keeps its direction (its
     * switch_margin is positive), a held one's force (F = (M_hat V)_i - p_i, taken when the row
     * below is known) stays within its limit. A held row's V is +0 (dp = cp = 0), and the last
     * row's V is its dp (cp there is +0, and x - +0 is x). */
    int ok = 1;
    const double v_last = dprev;
    double vn = v_last, v1 = 0.0, v2 = 0.0;  /* V of rows j, j + 1, j + 2 */
    for (size_t j = n; j-- > 0;) {
        if (j + 1 < n) vn = (mode[j] == 0 && R[j].Fb > 0.0) ? 0.0 : dp[j] - R[j].cp * vn;
        Vt[j] = vn;
        const size_t i = j + 1;  /* the row below in the sweep, complete now */
        if (i < n) {
            if (mode[i] == 0 && R[i].Fb > 0.0) {
                double f = q[i] + R[i - 1].e * vn;
                if (i + 1 < n) f += R[i].e * v2;
                Ft[i] = f;
                ok &= (R[i].Fb - fabs(f) > 0.0);
            } else {
                Ft[i] = (mode[i] == 0) ? 0.0 : 0.0 - mode[i] * R[i].mukN;
                ok &= !(R[i].Fb > 0.0) | (mode[i] * v1 > 0.0);
            }
        }
        v2 = v1;
        v1 = vn;
    }
    if (mode[0] == 0 && R[0].Fb > 0.0) {  /* the first row */
        double f = q[0];
        if (n > 1) f += R[0].e * v2;
        Ft[0] = f;
        ok &= (R[0].Fb - fabs(f) > 0.0);
    } else {
        Ft[0] = (mode[0] == 0) ? 0.0 : 0.0 - mode[0] * R[0].mukN;
        ok &= !(R[0].Fb > 0.0) | (mode[0] * vn > 0.0);
    }
    s->solves++;
    if (!ok) {
        /* as trial + solve_modes leave the model for a grid step of the whole chain */
        for (size_t i = 0; i < n; i++) {
            st[i] = (mode[i] == 0 && R[i].Fb > 0.0) ? 0 : mode[i];
            l[i] = (st[i] == 0) ? R[i].Fb : R[i].mukN;
        }
        M->kin = M->kinF;
        M->cd = M->dF;
        M->ce = M->eF;
        M->cw1 = cw1;
        M->sw1 = sw1;
        M->A0p = A0;
        return -1;
    }
    /* accept (the last row's V1 from its register: a held row's is +0 there too) */
    for (size_t i = 0; i < n; i++) {
        const double V1 = (i + 1 < n) ? Vt[i] : v_last;
        X[i] = xp[i] + cV * V1;
        A[i] = (V1 - V[i]) * c1 - g1 * A0[i];
        V[i] = V1;
        F[i] = Ft[i];
        hA[i] = hh;
        if (!(R[i].Fb > 0.0)) mode[i] = chain_sgn(V1);
    }
    M->jerk_valid = 0;
    return 1;
}

/* trial's re-basing of A for a whole grid step of the chain (method.md section 8), into M->A0 for
 * every block: the same values, each block's jerk taken on its own when it is re-based (trial
 * takes every block's, from the physical accelerations of all; a jerk needs its neighbours' only
 * with dampers). The jerks are not kept (jerk_valid stays 0). */
static void rebase_whole(chain_model *M, const chain_state *s, double hh)
{
    const size_t n = M->n;
    const double a = M->alpha, tol = 1e-12 * hh + 4.0 * DBL_EPSILON * fabs(s->t);
    int have = 0;
    M->jerk_valid = 0;
    double cw = 0.0, sw = 0.0, pcw = 0.0, psw = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double hA = s->hA[i];
        const int ri = a != 0.0 && hh != hA && fabs(hh - hA) > tol && M->rate_max * fmax(hh, hA) <= 1.0;
        if (!ri) {
            M->A0[i] = s->A[i];
            continue;
        }
        if (!have) {
            /* the excitation's rate at s->t, and its phase as chain_physical_accel reads it */
            cw = dfo_cos(M->omega * s->t + M->phi0);
            sw = dfo_sin(M->omega * s->t + M->phi0);
            chain_phase_of(M, s, s->t, &pcw, &psw);
            have = 1;
        }
        double j = 0.0;
        if (!chain_held(M, s, i)) {
            const double Pd = -M->Pc[i] * M->omega * sw + -M->Ps[i] * M->omega * cw;
            double cv = 0.0;
            if (M->damped) {
                /* (C a)_i with the physical accelerations of i and its neighbours (accelerations) */
                double acc[3];
                for (int k = 0; k < 3; k++) {
                    acc[k] = 0.0;
                    if ((k == 0 && i == 0) || (k == 2 && i + 1 >= n)) continue;
                    const size_t b = i + (size_t)k - 1;
                    if (chain_held(M, s, b)) continue;
                    const double F = chain_has_friction(M, b) ? -s->mode[b] * M->mukN[b] : 0.0;
                    acc[k] = (chain_P_at(M, b, pcw, psw) + M->u[b] - chain_Kx(M, s->X, b) + F - chain_Cv(M, s->V, b)) / M->m[b];
                }
                cv = M->Cd[i] * acc[1];
                if (i > 0) cv += M->Co[i - 1] * acc[0];
                if (i + 1 < n) cv += M->Co[i] * acc[2];
            }
            j = (Pd - chain_Kx(M, s->V, i) - cv) / M->m[i];
        }
        M->A0[i] = s->A[i] + a * (hh - hA) * j;
    }
}

/* A run of whole grid steps through step_fast, after one that it took: from the grid point s->t
 * (grid index n_grid, the excitation cache there), step after step, as chain_advance's loop takes
 * them, while the next grid point is at or before t_target, is not an anchor of the excitation
 * cache (chain_advance evaluates those) and is later than s->t, and while the stuck fast path
 * cannot apply (block 0 not stuck, or stuck_ok off). Returns 1 when it stopped before a step,
 * which it leaves to chain_advance; else the step it set up (n_grid, the cache, s->steps, *t_end
 * and the excitation phase at it, a whole grid step from s->t) that step_fast did not take, with
 * step_fast's result (0, -1) for chain_step_located. No calls: the loop keeps its data in registers. */
static HOT_INLINE int fast_run(chain_model *M, const fast_ctx *C, chain_state *s, double t_target, double *g_prev,
                               double *t_end, double *cw1, double *sw1)
{
    const double h = C->h, t0 = s->t0, rc = M->rot_c, rs = M->rot_s;
    const int stuck_ok = M->stuck_ok;
    if (M->any_frozen) return 1;
    for (;;) {
        const long long g = s->n_grid + 1;
        if ((stuck_ok && s->mode[0] == 0) || g % DFO_EXC_ANCHOR == 0 || s->exc_n != g - 1) return 1;
        const double grid = t0 + (double)g * h;
        if (!(grid <= t_target) || !(grid > s->t)) return 1;
        /* chain_advance's step: grid_phase with its cache at g - 1 (one rotation) */
        s->n_grid = g;
        *g_prev = grid;
        double cn = s->exc_c, sw = s->exc_s;
        dfo_phase_rotate(&cn, &sw, rc, rs);
        s->exc_n = g;
        s->exc_c = cn;
        s->exc_s = sw;
        const double cw = dfo_clamp1(cn), swc = dfo_clamp1(sw);
        s->steps++;
        const int fast = step_fast(M, C, s, cw, swc, s->A, 0);
        if (fast > 0) {
            s->t = grid;
            continue;
        }
        *t_end = grid;
        *cw1 = cw;
        *sw1 = swc;
        return fast;
    }
}

/* chain_start from the velocities v0 (n), with the fixed-frame belts vb (span; NULL: none) */
static void start_with(chain_model *M, const chain_inputs *in, const double *vb, const double *v0, double t0,
                       chain_state *s)
{
    const size_t n = M->n;
    chain_loads_init(M, in);
    s->t0 = s->t = t0;
    s->n_grid = 0;
    s->exc_n = -1;
    s->exc_c = s->exc_s = 0.0;
    s->W_applied = s->W_friction = s->D_damping = 0.0;
    s->steps = s->pivot_steps = s->switches = s->solves = 0;
    for (size_t i = 0; i < n; i++) {
        s->X[i] = M->x0[i];
        s->V[i] = v0[i];
        s->hA[i] = 0.0;
        s->t_stick[i] = t0;
    }
    const span G = chain_whole(M, s, vb, vb);
    chain_net_forces(M, s, &G, M->S);
    /* (belts, vb: at rest on its belt, V = vb; else the mode of V - vb) */
    for (size_t i = 0; i < n; i++) {
        const double vr = vb ? s->V[i] - vb[i] : s->V[i];
        if (chain_has_friction(M, i) && vr == 0.0) s->mode[i] = (fabs(M->S[i]) <= M->Fb[i]) ? 0 : chain_sgn(M->S[i]);
        else s->mode[i] = chain_sgn(vr);
    }
    chain_restart(M, s, &G);
    for (size_t i = 0; i < n; i++) {
        const int dir = s->mode[i];
        if (!chain_has_friction(M, i)) s->F[i] = 0.0;
        else if (dir != 0 && s->V[i] == chain_vb(&G, i))
            s->A[i] = dir * fmax(fmax(dir * M->S[i], M->Fb[i]) - chain_start_mag(M, i), 0.0) / M->m[i];
    }
}

void chain_start(chain_model *M, const chain_inputs *in, double t0, chain_state *s)
{
    start_with(M, in, NULL, M->v0, t0, s);
}

/* The stuck fast path: with every block stuck (all of them with friction) on a grid point, nothing
 * moves until the first breakaway, which each block's closed form gives (friction.h: its static
 * force is its excitation plus a constant while every position is frozen). The whole grid steps
 * that end before it (by a margin of 1e-6 h) and before t_end change nothing but the time and are
 * taken at once; the step that ends on t_end is always stepped. Returns the last grid index they
 * reach (s->n_grid when there is none). Same bits as stepping them (asserted by test_chain). */
static COLD_CALL long long stuck_until(chain_model *M, const chain_state *s, double t_end)
{
    const size_t n = M->n;
    const double h = M->h;
    if (!M->stuck_ok || M->any_frozen) return s->n_grid;
    for (size_t i = 0; i < n; i++)
        if (s->mode[i] != 0) return s->n_grid;
    double tb = t_end;
    for (size_t i = 0; i < n && tb > s->t; i++) {
        int dir = 0;
        tb = fmin(tb, chain_block_breakaway(M, s, i, &dir) - 1e-6 * h);
    }
    if (!(tb > s->t)) return s->n_grid;
    long long m = (long long)floor((tb - s->t0) / h);
    while (m > s->n_grid && !(s->t0 + (double)m * h < tb)) m--;
    while (s->t0 + (double)(m + 1) * h < tb) m++;
    return (m > s->n_grid) ? m : s->n_grid;
}

/* The consistent scheme: a stuck block at rest holds its static force, clamped to the limit,
 * evaluated where a call ends (as the oscillator's dfo_advance); the LCP's force of the step in
 * which it stopped would still carry the deceleration. */
static void rest_forces(chain_model *M, chain_state *s, const double *vb)
{
    /* (belts, vb: a stuck block riding on its belt holds the force of its position where the call
     * ends, as the oscillator's, the same as its LCP's to rounding) */
    if (M->scheme != DFO_SCHEME_CONSISTENT && !vb) return;
    double cw, sw;
    chain_phase_of(M, s, s->t, &cw, &sw);
    for (size_t i = 0; i < M->n; i++) {
        if (!chain_held(M, s, i)) continue;
        const double S = chain_P_at(M, i, cw, sw) + M->u[i] - chain_Kx(M, s->X, i) - chain_Cv(M, s->V, i);
        s->F[i] = -fmax(-M->Fb[i], fmin(M->Fb[i], S));
    }
}

chain_status chain_advance(chain_model *M, const chain_inputs *in, chain_state *s, double t_target,
                           int stop_at_switch, chain_switch_fn on_switch, void *ctx)
{
    return chain_advance_ramped(M, in, NULL, s, t_target, stop_at_switch, on_switch, ctx);
}

/* chain_advance_ramped with the fixed-frame belts vb (span; NULL: none) */
static chain_status advance(chain_model *M, const chain_inputs *in, const chain_ramp *ramp, const double *vb,
                            chain_state *s, double t_target, int stop_at_switch, chain_switch_fn on_switch, void *ctx)
{
    const double h = M->h;
    chain_loads_ramped(M, in, ramp);
    M->err = CHAIN_OK;
    M->switched = 0;
    M->jerk_valid = 0;
    /* a requested time within SNAP_REL_H h of a grid point is that grid point */
    t_target = dfo_grid_snap(s->t0, h, s->n_grid, s->t, t_target, SNAP_REL_H * h);
    /* whole grid steps of the located scheme try the fast path first (step_fast) */
    const int fast_grid = M->scheme == DFO_SCHEME_LOCATED && !(M->rate_max * h > STIFF_STEP) && !M->energy &&
                          !M->ramped && !M->stribeck && !vb;
    if (vb) M->stuck_ok = 0; /* (belts: a stuck block moves) */
    fast_ctx F;
    fast_ctx_init(M, &F);
    double g_prev = s->t0 + (double)s->n_grid * h;  /* the grid point n_grid */
    while (s->t < t_target) {
        /* (stuck_until's first tests, inline) */
        if (M->stuck_ok && s->mode[0] == 0 && s->t == g_prev) {
            const long long m = stuck_until(M, s, t_target);
            if (m > s->n_grid) {
                s->steps += m - s->n_grid;
                s->n_grid = m;
                M->jerk_valid = 0;
                g_prev = s->t = s->t0 + (double)m * h;
                continue;
            }
        }
        double grid = s->t0 + (double)(s->n_grid + 1) * h;
        const int from_grid = (s->t == g_prev);
        double t_end = t_target, cw1, sw1;
        if (grid <= t_target) {
            t_end = grid;
            s->n_grid++;
            g_prev = grid;
            grid_phase(M, s, s->n_grid, &cw1, &sw1);
        } else {
            chain_phase_of(M, s, t_end, &cw1, &sw1);
        }
        if (!(t_end > s->t)) return CHAIN_ERR_RESOLUTION;
        double hh = h;
        if (!(from_grid && t_end == grid)) hh = t_end - s->t;
        s->steps++;
        /* ramped inputs: the loads of this internal step are those at its end, where Bossak reads
         * them (also in its switches' sub-steps and restarts, as the oscillator's) */
        if (M->ramped) {
            M->t_step = M->t_load = t_end;
            chain_loads_ramp(M, t_end);
        }
        if (M->scheme == DFO_SCHEME_LOCATED) {
            int fast = 0;
            if (fast_grid && hh == h && !M->any_frozen) {
                fast = step_fast(M, &F, s, cw1, sw1, s->A, 0);
                if (fast == 0) {  /* A must be re-based first (after a switch) */
                    rebase_whole(M, s, h);
                    fast = step_fast(M, &F, s, cw1, sw1, M->A0, 1);
                }
                if (fast > 0) {
                    s->t = t_end;
                    fast = fast_run(M, &F, s, t_target, &g_prev, &t_end, &cw1, &sw1);
                    if (fast > 0) continue;
                    grid = t_end;  /* a whole grid step, set up by fast_run: hh is h */
                }
            }
            chain_step_located(M, s, vb, t_end, hh, cw1, sw1, fast, on_switch, ctx, stop_at_switch);
        } else {
            chain_step_lcp(M, s, vb, t_end, hh, on_switch, ctx, M->scheme == DFO_SCHEME_CONSISTENT);
        }
        if (M->err != CHAIN_OK) return M->err;
        if (stop_at_switch && M->switched) {
            /* the grid index stays that of the last grid point at or before the time reached */
            if (s->t < t_end && t_end == grid) s->n_grid--;
            chain_loads_at(M, s->t);
            rest_forces(M, s, vb);
            return CHAIN_SWITCHED;  /* (g_prev is not used again) */
        }
    }
    chain_loads_at(M, s->t);
    rest_forces(M, s, vb);
    for (size_t i = 0; i < M->n; i++)
        if (!(fabs(s->X[i]) <= DBL_MAX && fabs(s->V[i]) <= DBL_MAX && fabs(s->A[i]) <= DBL_MAX))
            return CHAIN_ERR_NONFINITE;
    return CHAIN_OK;
}

chain_status chain_advance_ramped(chain_model *M, const chain_inputs *in, const chain_ramp *ramp, chain_state *s,
                                  double t_target, int stop_at_switch, chain_switch_fn on_switch, void *ctx)
{
    return advance(M, in, ramp, NULL, s, t_target, stop_at_switch, on_switch, ctx);
}

/* ---- belts (chain.h: chain_advance_belt) ------------------------------------------------------
 * With the belt speeds vb held from t_ref, y = x - vb (t - t_ref) obeys the chain's equation with
 * friction on y' = v - vb and the external force F_ext - C vb - K vb (t - t_ref): a ramp of rate
 * -K vb (chain_advance_ramped, exact for a linear input), stuck meaning y' = 0. The state is moved
 * into y before and back after; the net forces, hence A and F, are the same in both. */

typedef struct {
    chain_switch_fn fn;
    void *ctx;
    const double *vb;
    double t_ref;
} belt_switch;

static void belt_on_switch(void *ctx, double t, size_t block, double x, int from, int to)
{
    const belt_switch *b = (const belt_switch *)ctx;
    if (b->fn) b->fn(b->ctx, t, block, x + b->vb[block] * (t - b->t_ref), from, to);
}

/* The inputs and ramp of the moving frame, their arrays in fw (2n: F_ext, then its rate), handed
 * back in bin and bramp. */
static void belt_frame(const chain_model *M, const chain_inputs *in, const chain_ramp *ramp, const double *vb,
                       double *fw, chain_inputs *bin, chain_ramp *bramp)
{
    const size_t n = M->n;
    double *bF = fw, *bD = fw + n;
    for (size_t i = 0; i < n; i++) {
        const double Cvb = M->damped ? chain_Cv(M, vb, i) : 0.0;
        bF[i] = (in->F_ext ? in->F_ext[i] : 0.0) - Cvb;
        bD[i] = (ramp && ramp->dF_ext[0] ? ramp->dF_ext[0][i] : 0.0) - chain_Kx(M, vb, i);
    }
    bin->F_ext = bF;
    bin->N_ext = in->N_ext;
    if (ramp) *bramp = *ramp;
    else {
        bramp->dF_ext[1] = bramp->dN_ext[0] = bramp->dN_ext[1] = NULL;
    }
    bramp->dF_ext[0] = bD;
}

static void belt_shift(const chain_model *M, chain_state *s, const double *vb, double t_ref, double sign)
{
    for (size_t i = 0; i < M->n; i++) {
        s->X[i] += sign * (vb[i] * (s->t - t_ref));
        s->V[i] += sign * vb[i];
    }
}

/* The located scheme (on steps that resolve the motion) steps in the fixed frame with the LCP on the
 * velocity relative to the belts, as the oscillator's located step; the consistent scheme (and a
 * stiff grid, which hands its steps to it) in the belts' moving frame. */
static int belt_fixed_frame(const chain_model *M)
{
    return M->scheme == DFO_SCHEME_LOCATED && !(M->rate_max * M->h > STIFF_STEP);
}

chain_status chain_advance_belt(chain_model *M, const chain_inputs *in, const chain_ramp *ramp, const double *vb,
                                chain_state *s, double t_target, int stop_at_switch, chain_switch_fn on_switch,
                                void *ctx)
{
    if (!vb) return advance(M, in, ramp, NULL, s, t_target, stop_at_switch, on_switch, ctx);
    if (belt_fixed_frame(M)) return advance(M, in, ramp, vb, s, t_target, stop_at_switch, on_switch, ctx);
    chain_inputs bin;
    chain_ramp bramp;
    belt_frame(M, in, ramp, vb, M->fw, &bin, &bramp);
    bramp.t_ref = ramp ? ramp->t_ref : s->t;
    belt_switch bs = {on_switch, ctx, vb, bramp.t_ref};
    belt_shift(M, s, vb, bramp.t_ref, -1.0);
    /* in the belt's frame V is the relative velocity: no belts inside */
    const chain_status st = advance(M, &bin, &bramp, NULL, s, t_target, stop_at_switch, belt_on_switch, &bs);
    belt_shift(M, s, vb, bramp.t_ref, 1.0);
    return st;
}

void chain_start_belt(chain_model *M, const chain_inputs *in, const double *vb, double t0, chain_state *s)
{
    if (!vb) { chain_start(M, in, t0, s); return; }
    if (belt_fixed_frame(M)) {
        start_with(M, in, vb, M->v0, t0, s);
        return;
    }
    chain_inputs bin;
    chain_ramp bramp;
    belt_frame(M, in, NULL, vb, M->fw, &bin, &bramp);
    /* the start in the moving frame: from v0 - vb (in Vt, free until the first step) */
    double *v0r = M->Vt;
    for (size_t i = 0; i < M->n; i++) v0r[i] = M->v0[i] - vb[i];
    start_with(M, &bin, NULL, v0r, t0, s);
    for (size_t i = 0; i < M->n; i++) s->V[i] += vb[i];
    /* (the stuck blocks' rest, V - vb = 0 exactly: V = vb) */
    for (size_t i = 0; i < M->n; i++)
        if (s->mode[i] == 0 && chain_has_friction(M, i)) s->V[i] = vb[i];
}

void chain_new_belt(chain_model *M, const chain_inputs *in, const double *vb_old, const double *vb_new, chain_state *s,
                    chain_switch_fn on_switch, void *ctx)
{
    const size_t n = M->n;
    chain_loads_init(M, in);
    int changed = 0;
    for (size_t i = 0; i < n; i++) {
        if (!chain_has_friction(M, i)) continue;
        const double vo = vb_old ? vb_old[i] : 0.0, vn = vb_new ? vb_new[i] : 0.0;
        if (vo == vn) continue;
        const double vr = s->V[i] - vn;
        const int from = s->mode[i];
        int to = chain_sgn(vr);
        if (vr == 0.0 && from != 0) {
            /* a slide that the new belt meets: the rest rule */
            const span G = chain_whole(M, s, NULL, vb_new);
            chain_net_forces(M, s, &G, M->S);
            to = (fabs(M->S[i]) <= M->Fb[i]) ? 0 : chain_sgn(M->S[i]);
        }
        if (to == from) {
            /* a slide goes on relative to the new belt: it restarts with the physical acceleration (as
             * the oscillator's; with Stribeck at another relative speed, so with another force) */
            if (to != 0) changed = 1;
            continue;
        }
        s->mode[i] = to;
        if (to == 0) s->t_stick[i] = s->t;
        chain_report(M, s, i, from, on_switch, ctx);
        changed = 1;
    }
    if (!changed) return;
    /* the consistent restart of the new mode set in the moving frame (net forces are the same) */
    const span G = chain_whole(M, s, NULL, vb_new);
    chain_restart(M, s, &G);
    M->jerk_valid = 0;
}
