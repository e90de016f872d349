/* The chain's located scheme (method.md section 9): the basis solve of a trial (the kept
 * factorisation of a grid step's M_hat, or lcp_box_basis), the switch margins, the bracketed root
 * of the first switch, the switches and the consistent restart, spans and clusters with ghosts.
 * See chain_internal.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_internal.h"
#include "roots.h"

#include <string.h>

/* lcp_box_basis on the whole chain with a whole grid step's M_hat (dF, eF), by its factorisation kept
 * for the held pattern (M->rows; see step_fast): the same operations, so the same bits. */
static void solve_kept(chain_model *M)
{
    const size_t n = M->n;
    const double *restrict q = M->q, *restrict l = M->l;
    const int *restrict mode = M->st;
    fast_row *restrict R = M->rows;
    double *restrict dp = M->dp, *restrict V = M->Vt, *restrict F = M->Ft;
    double cprev = 0.0, dprev = 0.0;
    int refac = 0;
    for (size_t i = 0; i < n; i++) {
        const int hold = (mode[i] == 0 && l[i] > 0.0);
        refac = chain_refactor_row(R, i, hold, cprev, refac);
        double dpi = 0.0;
        if (!hold) {
            const double lo_e = (i > 0) ? R[i - 1].e : 0.0;
            const double rhs = -q[i] - ((l[i] > 0.0) ? mode[i] * l[i] : 0.0);
            dpi = (rhs - lo_e * dprev) * R[i].inv;
        }
        dp[i] = dpi;
        cprev = R[i].cp;
        dprev = dpi;
    }
    double vn = 0.0;
    for (size_t j = n; j-- > 0;) {
        vn = dp[j] - R[j].cp * vn;
        V[j] = vn;
    }
    for (size_t i = 0; i < n; i++) {
        if (mode[i] == 0 && l[i] > 0.0) {
            V[i] = 0.0;
            double f = q[i];
            if (i > 0) f += R[i - 1].e * V[i - 1];
            if (i + 1 < n) f += R[i].e * V[i + 1];
            F[i] = f;
        } else {
            F[i] = (l[i] > 0.0) ? 0.0 - mode[i] * l[i] : 0.0;
        }
    }
}

/* Stribeck: the sliding blocks' friction at the step's end, -s N mu(u), u = s V the relative speed
 * (implicit, as the damper: Bossak's second order kept), after the basis solve with the smaller
 * kinetic limit min(mu_s, mu_k) N has decided the modes. Over each run of consecutive free rows
 * of the span (its other rows held at V = 0 or ghosts) the equations M_hat V = p_hat + F(V), F_i =
 * -s_i N_i mu(max(s_i V_i, 0)) (continued below u = 0 with mu(0), so that s_i V_i is continuous in
 * the step length and its sign tells a stop) are solved by Newton's iteration from the basis
 * solve, one tridiagonal solve per iteration; a run of one row takes the oscillator's scalar
 * iteration (friction.h's dfo_stribeck_speed), so that n = 1 is the oscillator's arithmetic. The
 * held rows' forces are then read anew. */
static int stribeck_row(const chain_model *M, size_t i)
{
    return M->st[i] != 0 && chain_has_friction(M, i);
}

