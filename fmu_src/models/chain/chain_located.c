/* The chain's located scheme (method.md section 9): the basis solve of a trial (the kept
 * factorisation of a grid step's M_hat, or lcp_box_basis), the switch margins, the bracketed root
 * of the first switch, the switches and the consistent restart, spans and clusters with ghosts.
 * See chain_internal.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_internal.h"

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

static void solve_modes(chain_model *M, const span *G)
{
    if (M->cd == M->dF && G->a == 0 && G->b == M->n && !G->has[0] && !G->has[1]) {
        solve_kept(M);
        return;
    }
    const size_t lo = G->a - (size_t)G->has[0], hi = G->b + (size_t)G->has[1];
    /* l (set with st): Fb for held rows (a flag there), mu_k N for sliding ones, 0 without friction */
    lcp_box_basis(lo, hi, G->has[0], G->gV[0], G->has[1], G->gV[1], M->cd, M->ce, M->q, M->l, M->st, M->Vt, M->Ft,
               M->cp, M->dp);
}

/* How far block i is from its switch at the trial (> 0: not yet): s V for a sliding block (as the
 * oscillator's stop), F_b - |F| for a stuck one. */
static double switch_margin(const chain_model *M, const chain_state *s, size_t i)
{
    if (M->st[i] != 0) return s->mode[i] * M->Vt[i];
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
    chain_trial(M, s, c->G, x, cw, sw);
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
            if (immediate && s->V[i] == 0.0) M->frozen[i] = M->any_frozen = 1;
            s->V[i] = 0.0;
        }
    }
    M->ncand = nsw;
    chain_loads_at(M, s->t);  /* ramped inputs: the loads at the switch */
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
        if (dir != 0) s->A[i] = dir * fmax(fmax(dir * M->S[i], M->Fb[i]) - M->mukN[i], 0.0) / M->m[i];
    }
}

/* Block i stuck with X frozen and every neighbour at rest: its static force is its excitation
 * plus a constant, and its next breakaway after the stick phase's start is known in closed form
 * (friction.h, as the oscillator's); INFINITY when it does not apply. */
static double closed_breakaway(const chain_model *M, const chain_state *s, const span *G, size_t i, int *dir)
{
    if (M->ramped) return INFINITY;  /* the closed form holds for held inputs */
    for (int side = -1; side <= 1; side += 2) {
        if ((side < 0 && i == 0) || (side > 0 && i + 1 >= M->n)) continue;
        const size_t j = (side < 0) ? i - 1 : i + 1;
        const int inside = j >= G->a && j < G->b;
        if (!(chain_held(M, s, j) || (inside && M->frozen[j]))) return INFINITY;
    }
    return chain_block_breakaway(M, s, i, dir);
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
        for (size_t i = G->a; i < G->b; i++) {
            M->st[i] = (chain_held(M, s, i) || M->frozen[i]) ? 0 : s->mode[i];
            M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mukN[i];
        }
        double cw1, sw1;
        chain_phase_of(M, s, t_end, &cw1, &sw1);
        chain_trial(M, s, G, r, cw1, sw1);
        solve_modes(M, G);
        s->solves++;
        M->ncand = 0;
        for (size_t i = G->a; i < G->b; i++) {
            if (!chain_has_friction(M, i) || M->frozen[i]) continue;
            if (switch_margin(M, s, i) <= 0.0) M->cand[M->ncand++] = i;
        }
        if (M->ncand == 0) {  /* the warm basis solves the LCP: the whole remainder in these modes */
            chain_finish(M, s, G, M->Vt, M->Ft);
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
            const double t = (M->st[i] == 0) ? closed_breakaway(M, s, G, i, &dir) : -INFINITY;
            M->S[i] = t;
            tb = fmin(tb, t);
        }
        if (tb >= s->t && tb <= t_end) {
            const double ta = s->t, hs = tb - ta;
            if (hs > 0.0) {
                double c1w, s1w;
                chain_phase_of(M, s, tb, &c1w, &s1w);
                chain_trial(M, s, G, (tb == t_end) ? r : hs, c1w, s1w);
                solve_modes(M, G);
                s->solves++;
                chain_finish(M, s, G, M->Vt, M->Ft);
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
            glo = (M->st[i] != 0) ? fmin(glo, s->mode[i] * s->V[i]) : -INFINITY;
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
        const double hs = dfo_brent(min_margin, &mc, ta, lo, glo, hi, ghi);
        const double t1 = (hs >= r) ? t_end : ta + hs;
        double c1w, s1w;
        if (hs >= r) chain_phase_of(M, s, t_end, &c1w, &s1w);
        else { c1w = dfo_cos(M->omega * t1 + M->phi0); s1w = dfo_sin(M->omega * t1 + M->phi0); }
        chain_trial(M, s, G, hs, c1w, s1w);
        solve_modes(M, G);
        s->solves++;
        for (size_t k = 0; k < M->ncand; k++) {  /* a stopping block ends the sub-step at rest */
            const size_t i = M->cand[k];
            if (M->st[i] != 0 && switch_margin(M, s, i) <= 0.0) M->Vt[i] = 0.0;
        }
        chain_finish(M, s, G, M->Vt, M->Ft);
        s->t = (hs >= r) ? t_end : fmax(t1, nextafter(ta, INFINITY));
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
COLD_CALL void chain_step_located(chain_model *M, chain_state *s, double t_end, double hh, double cw1, double sw1,
                                   int fast, chain_switch_fn fn, void *ctx, int stop_at_switch)
{
    const size_t n = M->n;
    /* a stiff step (several periods of the fastest mode) cannot place a switch: restarts with the
     * physical acceleration would feed the unresolved mode; the consistent test, which is stable,
     * takes it (as in the oscillator) */
    if (M->rate_max * hh > STIFF_STEP) {
        chain_step_lcp(M, s, t_end, hh, fn, ctx, 1);
        return;
    }
    span G0 = chain_whole(M, s);
    if (fast == 0) {  /* else step_fast has solved the trial in the current modes */
        if (M->any_frozen) {
            for (size_t i = 0; i < n; i++) M->frozen[i] = 0;
            M->any_frozen = 0;
        }
        for (size_t i = 0; i < n; i++) {
            M->st[i] = chain_held(M, s, i) ? 0 : s->mode[i];
            M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mukN[i];
        }
        chain_trial(M, s, &G0, hh, cw1, sw1);
        solve_modes(M, &G0);
        s->solves++;
    }
    M->ncand = 0;
    for (size_t i = 0; i < n; i++)
        if (chain_has_friction(M, i) && switch_margin(M, s, i) <= 0.0) M->cand[M->ncand++] = i;
    if (M->ncand == 0) {  /* the warm basis solves the LCP: O(n), no pivot */
        chain_finish(M, s, &G0, M->Vt, M->Ft);
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
    chain_finish(M, s, &G0, M->Vt, M->Ft);
    for (size_t i = 0; i < n; i++)
        if (!chain_has_friction(M, i)) s->mode[i] = chain_sgn(s->V[i]);
    for (size_t j = 0; j < nc && M->err == CHAIN_OK; j++) {
        span G;
        memset(&G, 0, sizeof G);
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