static void stribeck_run(chain_model *M, size_t lo, size_t hi, size_t r0, size_t r1)
{
    const double *d = M->cd, *e = M->ce, *q = M->q;
    double *V = M->Vt, *F = M->Ft, *cp = M->cp, *dp = M->dp;
    if (r1 - r0 == 1) {
        const size_t i = r0;
        double p = -q[i];
        if (i > lo) p -= e[i - 1] * V[i - 1];
        if (i + 1 < hi) p -= e[i] * V[i + 1];
        const int sd = M->st[i];
        const double u = dfo_stribeck_speed(&M->law[i], M->Nn[i], sd * p, d[i], 1.0 / d[i]);
        V[i] = sd * u;
        F[i] = -sd * M->Nn[i] * dfo_friction_mu(&M->law[i], fmax(u, 0.0));
        return;
    }
    int done = 0;
    double dlast = INFINITY;
    for (int it = 0; it < 60 && !done; it++) {
        /* the residual and the Jacobian's diagonal, eliminated at once (Thomas) */
        double cprev = 0.0, dprev = 0.0;
        for (size_t i = r0; i < r1; i++) {
            double R = d[i] * V[i] + q[i], J = d[i];
            if (i > lo) R += e[i - 1] * V[i - 1];
            if (i + 1 < hi) R += e[i] * V[i + 1];
            if (stribeck_row(M, i)) {
                const int sd = M->st[i];
                const double u = sd * V[i];
                R += sd * M->Nn[i] * dfo_friction_mu(&M->law[i], fmax(u, 0.0));
                if (u > 0.0) J += M->Nn[i] * dfo_friction_dmu(&M->law[i], u);
            }
            const double lo_e = (i > r0) ? e[i - 1] : 0.0;
            const double inv = 1.0 / (J - lo_e * cprev);
            cp[i] = (i + 1 < r1) ? e[i] * inv : 0.0;
            dp[i] = (R - lo_e * dprev) * inv;
            cprev = cp[i];
            dprev = dp[i];
        }
        double dn = 0.0, dmax = 0.0, vmax = 0.0;
        for (size_t j = r1; j-- > r0;) {
            dn = dp[j] - cp[j] * dn;
            V[j] -= dn;
            dmax = fmax(dmax, fabs(dn));
            vmax = fmax(vmax, fabs(V[j]));
        }
        /* converged to a few ulps, or (a long run) to the rounding of its residual: the correction
         * small and no longer contracting, as Newton's quadratic convergence would */
        done = dmax <= 4.0 * DBL_EPSILON * vmax || (dmax <= 1e-10 * vmax && dmax >= 0.25 * dlast);
        dlast = dmax;
    }
    if (!done && M->err == CHAIN_OK) M->err = CHAIN_ERR_FRICTION;
    for (size_t i = r0; i < r1; i++)
        if (stribeck_row(M, i))
            F[i] = -M->st[i] * M->Nn[i] * dfo_friction_mu(&M->law[i], fmax(M->st[i] * V[i], 0.0));
}

static COLD_CALL void stribeck_solve(chain_model *M, const span *G)
{
    const size_t lo = G->a - (size_t)G->has[0], hi = G->b + (size_t)G->has[1];
    int any = 0;
    for (size_t i = G->a; i < G->b;) {
        const int held = M->st[i] == 0 && M->l[i] > 0.0;
        if (held) { i++; continue; }
        size_t r1 = i;
        int fr = 0;
        while (r1 < G->b && !(M->st[r1] == 0 && M->l[r1] > 0.0)) fr |= stribeck_row(M, r1++);
        if (fr) { stribeck_run(M, lo, hi, i, r1); any = 1; }
        i = r1;
    }
    if (!any) return;
    for (size_t i = G->a; i < G->b; i++) { /* the held rows' forces with their neighbours' new V */
        if (!(M->st[i] == 0 && M->l[i] > 0.0)) continue;
        double f = M->q[i];
        if (i > lo) f += M->ce[i - 1] * M->Vt[i - 1];
        if (i + 1 < hi) f += M->ce[i] * M->Vt[i + 1];
        M->Ft[i] = f;
    }
}

static void solve_modes(chain_model *M, const span *G)
{
    if (M->cd == M->dF && G->a == 0 && G->b == M->n && !G->has[0] && !G->has[1]) {
        solve_kept(M);
    } else {
        const size_t lo = G->a - (size_t)G->has[0], hi = G->b + (size_t)G->has[1];
        /* l (set with st): Fb for held rows (a flag there), the LCP's sliding limit mlN for sliding
         * ones, 0 without friction */
        double g0 = G->gV[0], g1 = G->gV[1];
        if (G->vb) { /* the ghosts' velocities relative to their belts */
            if (G->has[0]) g0 -= G->vb[G->idx[0]];
            if (G->has[1]) g1 -= G->vb[G->idx[1]];
        }
        lcp_box_basis(lo, hi, G->has[0], g0, G->has[1], g1, M->cd, M->ce, M->q, M->l, M->st, M->Vt, M->Ft, M->cp,
                      M->dp);
    }
    if (M->stribeck) stribeck_solve(M, G);
}

/* How far block i is from its switch at the trial (> 0: not yet): s V for a sliding block (as the
 * oscillator's stop), F_b - |F| for a stuck one. */
static double switch_margin(const chain_model *M, const chain_state *s, size_t i)
{
    if (M->st[i] != 0) return s->mode[i] * M->Vt[i];
    if (M->ramped) {
        /* ramped inputs: the held force and the limit with the inputs at the trial's end (the
         * trial's loads are the internal step's), so that a breakaway is placed to second order */
        double u, Ne, rate;
        chain_ramp_value(&M->rin, &M->ramp, 0, i, M->t_trial, &u, &rate);
        chain_ramp_value(&M->rin, &M->ramp, 1, i, M->t_trial, &Ne, &rate);
        const double Fb = M->mu_b[i] * fmax(M->N[i] + Ne, 0.0);
        return Fb - fabs(M->Ft[i] - (u - M->u[i]));
    }
    return M->Fb[i] - fabs(M->Ft[i]);
}

typedef struct {
    chain_model *M;
    const chain_state *s;
    span *G;
} margin_ctx;

/* The smallest margin of the candidates after a trial step of length x. */
static double min_margin(void *vctx, double x)
{
    margin_ctx *c = (margin_ctx *)vctx;
    chain_model *M = c->M;
    const chain_state *s = c->s;
    double cw, sw;
    chain_phase_of(M, s, s->t + x, &cw, &sw);
    M->t_load = s->t + x; /* ramped inputs: a sub-step takes the loads at its own end */
    chain_trial(M, s, c->G, x, cw, sw);
    M->t_load = M->t_step;
    solve_modes(M, c->G);
    double g = INFINITY;
    for (size_t k = 0; k < M->ncand; k++) g = fmin(g, switch_margin(M, s, M->cand[k]));
    return g;
}

/* Switch the candidates whose margin is <= 0 at the state just reached (all of them when
 * immediate: no sub-step before the switch could be resolved). A stopping block is set at rest
 * and the rest rule of friction.h decides with its own net force; a stuck one breaks away in the
 * direction of its net force. Then the consistent restart of the span's new mode set. */
static void apply_switches(chain_model *M, chain_state *s, const span *G, int immediate, chain_switch_fn fn, void *ctx)
{
    size_t nsw = 0;
    for (size_t k = 0; k < M->ncand; k++) {
        const size_t i = M->cand[k];
        if (!immediate && switch_margin(M, s, i) > 0.0) continue;  /* (at the trial's loads) */
        M->cand[nsw++] = i;
        if (s->mode[i] != 0) {
            /* a slide from rest that cannot move in double precision: held to the step's end */
            const double vb = chain_vb(G, i);
            if (immediate && s->V[i] == vb) M->frozen[i] = M->any_frozen = 1;
            s->V[i] = vb;
        }
    }
    M->ncand = nsw;
    /* ramped inputs: the rest rule and the restart with the loads at the switch (as the oscillator's),
     * those of the internal step's end again for its remainder */
    if (M->ramped) chain_loads_ramp(M, s->t);
    chain_net_forces(M, s, G, M->S);
    for (size_t k = 0; k < nsw; k++) {
        const size_t i = M->cand[k];
        const int from = s->mode[i];
        const double S = M->S[i];
        if (M->frozen[i]) s->mode[i] = 0;
        else if (from != 0) s->mode[i] = (fabs(S) <= M->Fb[i]) ? 0 : chain_sgn(S);
        else s->mode[i] = (chain_sgn(S) != 0) ? chain_sgn(S) : -chain_sgn(M->Ft[i]);
        if (s->mode[i] == 0 && from != 0) s->t_stick[i] = s->t;
        if (s->mode[i] != from) chain_report(M, s, i, from, fn, ctx);
    }
    chain_restart(M, s, G);
    /* the consistent acceleration of a slide from rest never points against it (friction.h) */
    for (size_t k = 0; k < nsw; k++) {
        const size_t i = M->cand[k];
        const int dir = s->mode[i];
        if (dir != 0) s->A[i] = dir * fmax(fmax(dir * M->S[i], M->Fb[i]) - chain_start_mag(M, i), 0.0) / M->m[i];
    }
    if (M->ramped) chain_loads_ramp(M, M->t_step);
}

/* Block i stuck with X frozen and every neighbour at rest: its static force is its excitation
 * plus a constant, and its next breakaway after the stick phase's start is known in closed form
 * (friction.h, as the oscillator's); INFINITY when it does not apply. */
/* Ramped inputs: side times block i's static force beyond its limit at t, with the inputs at t
 * (> 0: broken away). The root finder's context of a block's gap (ramped or on belts). */
typedef struct {
    const chain_model *M;
    const chain_state *s;
    const double *vb;  /* the belts (belt_gap), or NULL */
    size_t i;
    int side;
} block_gap_ctx;

static double ramp_gap(const chain_model *M, const chain_state *s, size_t i, double t, int side)
{
    double u, Ne, rate, cw, sw;
    chain_ramp_value(&M->rin, &M->ramp, 0, i, t, &u, &rate);
    chain_ramp_value(&M->rin, &M->ramp, 1, i, t, &Ne, &rate);
    const double Fb = M->mu_b[i] * fmax(M->N[i] + Ne, 0.0);
    chain_phase_of(M, s, t, &cw, &sw);
    return side * (chain_P_at(M, i, cw, sw) + u - chain_Kx(M, s->X, i)) - Fb;
}

static double ramp_gap_fn(void *vctx, double x)
{
    const block_gap_ctx *g = (const block_gap_ctx *)vctx;
    return -ramp_gap(g->M, g->s, g->i, g->s->t + x, g->side);
}

/* The breakaway of block i inside [s->t, tb] with the inputs varying (as the oscillator's): the side
 * broken through at tb, or at the closed form's breakaway for the loads of the internal step; its
 * time the root of the gap with the loads varying (Brent), so that it is placed to second order. */
static double ramp_breakaway(const chain_model *M, const chain_state *s, size_t i, double tb, int *dir)
{
    const double ta = s->t;
    int side = 0;
    double hi = tb, ghi = 0.0;
    for (int sd = -1; sd <= 1; sd += 2) {
        const double g = ramp_gap(M, s, i, tb, sd);
        if (g > 0.0) { side = sd; ghi = g; }
    }
    if (side == 0) {
        dfo_harmonic P;
        dfo_harmonic_init(&P, M->P0[i], M->omega, M->phi[i]);
        const dfo_loads L = {M->u[i], 0.0, M->mukN[i], M->Fb[i]};  /* (N is not read) */
        int d = 0;
        const double t1 = dfo_next_breakaway(&P, &L, M->u[i] - chain_Kx(M, s->X, i), ta, &d);
        if (t1 <= tb && d != 0) {
            const double g = ramp_gap(M, s, i, t1, d);
            if (g > 0.0) { side = d; hi = t1; ghi = g; }
        }
    }
    if (side == 0) return INFINITY;
    *dir = side;
    const double g0 = ramp_gap(M, s, i, ta, side);
    if (g0 >= 0.0) return ta;
    block_gap_ctx g = {M, s, NULL, i, side};
    return ta + dfo_root_bracketed(ramp_gap_fn, &g, ta, 0.0, -g0, hi - ta, -ghi);
}

/* Block i's neighbours are at rest (held, or frozen inside the span) */
static int neighbours_rest(const chain_model *M, const chain_state *s, const span *G, size_t i)
{
    for (int side = -1; side <= 1; side += 2) {
        if ((side < 0 && i == 0) || (side > 0 && i + 1 >= M->n)) continue;
        const size_t j = (side < 0) ? i - 1 : i + 1;
        const int inside = j >= G->a && j < G->b;
        if (!(chain_held(M, s, j) || (inside && M->frozen[j]))) return 0;
    }
    return 1;
}

/* ---- belts (span's vb): a stuck block riding on its belt, its neighbours on theirs ----
 * side times block i's static force beyond its limit at t, every block at X + vb (t - s->t), the
 * loads at t (ramped inputs) or held: side (P + u - (K x)_i - (C vb)_i) - Fb, the oscillator's
 * belt_gap for one block. */
static double belt_gap(const chain_model *M, const chain_state *s, const double *vb, size_t i, double t, int side)
{
    double u = M->u[i], Fb = M->Fb[i], cw, sw;
    if (M->ramped) {
        double Ne, rate;
        chain_ramp_value(&M->rin, &M->ramp, 0, i, t, &u, &rate);
        chain_ramp_value(&M->rin, &M->ramp, 1, i, t, &Ne, &rate);
        Fb = M->mu_b[i] * fmax(M->N[i] + Ne, 0.0);
    }
    const double *X = s->X, dt = t - s->t;
    double kx = M->Kd[i] * (X[i] + vb[i] * dt);
    if (i > 0) kx += M->Ko[i - 1] * (X[i - 1] + vb[i - 1] * dt);
    if (i + 1 < M->n) kx += M->Ko[i] * (X[i + 1] + vb[i + 1] * dt);
    chain_phase_of(M, s, t, &cw, &sw);
    return side * (chain_P_at(M, i, cw, sw) + u - kx - chain_Cv(M, vb, i)) - Fb;
}

static double belt_gap_fn(void *vctx, double x)
{
    const block_gap_ctx *g = (const block_gap_ctx *)vctx;
    return -belt_gap(g->M, g->s, g->vb, g->i, g->s->t + x, g->side);
}

/* broken away by t_end (either side) */
static int belt_breaks(const chain_model *M, const chain_state *s, const double *vb, size_t i, double t_end)
{
    return belt_gap(M, s, vb, i, t_end, -1) > 0.0 || belt_gap(M, s, vb, i, t_end, 1) > 0.0;
}

/* The breakaway inside [s->t, tb] of stuck block i riding on its belt between resting neighbours:
 * the side broken through at tb, the time the root of the gap (Brent), as the oscillator's
 * belt_breakaway; INFINITY when not broken through at tb. */
static double belt_breakaway(const chain_model *M, const chain_state *s, const double *vb, size_t i, double tb,
                             int *dir)
{
    const double ta = s->t;
    for (int sd = -1; sd <= 1; sd += 2) {
        const double ghi = belt_gap(M, s, vb, i, tb, sd);
        if (!(ghi > 0.0)) continue;
        *dir = sd;
        const double g0 = belt_gap(M, s, vb, i, ta, sd);
        if (g0 >= 0.0) return ta;
        block_gap_ctx g = {M, s, vb, i, sd};
        return ta + dfo_root_bracketed(belt_gap_fn, &g, ta, 0.0, -g0, tb - ta, -ghi);
    }
    return INFINITY;
}

static double closed_breakaway(const chain_model *M, const chain_state *s, const span *G, size_t i, double t_end,
                               int *dir)
{
    if (!neighbours_rest(M, s, G, i)) return INFINITY;
    if (G->vb) return belt_breakaway(M, s, G->vb, i, t_end, dir);  /* the static force drifts with the belts */
    if (M->ramped) return ramp_breakaway(M, s, i, t_end, dir);  /* the closed form holds for held inputs */
    return chain_block_breakaway(M, s, i, dir);
}


/* Ramped inputs: a stuck block whose static force crosses its limit inside the step, also where it
 * is back inside at the step's end (the oscillator's breakaway test), is a candidate. */
static int ramp_breaks(const chain_model *M, const chain_state *s, const span *G, size_t i, double t_end)
{
    if (!M->ramped || M->st[i] != 0) return 0;
    int dir = 0;
    return closed_breakaway(M, s, G, i, t_end, &dir) <= t_end;
}

/* Whether a block with friction is a candidate to switch in the trial to t_end: its margin is not
 * positive; with ramped inputs, a stuck one whose force crosses its limit inside the step; on belts,
 * a stuck one between resting neighbours whose static force at t_end, the belts carrying them, is
 * beyond its limit (the oscillator's test; its held force's rounding aside). */
static HOT_INLINE int is_candidate(chain_model *M, const chain_state *s, const span *G, size_t i, double t_end)
{
    if (G->vb && M->st[i] == 0 && neighbours_rest(M, s, G, i)) return belt_breaks(M, s, G->vb, i, t_end);
    return switch_margin(M, s, i) <= 0.0 || ramp_breaks(M, s, G, i, t_end);
}

/* On belts, a sliver of a step after a switch (r <= 1e-6 h, every block of the span restarted: hA =
 * 0, one of them moving): V = vb + u is not small, and Bossak's A = (V1 - V) / (gamma r) would be
 * its rounding over r; Taylor's expansion with the physical accelerations is exact to O(r^2)
 * instead (the oscillator's), the held blocks riding on their belts. Returns 1 when taken. */
#define BELT_TINY_REL_H 1e-6
static int belt_sliver(chain_model *M, chain_state *s, const span *G, double t_end, double r)
{
    if (!(r <= BELT_TINY_REL_H * M->h)) return 0;
    int moving = 0;
    for (size_t i = G->a; i < G->b; i++) {
        if (s->hA[i] != 0.0) return 0;
        moving |= !(chain_held(M, s, i) || M->frozen[i]);
    }
    if (!moving) return 0;
    for (size_t i = G->a; i < G->b; i++) {
        if (chain_held(M, s, i) || M->frozen[i]) {
            s->X[i] = s->X[i] + G->vb[i] * (t_end - s->t);
        } else {
            s->X[i] += (s->V[i] + 0.5 * s->A[i] * r) * r;
            s->V[i] += s->A[i] * r;
        }
    }
    M->jerk_valid = 0;
    s->t = t_end;
    return 1;
}

/* The located step of a span from s->t to t_end (first phase of length hh): phases in the current
 * modes, each ended at the earliest switch of a block of the span (method.md section 9). */
static void located_span(chain_model *M, chain_state *s, span *G, double t_end, double hh, chain_switch_fn fn,
                         void *ctx, int stop_at_switch)
{
    const long max_phases = 64 + 4 * (long)(G->b - G->a);
    for (long phase = 0; s->t < t_end; phase++) {
        if (phase >= max_phases) { M->err = CHAIN_ERR_NO_PROGRESS; return; }
        chain_set_ghosts(M, s, G);
        const double r = (phase == 0) ? hh : t_end - s->t;
        if (G->vb && belt_sliver(M, s, G, t_end, r)) return;
        for (size_t i = G->a; i < G->b; i++) {
            M->st[i] = (chain_held(M, s, i) || M->frozen[i]) ? 0 : s->mode[i];
            M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mlN[i];
        }
        double cw1, sw1;
        chain_phase_of(M, s, t_end, &cw1, &sw1);
        chain_trial(M, s, G, r, cw1, sw1);
        solve_modes(M, G);
        s->solves++;
        M->ncand = 0;
        for (size_t i = G->a; i < G->b; i++) {
            if (!chain_has_friction(M, i) || M->frozen[i]) continue;
            if (is_candidate(M, s, G, i, t_end)) M->cand[M->ncand++] = i;
        }
        if (M->ncand == 0) {  /* the warm basis solves the LCP: the whole remainder in these modes */
            chain_finish(M, s, G, M->Vt, M->Ft, t_end);
            for (size_t i = G->a; i < G->b; i++)
                if (!chain_has_friction(M, i)) s->mode[i] = chain_sgn(s->V[i]);
            s->t = t_end;
            return;
        }
        /* breakaways among resting neighbours only: at their closed-form time */
        double tb = INFINITY;
        for (size_t k = 0; k < M->ncand; k++) {
            const size_t i = M->cand[k];
            int dir = 0;
            const double t = (M->st[i] == 0) ? closed_breakaway(M, s, G, i, t_end, &dir) : -INFINITY;
            M->S[i] = t;
            tb = fmin(tb, t);
        }
        if (tb >= s->t && tb <= t_end) {
            const double ta = s->t, hs = tb - ta;
            if (hs > 0.0) {
                double c1w, s1w;
                chain_phase_of(M, s, tb, &c1w, &s1w);
                M->t_load = (tb == t_end) ? M->t_step : tb;
                chain_trial(M, s, G, (tb == t_end) ? r : hs, c1w, s1w);
                M->t_load = M->t_step;
                solve_modes(M, G);
                s->solves++;
                chain_finish(M, s, G, M->Vt, M->Ft, tb);
            }
            s->t = tb;
            size_t nsw = 0;
            for (size_t k = 0; k < M->ncand; k++)
                if (M->S[M->cand[k]] == tb) M->cand[nsw++] = M->cand[k];
            M->ncand = nsw;
            chain_set_ghosts(M, s, G);
            apply_switches(M, s, G, 1, fn, ctx);
            if (stop_at_switch && M->switched) return;
            continue;
        }
        /* bracket the first switch: (lo, hi] with min_margin(lo) > 0 >= min_margin(hi) */
        margin_ctx mc = {M, s, G};
        double hi = r, ghi = INFINITY;
        for (size_t k = 0; k < M->ncand; k++) ghi = fmin(ghi, switch_margin(M, s, M->cand[k]));
        /* from the state itself when every candidate is a block still moving its way (as the
         * oscillator's stop), else by halving the step */
        double lo = 0.0, glo = INFINITY;
        for (size_t k = 0; k < M->ncand; k++) {
            const size_t i = M->cand[k];
            glo = (M->st[i] != 0) ? fmin(glo, s->mode[i] * (G->vb ? s->V[i] - G->vb[i] : s->V[i])) : -INFINITY;
        }
        if (!(glo > 0.0)) {
            lo = r;
            glo = -INFINITY;
            for (int it = 0; it < HALVINGS && !(glo > 0.0); it++) {
                lo *= 0.5;
                glo = min_margin(&mc, lo);
                s->solves++;
            }
        }
        if (!(glo > 0.0)) {  /* nothing resolvable before the switch: it happens now */
            apply_switches(M, s, G, 1, fn, ctx);
            if (stop_at_switch && M->switched) return;
            continue;
        }
        const double ta = s->t;
        const double hs = dfo_root_bracketed(min_margin, &mc, ta, lo, glo, hi, ghi);
        const double t1 = (hs >= r) ? t_end : ta + hs;
        double c1w, s1w;
        if (hs >= r) chain_phase_of(M, s, t_end, &c1w, &s1w);
        else { c1w = dfo_cos(M->omega * t1 + M->phi0); s1w = dfo_sin(M->omega * t1 + M->phi0); }
        if (M->ramped && hs < r) {
            /* ramped inputs: which blocks switch, from the sub-step with the loads at its own end
             * (the root's); the sub-step itself with the internal step's loads, as the oscillator's */
            M->t_load = t1;
            chain_trial(M, s, G, hs, c1w, s1w);
            solve_modes(M, G);
            s->solves++;
            size_t nsw = 0;
            for (size_t k = 0; k < M->ncand; k++)
                if (switch_margin(M, s, M->cand[k]) <= 0.0) M->cand[nsw++] = M->cand[k];
            M->ncand = nsw;
            /* the velocities and forces of that sub-step (S and box hold them: free until the
             * switches), the predicted positions and re-based accelerations of the one with the
             * internal step's loads (for one block: the oscillator's sub-step, bit for bit) */
            const size_t lo = G->a - (size_t)G->has[0], hi = G->b + (size_t)G->has[1];
            for (size_t i = lo; i < hi; i++) { M->S[i] = M->Vt[i]; M->box[i] = M->Ft[i]; }
            M->t_load = M->t_step;
            chain_trial(M, s, G, hs, c1w, s1w);
            for (size_t i = lo; i < hi; i++) { M->Vt[i] = M->S[i]; M->Ft[i] = M->box[i]; }
            for (size_t k = 0; k < M->ncand; k++)
                if (M->st[M->cand[k]] != 0) M->Vt[M->cand[k]] = 0.0;
        } else {
            chain_trial(M, s, G, hs, c1w, s1w);
            solve_modes(M, G);
            s->solves++;
            for (size_t k = 0; k < M->ncand; k++) {  /* a stopping block ends the sub-step at rest */
                const size_t i = M->cand[k];
                if (M->st[i] != 0 && switch_margin(M, s, i) <= 0.0) M->Vt[i] = 0.0;
            }
        }
        const double t_new = (hs >= r) ? t_end : fmax(t1, nextafter(ta, INFINITY));
        chain_finish(M, s, G, M->Vt, M->Ft, t_new);
        s->t = t_new;
        chain_set_ghosts(M, s, G);
        apply_switches(M, s, G, 0, fn, ctx);
        if (stop_at_switch && M->switched) return;
    }
}

/* Save (dir 0) or restore (dir 1) the state of blocks [a, b). */
static void save_blocks(chain_model *M, chain_state *s, size_t a, size_t b, int restore)
{
    M->jerk_valid = 0;
    for (size_t i = a; i < b; i++) {
        if (!restore) {
            M->sX[i] = s->X[i]; M->sV[i] = s->V[i]; M->sA[i] = s->A[i]; M->sF[i] = s->F[i]; M->shA[i] = s->hA[i];
            M->smode[i] = s->mode[i];
        } else {
            s->X[i] = M->sX[i]; s->V[i] = M->sV[i]; s->A[i] = M->sA[i]; s->F[i] = M->sF[i]; s->hA[i] = M->shA[i];
            s->mode[i] = M->smode[i];
        }
    }
}

/* One located step. The whole chain is solved in the current modes; when blocks must switch, a long
 * chain (more than 2 w + 3 blocks, w the span beyond which a block's influence inside one step is
 * below rounding: M_hat's inverse decays like rho^distance) takes the step in those modes outside
 * clusters of w blocks either side of the switching ones, and each cluster takes it again on its
 * own, switches placed inside, with its outside neighbours as interpolated ghosts. A short chain,
 * stop_at_switch and the energy accounts take the located step on the whole chain. fast: step_fast's
 * result for this step (-1: it has solved the step in the current modes), or 0. */
COLD_CALL void chain_step_located(chain_model *M, chain_state *s, const double *vb, double t_end, double hh, double cw1,
                                   double sw1, int fast, chain_switch_fn fn, void *ctx, int stop_at_switch)
{
    const size_t n = M->n;
    /* a stiff step (several periods of the fastest mode) cannot place a switch: restarts with the
     * physical acceleration would feed the unresolved mode; the consistent test, which is stable,
     * takes it (as in the oscillator) */
    if (M->rate_max * hh > STIFF_STEP) {
        chain_step_lcp(M, s, vb, t_end, hh, fn, ctx, 1);
        return;
    }
    span G0 = chain_whole(M, s, vb, vb);
    if (fast == 0) {  /* else step_fast has solved the trial in the current modes */
        if (M->any_frozen) {
            for (size_t i = 0; i < n; i++) M->frozen[i] = 0;
            M->any_frozen = 0;
        }
        if (G0.vb && belt_sliver(M, s, &G0, t_end, hh)) return;
        for (size_t i = 0; i < n; i++) {
            M->st[i] = chain_held(M, s, i) ? 0 : s->mode[i];
            M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mlN[i];
        }
        M->sparse_rebase = n > 2 * M->w + 3 && !stop_at_switch && !M->energy;  /* (its clusters' own) */
        chain_trial(M, s, &G0, hh, cw1, sw1);
        M->sparse_rebase = 0;
        solve_modes(M, &G0);
        s->solves++;
    }
    M->ncand = 0;
    if (!G0.vb) { /* (the fixed support's loop as it was) */
        for (size_t i = 0; i < n; i++)
            if (chain_has_friction(M, i) && (switch_margin(M, s, i) <= 0.0 || ramp_breaks(M, s, &G0, i, t_end)))
                M->cand[M->ncand++] = i;
    } else {
        for (size_t i = 0; i < n; i++)
            if (chain_has_friction(M, i) && is_candidate(M, s, &G0, i, t_end)) M->cand[M->ncand++] = i;
    }
    if (M->ncand == 0) {  /* the warm basis solves the LCP: O(n), no pivot */
        chain_finish(M, s, &G0, M->Vt, M->Ft, t_end);
        for (size_t i = 0; i < n; i++)
            if (!chain_has_friction(M, i)) s->mode[i] = chain_sgn(s->V[i]);
        s->t = t_end;
        return;
    }
    s->pivot_steps++;
    const size_t w = M->w;
    if (stop_at_switch || M->energy || n <= 2 * w + 3) {
        located_span(M, s, &G0, t_end, hh, fn, ctx, stop_at_switch);
        return;
    }
    /* clusters [a, b) around the candidates, at least 3 blocks apart (distinct ghosts) */
    size_t nc = 0;
    for (size_t k = 0; k < M->ncand; k++) {
        const size_t c = M->cand[k], a = (c > w) ? c - w : 0, b = (c + w + 1 < n) ? c + w + 1 : n;
        if (nc > 0 && a <= M->clu[2 * nc - 1] + 2) M->clu[2 * nc - 1] = b;
        else { M->clu[2 * nc] = a; M->clu[2 * nc + 1] = b; nc++; }
    }
    for (size_t j = 0; j < nc; j++) {
        const size_t a = M->clu[2 * j], b = M->clu[2 * j + 1];
        save_blocks(M, s, (a > 0) ? a - 1 : 0, (b < n) ? b + 1 : n, 0);
    }
    /* everything in the current modes first */
    const double t_start = s->t;
    chain_finish(M, s, &G0, M->Vt, M->Ft, t_end);
    for (size_t i = 0; i < n; i++)
        if (!chain_has_friction(M, i)) s->mode[i] = chain_sgn(s->V[i]);
    for (size_t j = 0; j < nc && M->err == CHAIN_OK; j++) {
        span G;
        memset(&G, 0, sizeof G);
        G.vb = G.vrel = vb;
        G.a = M->clu[2 * j];
        G.b = M->clu[2 * j + 1];
        G.t_start = t_start;
        G.H = t_end - t_start;
        G.has[0] = G.a > 0;
        G.has[1] = G.b < n;
        G.idx[0] = G.a - (size_t)G.has[0];
        G.idx[1] = G.b;
        double A1[2] = {0.0, 0.0};
        for (int k = 0; k < 2; k++) {
            if (!G.has[k]) continue;
            const size_t g = G.idx[k];
            G.X0[k] = M->sX[g]; G.V0[k] = M->sV[g];
            G.X1[k] = s->X[g]; G.V1[k] = s->V[g];
            A1[k] = s->A[g];
        }
        save_blocks(M, s, G.a, G.b, 1);
        s->t = t_start;
        located_span(M, s, &G, t_end, hh, fn, ctx, 0);
        for (int k = 0; k < 2; k++) {
            if (!G.has[k]) continue;
            const size_t g = G.idx[k];
            s->X[g] = G.X1[k]; s->V[g] = G.V1[k]; s->A[g] = A1[k]; s->hA[g] = hh;
        }
    }
    s->t = t_end;
}
