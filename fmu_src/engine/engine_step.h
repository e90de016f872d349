/* The engine's schemes as a template over the model's operators: included once by engine_generic.c with
 * the defaults below (the operators through eng_ops's function pointers, the sizes from the setup:
 * the public eng_* functions of engine.h), and by a model that wants its own operators inlined:
 * before including this file it defines, as macros of the engine E,
 *
 *   ENG_N(E), ENG_NC(E)          the sizes (a model with fixed sizes gives constants: the loops unroll)
 *   ENG_APPLY_K(E, x, y)         y = K x
 *   ENG_APPLY_C(E, v, y)         y = C v (read only where ENG_HAS_C(E))
 *   ENG_HAS_C(E)                 C is not 0
 *   ENG_APPLY_M(E, a, y)         y = M a
 *   ENG_ADD_MK(E, r, x, p)       optional: p_i += (M r)_i - (K x)_i, the products ENG_APPLY_M's and
 *                                ENG_APPLY_K's (one pass for the trial's p_hat; by default the two
 *                                operators and a loop)
 *   ENG_FACTOR(E, slot, cM, cC, cK), ENG_SOLVE(E, slot, b, x)   as eng_ops.factor and .solve
 *   ENG_HAS_FRICTION(E), ENG_FRICTION(E, P, what, mode, V1, f, pivots)   its friction solver
 *   ENG_HAS_BREAKAWAY(E), ENG_BREAKAWAY(E, s, in, Fb)   its closed-form breakaway (the stuck fast path)
 *   ENG_HELD_BASIS(E)            its friction solver takes the held solves of the mass slot (eng_sparse)
 *   ENG_HAS_STEP_HELD(E), ENG_STEP_HELD(E, F, s)   its fused step in the held pattern (eng_sparse)
 *   ENG_STEP_RUN(E, F, s)        that step within a run (F->run > 0; by default ENG_STEP_HELD): a model
 *                                may inline it into the run's loop alone
 *   ENG_HAS_CONTACT_BREAKAWAY(E), ENG_CONTACT_BREAKAWAY(E, j, s, in, Fb)   a held contact's breakaway
 *                                in closed form (eng_sparse)
 *   ENG_ROW_DOT(E, j, x)         w_j . x for the contact rows it knows (a slip; row_dot's arithmetic)
 *   ENG_OBSERVE(obs, ph, s)      the observer's call (obs->on_phase), for a model that inlines its own
 *   ENG_OBS_RUN, ENG_OBS_RUN_BEGIN(obs, R, s), ENG_OBS_RUN_PHASE(obs, R, ph, s), ENG_OBS_RUN_END(obs, R)
 *                                the observer over a run of fused steps: R, a local of type ENG_OBS_RUN,
 *                                set up by _BEGIN (obs may be NULL; s the state at the run's start, its
 *                                phases begin at or after s->t), each observed step's phase given to
 *                                _PHASE, R written back by _END when the run ends (a model keeps its
 *                                observables in registers over the run; by default R is unused and
 *                                _PHASE is ENG_OBSERVE)
 *   ENG_FUSED_N, ENG_FUSED_NC    the sizes as constants: the fused steps' state in local arrays
 *   ENG_FN(name), ENG_API        the names and linkage of the entry points (eng_start, eng_advance,
 *                                eng_new_inputs, eng_snap_target, eng_accelerations,
 *                                eng_contact_forces, eng_dense_friction): a prefix and static
 *
 * and gets the same schemes, their arithmetic in the same order: the same numbers as engine_generic.c's
 * with the same operators. The engine object is made by eng_create (engine.c) either way. Include
 * once per translation unit, after "dfo_fp.h". See engine.c's header for the functions' order. */
#include "dfo_inline.h"
#include "engine_private.h"

#ifndef ENG_FN
#define ENG_FN(name) name
#endif
#ifndef ENG_API
#define ENG_API
#endif
#ifndef ENG_N
#define ENG_N(E) ((E)->S.n)
#endif
#ifndef ENG_NC
#define ENG_NC(E) ((E)->S.nc)
#endif
#ifndef ENG_APPLY_K
#define ENG_APPLY_K(E, x, y) ((E)->S.ops.apply_K((E)->S.ops.ctx, (x), (y)))
#endif
#ifndef ENG_APPLY_C
#define ENG_APPLY_C(E, v, y) ((E)->S.ops.apply_C((E)->S.ops.ctx, (v), (y)))
#endif
#ifndef ENG_HAS_C
#define ENG_HAS_C(E) ((E)->S.ops.apply_C != NULL)
#endif
#ifndef ENG_HAS_JENKINS /* some contact is a Jenkins element (a model without any: 0, its code left out) */
#define ENG_HAS_JENKINS(E) ((E)->any_jenk)
#endif
#ifndef ENG_APPLY_M
#define ENG_APPLY_M(E, a, y) ((E)->S.ops.apply_M((E)->S.ops.ctx, (a), (y)))
#endif
#ifndef ENG_FACTOR
#define ENG_FACTOR(E, slot, cM, cC, cK) ((E)->S.ops.factor((E)->S.ops.ctx, (slot), (cM), (cC), (cK)))
#endif
#ifndef ENG_SOLVE
#define ENG_SOLVE(E, slot, b, x) ((E)->S.ops.solve((E)->S.ops.ctx, (slot), (b), (x)))
#endif
#ifndef ENG_HAS_FRICTION
#define ENG_HAS_FRICTION(E) ((E)->S.ops.friction != NULL)
#endif
#ifndef ENG_FRICTION
#define ENG_FRICTION(E, P, what, mode, V1, f, pivots) \
    ((E)->S.ops.friction((E)->S.ops.ctx, (P), (what), (mode), (V1), (f), (pivots)))
#endif
#ifndef ENG_HELD_BASIS
#define ENG_HELD_BASIS(E) ((E)->S.sparse && (E)->S.sparse->held_basis)
#endif
#ifndef ENG_HAS_STEP_HELD
#define ENG_HAS_STEP_HELD(E) ((E)->S.sparse && (E)->S.sparse->step_held)
#endif
#ifndef ENG_STEP_HELD
#define ENG_STEP_HELD(E, F, s) ((E)->S.sparse->step_held((E)->S.ops.ctx, (F), (s)))
#endif
#ifndef ENG_STEP_RUN
#define ENG_STEP_RUN(E, F, s) ENG_STEP_HELD(E, F, s)
#endif
#ifndef ENG_HAS_CONTACT_BREAKAWAY
#define ENG_HAS_CONTACT_BREAKAWAY(E) ((E)->S.sparse && (E)->S.sparse->contact_breakaway)
#endif
#ifndef ENG_CONTACT_BREAKAWAY
#define ENG_CONTACT_BREAKAWAY(E, j, s, in, Fb) \
    ((E)->S.sparse->contact_breakaway((E)->S.ops.ctx, (j), &(E)->S.exc, (s), (in), (Fb)))
#endif
#ifndef ENG_HAS_BREAKAWAY
#define ENG_HAS_BREAKAWAY(E) ((E)->S.ops.breakaway != NULL)
#endif
#ifndef ENG_BREAKAWAY
#define ENG_BREAKAWAY(E, s, in, Fb) ((E)->S.ops.breakaway((E)->S.ops.ctx, &(E)->S.exc, (s), (in), (Fb)))
#endif

#ifndef ENG_TANGENTS /* the located map's tangent propagated (eng_setup.tangent; a model without: 0) */
#define ENG_TANGENTS(E) ((E)->S.tangent)
#endif
#ifndef ENG_ROW_DOT
#define ENG_ROW_DOT(E, j, x) row_dot(&(E)->S.rows[(j)], (x))
#endif
#ifndef ENG_OBSERVE
#define ENG_OBSERVE(obs, ph, s) ((obs)->on_phase((obs)->ctx, (ph), (s)))
#endif
#ifndef ENG_OBS_RUN
#define ENG_OBS_RUN int
#define ENG_OBS_RUN_BEGIN(obs, R, s) ((void)(obs), (void)(s), (void)((R) = 0))
#define ENG_OBS_RUN_PHASE(obs, R, ph, s) ((void)(R), ENG_OBSERVE(obs, ph, s))
#define ENG_OBS_RUN_END(obs, R) ((void)(obs), (void)(R))
#endif

/* A model whose sizes are constants (ENG_FUSED_N, ENG_FUSED_NC): the fused steps' and the trials'
 * vectors in local arrays, which the compiler keeps in registers (stores through the engine's arrays
 * would make it reload every double it reads after them). */
#if defined(ENG_FUSED_N) && defined(ENG_FUSED_NC)
#define ENG_FUSED_LOCAL 1
#else
#define ENG_FUSED_LOCAL 0
#endif

/* The functions of every step: inline where the compiler finds it pays (gcc -O3 inlines them into
 * the fused loops by itself: forcing it, always_inline, measured 0.93x to 1.05x the same step
 * cost on bench_stepper and bench_chain, and made the files that include this one about five
 * times slower to compile). The cold paths are kept out of the loops. The same arithmetic either
 * way. */
#define ENG_HOT inline
#define ENG_COLD DFO_NO_INLINE

/* ---- small algebra --------------------------------------------------------------------------- */

static int sgn(double x) { return (x > 0.0) - (x < 0.0); }

/* fmax(a, b) and fmin(a, b) for b not NaN (a NaN a gives b, as fmax and fmin do), and f clamped to
 * [-lim, lim] (lim > 0 not NaN; a NaN f gives lim) as fmax(-lim, fmin(lim, f)) does: comparisons,
 * the same values; fmin and fmax are library calls without -ffinite-math-only, on the step's path. */
static ENG_HOT double max_b(double a, double b) { return (a > b) ? a : b; }
static ENG_HOT double min_b(double a, double b) { return (a < b) ? a : b; }
static ENG_HOT double clamp_lim(double f, double lim)
{
    const double u = min_b(f, lim);
    return max_b(u, -lim);
}

/* w_j . x */
static double row_dot(const eng_row *R, const double *x)
{
    double d = 0.0;
    for (size_t k = 0; k < R->nnz; k++) d += R->w[k] * x[R->idx[k]];
    return d;
}

/* sum |w_k x_k| over the row (the terms of w . x) */
static double row_abs_dot(const eng_row *R, const double *x)
{
    double d = 0.0;
    for (size_t k = 0; k < R->nnz; k++) d += fabs(R->w[k] * x[R->idx[k]]);
    return d;
}

/* y += c w_j */
static void row_axpy(const eng_row *R, double c, double *y)
{
    for (size_t k = 0; k < R->nnz; k++) y[R->idx[k]] += c * R->w[k];
}

/* Cholesky of the m x m matrix a (row-major, leading dimension ld) into L (lower, same layout); a
 * pivot below DEPENDENT_REL of its diagonal marks a dependent row: dep[i] = 1, its row and column
 * left out (its unknown 0: the minimum-norm choice among the solutions of a semi-definite system). */
static void chol(size_t m, const double *a, size_t ld, double *L, int *dep)
{
    for (size_t i = 0; i < m; i++) {
        dep[i] = 0;
        for (size_t j = 0; j <= i; j++) {
            double s = a[i * ld + j];
            for (size_t k = 0; k < j; k++) s -= L[i * ld + k] * L[j * ld + k];
            if (i == j) {
                if (!(s > DEPENDENT_REL * fabs(a[i * ld + i])) || !(s > 0.0)) {
                    dep[i] = 1;
                    for (size_t k = 0; k <= i; k++) L[i * ld + k] = 0.0;
                } else {
                    L[i * ld + i] = sqrt(s);
                }
            } else {
                L[i * ld + j] = dep[j] ? 0.0 : s / L[j * ld + j];
            }
        }
    }
}

static void chol_solve(size_t m, const double *L, size_t ld, const int *dep, const double *b, double *x)
{
    for (size_t i = 0; i < m; i++) {
        if (dep[i]) { x[i] = 0.0; continue; }
        double s = b[i];
        for (size_t k = 0; k < i; k++) s -= L[i * ld + k] * x[k];
        x[i] = s / L[i * ld + i];
    }
    for (size_t i = m; i-- > 0;) {
        if (dep[i]) continue;
        double s = x[i];
        for (size_t k = i + 1; k < m; k++) s -= L[k * ld + i] * x[k];
        x[i] = s / L[i * ld + i];
    }
}

/* ---- loads, excitation, slip --------------------------------------------------------------- */

static int ramped(const eng_inputs *in)
{
    if (!in) return 0;
    /* (the four tests without branches: a path asks for it at every phase) */
    return (in->dF_ext[0] != NULL) | (in->dF_ext[1] != NULL) | (in->dN_ext[0] != NULL) | (in->dN_ext[1] != NULL);
}

static double poly_at(const double *u, const double *const *du, const eng_inputs *in, size_t i, double t)
{
    const double tau = t - in->t_ref;
    const double u1 = du[0] ? du[0][i] : 0.0, u2 = du[1] ? du[1][i] : 0.0;
    return (u ? u[i] : 0.0) + tau * (u1 + 0.5 * tau * u2);
}

static double poly_rate(const double *const *du, const eng_inputs *in, size_t i, double t)
{
    const double tau = t - in->t_ref;
    return (du[0] ? du[0][i] : 0.0) + tau * (du[1] ? du[1][i] : 0.0);
}

/* The loads of the inputs at t (their polynomials' values with a ramp) into u, Nn, mukN, Fb, mlN,
 * and the belts into vb. Held inputs give the same loads at every t: taken once per public call
 * (loads_for: the inputs they are of, cleared on entry to every public function). */
static ENG_HOT void loads_at(eng *E, const eng_inputs *in, double t)
{
    const eng_setup *S = &E->S;
    if (in && in == E->loads_for) return;
    const int rp = ramped(in);
    int fr = 1;
    E->loads_for = rp ? NULL : in;
    for (size_t i = 0; i < ENG_N(E); i++)
        E->u[i] = !in ? 0.0 : rp ? poly_at(in->F_ext, in->dF_ext, in, i, t) : (in->F_ext ? in->F_ext[i] : 0.0);
    for (size_t j = 0; j < ENG_NC(E); j++) {
        const double Ne = !in ? 0.0 : rp ? poly_at(in->N_ext, in->dN_ext, in, j, t) : (in->N_ext ? in->N_ext[j] : 0.0);
        const double N = fmax(S->N[j] + Ne, 0.0);
        E->Nn[j] = N;
        E->mukN[j] = S->mu_k[j] * N;
        E->Fb[j] = E->mu_b[j] * N;
        const int strib = S->law && S->law[j].law == DFO_LAW_STRIBECK;
        E->mlN[j] = strib ? fmin(S->law[j].mu_s, S->law[j].mu_k) * N : E->mukN[j];
        fr &= E->Fb[j] > 0.0;
    }
    E->all_friction = fr;
    E->vb = (in && in->v_belt) ? in->v_belt : E->zero_nc;
}

static int has_friction(const eng *E, size_t j) { return E->Fb[j] > 0.0; }

static int is_strib(const eng *E, size_t j) { return E->S.law && E->S.law[j].law == DFO_LAW_STRIBECK; }

/* contact j is a Jenkins element (eng_setup.k_t) */
static int is_jenk(const eng *E, size_t j) { return ENG_HAS_JENKINS(E) && E->S.k_t[j] > 0.0; }

/* a Jenkins contact's spring force -k_t (w_j . X - s_j) at the state */
static double jenk_force(const eng *E, size_t j, const eng_state *s)
{
    return -E->S.k_t[j] * (row_dot(&E->S.rows[j], s->X) - s->slider[j]);
}

/* The kinetic magnitude of contact j sliding at slip speed u >= 0 (Coulomb: mu_k N). */
static double slide_mag(const eng *E, size_t j, double u)
{
    return is_strib(E, j) ? E->Nn[j] * dfo_friction_mu(&E->S.law[j], u) : E->mukN[j];
}

/* cos and sin of omega t + phi0, evaluated (dmath), the last time's kept (a switch's time is asked
 * for several times: the rest rule, the restart, the re-basing's accelerations and jerks); only the
 * ones asked for (want_c, want_s: the excitation's P reads cos where Pc is given, sin where Ps is;
 * its rate reads both), each kept for the last time it was evaluated */
static void trig_at(eng *E, double t, double *cw, double *sw, int want_c, int want_s)
{
    const double th = E->S.exc.omega * t + E->S.exc.phi0;
    if (want_c && t != E->trig_tc) {
        E->trig_tc = t;
        E->trig_c = dfo_cos(th);
    }
    if (want_s && t != E->trig_ts) {
        E->trig_ts = t;
        E->trig_s = dfo_sin(th);
    }
    *cw = want_c ? E->trig_c : 0.0;
    *sw = want_s ? E->trig_s : 0.0;
}

/* cos and sin of omega t + phi0: from the state's cache when t is its grid point, else evaluated */
static ENG_HOT void phase_of(eng *E, const eng_state *s, double t, double *cw, double *sw)
{
    if (s->exc_n >= 0 && t == s->t0 + (double)s->exc_n * E->S.h) {
        *cw = dfo_clamp1(s->exc_c);
        *sw = dfo_clamp1(s->exc_s);
        return;
    }
    trig_at(E, t, cw, sw, E->S.exc.Pc != NULL, E->S.exc.Ps != NULL);
}

/* P(t) + F_ext into out (the loads already at t) */
static ENG_HOT void applied_at(eng *E, const eng_state *s, double t, double *out)
{
    const eng_harmonic *H = &E->S.exc;
    double cw = 0.0, sw = 0.0;
    if (H->Pc || H->Ps) phase_of(E, s, t, &cw, &sw);
    const size_t n = ENG_N(E);
    const double *const u = E->u, *const Pc = H->Pc, *const Ps = H->Ps;
    /* (the arrays' tests out of the loop: p = u, + Pc cw, - Ps sw as given) */
    if (Pc && Ps)
        for (size_t i = 0; i < n; i++) out[i] = (u[i] + Pc[i] * cw) - Ps[i] * sw;
    else if (Pc)
        for (size_t i = 0; i < n; i++) out[i] = u[i] + Pc[i] * cw;
    else if (Ps)
        for (size_t i = 0; i < n; i++) out[i] = u[i] - Ps[i] * sw;
    else
        for (size_t i = 0; i < n; i++) out[i] = u[i];
}

/* dP/dt + dF_ext/dt at t into out */
static void applied_rate(eng *E, const eng_inputs *in, double t, double *out)
{
    const eng_harmonic *H = &E->S.exc;
    double cw, sw;
    trig_at(E, t, &cw, &sw, H->Ps != NULL, H->Pc != NULL); /* (only the ones it reads) */
    const int rp = ramped(in);
    for (size_t i = 0; i < ENG_N(E); i++) {
        double p = rp ? poly_rate(in->dF_ext, in, i, t) : 0.0;
        if (H->Pc) p -= H->Pc[i] * H->omega * sw;
        if (H->Ps) p -= H->Ps[i] * H->omega * cw;
        out[i] = p;
    }
}

/* contact j's slip velocity w_j . V - vb_j */
static ENG_HOT double slip(const eng *E, size_t j, const double *V) { return ENG_ROW_DOT(E, j, V) - E->vb[j]; }

/* Factor slot with the coefficients, unless it holds them already. */
static ENG_HOT int factor_slot(eng *E, int slot, double cM, double cC, double cK)
{
    if (!ENG_HAS_C(E)) cC = 0.0;
    double *c = E->slot_c[slot];
    if (E->slot_ok[slot] && c[0] == cM && c[1] == cC && c[2] == cK) return 1;
    E->slot_ok[slot] = ENG_FACTOR(E, slot, cM, cC, cK);
    for (size_t j = 0; j < ENG_NC(E); j++) E->cok[(size_t)slot * ENG_NC(E) + j] = 0; /* its columns anew */
    if (slot == ENG_SLOT_GRID) E->gd_ok = 0; /* and its D^-1 */
    c[0] = cM;
    c[1] = cC;
    c[2] = cK;
    return E->slot_ok[slot];
}

/* The model's coupling operators for slot (eng_setup.coupling, where it serves the slot), or NULL: the
 * columns. */
static inline const eng_coupling *coupling_of(const eng *E, int slot)
{
    const eng_coupling *c = E->S.coupling;
    return (c && ((c->slots >> slot) & 1)) ? c : NULL;
}

/* colp[a] := A_slot^-1 w_j for the selected contacts j = sel[a], a < m, each solved once per
 * factorisation of the slot. */
static void columns(eng *E, int slot, size_t m)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    for (size_t a = 0; a < m; a++) {
        const size_t j = (size_t)E->sel[a];
        double *col = E->ccol + ((size_t)slot * nc + j) * n;
        int *done = &E->cok[(size_t)slot * nc + j];
        if (!*done) {
            for (size_t i = 0; i < n; i++) col[i] = 0.0;
            row_axpy(&S->rows[j], 1.0, col);
            ENG_SOLVE(E, slot, col, col);
            *done = 1;
        }
        E->colp[a] = col;
    }
}

/* ---- constrained solves ------------------------------------------------------------------- */

/* The held contacts sel[0 .. m-1] whose rows are dependent (dep[] from chol of their Delassus matrix
 * D, factor L): their forces are not unique (the basic ones fb, 0 on the dependent
 * rows, plus any vector of D's null space). The rule: the forces that minimise
 * sum_a sqrt(D_aa) f_a^2 / F_b,a, so that contacts along one direction (rows that are multiples of
 * one another) each carry the same share of their limits: they reach their limits together and the
 * group holds up to the sum of its limits (method.md section 13). The null space from the factor:
 * a dependent row i's vector e_i - beta, D_II beta = D_Ii over the independent rows I. Returns fb
 * when no row is dependent, else the shared forces (in E->lz; scratch: E->lM, E->lq, E->lw, the dense
 * LCP's, idle while a basis is solved). */
static const double *dependent_share(eng *E, size_t m, const int *sel, const double *D, const double *L,
                                     const int *dep, const double *fb)
{
    size_t d = 0;
    for (size_t a = 0; a < m; a++) d += dep[a] != 0;
    if (d == 0) return fb;
    const size_t nc = ENG_NC(E);
    double *N = E->lM, *G = E->lM + m * d, *GL = G + d * d, *col = E->lw, *z = E->lq, *g = E->lq + nc;
    double *out = E->lz, *c = E->lw + nc;
    int *gdep = E->zb;
    for (size_t a = 0, k = 0; a < m; a++) { /* N's columns; the weights c_a */
        const double fl = E->Fb[sel[a]], daa = D[a * m + a];
        c[a] = sqrt(daa > 0.0 ? daa : 0.0) / (fl > 0.0 ? fl : DBL_EPSILON);
        if (!dep[a]) continue;
        for (size_t b = 0; b < m; b++) col[b] = D[b * m + a];
        chol_solve(m, L, m, dep, col, col);
        for (size_t b = 0; b < m; b++) N[b * d + k] = ((b == a) ? 1.0 : 0.0) - col[b];
        k++;
    }
    for (size_t p = 0; p < d; p++) { /* G = N' C N, g = -N' C fb */
        double s = 0.0;
        for (size_t b = 0; b < m; b++) s -= N[b * d + p] * c[b] * fb[b];
        g[p] = s;
        for (size_t q = 0; q <= p; q++) {
            double t = 0.0;
            for (size_t b = 0; b < m; b++) t += N[b * d + p] * c[b] * N[b * d + q];
            G[p * d + q] = G[q * d + p] = t;
        }
    }
    chol(d, G, d, GL, gdep);
    chol_solve(d, GL, d, gdep, g, z);
    for (size_t b = 0; b < m; b++) {
        double s = fb[b];
        for (size_t p = 0; p < d; p++) s += N[b * d + p] * z[p];
        out[b] = s;
    }
    return out;
}

/* y = A_slot^-1 (r + W_S' f_S) with W_S y = target_S, S the contacts with held[j]; f_S out in
 * f (other entries untouched). m: |S|. Dense: the columns A^-1 w_j of S (or the model's coupling
 * operators, eng_setup.coupling), their Delassus matrix by Cholesky. Uses cols, D, Lc, rhs, sol, sel. */
static void csolve(eng *E, int slot, const double *r, const int *held, const double *target, const double *comp,
                   double *y, double *f)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    ENG_SOLVE(E, slot, r, y);
    if (n == 1 && nc == 1) { /* one DOF, one contact: the steps below in scalars, the same arithmetic */
        if (!held[0]) return;
        const double w = S->rows[0].w[0];
        double col = 0.0 + 1.0 * w; /* row_axpy into zeros, then the solve */
        ENG_SOLVE(E, slot, &col, &col);
        const double D = (0.0 + w * col) + (comp ? comp[0] : 0.0), rhs = target[0] - (0.0 + w * y[0]);
        double x = 0.0;
        if (!(!(D > DEPENDENT_REL * fabs(D)) || !(D > 0.0))) { /* chol's test of a dependent row */
            const double L = sqrt(D);
            x = rhs / L;
            x = x / L;
        }
        y[0] += col * x;
        f[0] = x;
        return;
    }
    size_t m = 0;
    for (size_t j = 0; j < nc; j++)
        if (held[j]) E->sel[m++] = (int)j;
    if (m == 0) return;
    const eng_coupling *Cp = coupling_of(E, slot);
    if (Cp) /* the model's Delassus matrix (no columns) */
        Cp->delassus(Cp->ctx, slot, E->sel, m, E->D);
    else
        columns(E, slot, m);
    for (size_t a = 0; a < m; a++) {
        const eng_row *Ra = &S->rows[E->sel[a]];
        if (!Cp)
            for (size_t c = 0; c <= a; c++) E->D[a * m + c] = E->D[c * m + a] = row_dot(Ra, E->colp[c]);
        if (comp) E->D[a * m + a] += comp[E->sel[a]];
        E->rhs[a] = target[E->sel[a]] - row_dot(Ra, y);
    }
    int *dep = E->st2;
    chol(m, E->D, m, E->Lc, dep);
    chol_solve(m, E->Lc, m, dep, E->rhs, E->sol);
    /* the response from the basic forces; the forces shared where rows are dependent (the response is
     * the same: the shares differ by a vector W_S' maps to 0) */
    const double *fs = dependent_share(E, m, E->sel, E->D, E->Lc, dep, E->sol);
    if (Cp) { /* y += A^-1 W_S' f_S */
        Cp->respond(Cp->ctx, slot, E->sel, m, E->sol, y);
        for (size_t a = 0; a < m; a++) f[E->sel[a]] = fs[a];
        return;
    }
    for (size_t a = 0; a < m; a++) {
        const double fa = E->sol[a];
        const double *col = E->colp[a];
        for (size_t i = 0; i < n; i++) y[i] += col[i] * fa;
        f[E->sel[a]] = fs[a];
    }
}

/* csolve on the mass slot with target 0: y = M^-1 (r + W_H' f_H), W_H y = 0 on the contacts with
 * held[j] (f_H out in f, other entries untouched); through the model's friction solver where it
 * offers the held basis solve (eng_sparse.held_basis), else csolve's Delassus matrix. */
static void held_solve(eng *E, const double *r, const int *held, double *y, double *f)
{
    factor_slot(E, ENG_SLOT_MASS, 1.0, 0.0, 0.0);
    if (!(ENG_HAS_FRICTION(E) && ENG_HELD_BASIS(E))) {
        csolve(E, ENG_SLOT_MASS, r, held, E->zero_nc, NULL, y, f);
        return;
    }
    const size_t nc = ENG_NC(E);
    for (size_t j = 0; j < nc; j++) {
        E->hlim[j] = dfo_select(held[j], E->Fb[j], 0.0);
        E->hmode[j] = !held[j];
    }
    eng_problem P;
    P.slot = ENG_SLOT_MASS;
    P.h = 0.0;
    P.cM = 1.0;
    P.cC = P.cK = 0.0;
    P.p_hat = r;
    P.vb = E->zero_nc;
    P.limit = E->hlim;
    P.N = E->Nn;
    P.law = NULL;
    P.comp = NULL;
    (void)ENG_FRICTION(E, &P, ENG_SOLVE_BASIS, E->hmode, y, E->hf, NULL);
    for (size_t j = 0; j < nc; j++) f[j] = dfo_select(held[j], E->hf[j], f[j]);
}

/* ---- a span's ghosts (a sub-engine's: E->ghost) ------------------------------------------------ */

/* Ghost i's cubic Hermite interpolation at tau after the step's start: position, velocity,
 * acceleration, jerk (any may be NULL). */
static void ghost_at(const eng *E, size_t i, double tau, double *x, double *v, double *a, double *jk)
{
    const double H = E->gH, r = tau / H, dx = E->gX1[i] - E->gX0[i], v0 = E->gV0[i], v1 = E->gV1[i];
    if (x) *x = E->gX0[i] + v0 * H * (r * r * r - 2.0 * r * r + r) + dx * (3.0 * r * r - 2.0 * r * r * r) +
                v1 * H * (r * r * r - r * r);
    if (v) *v = v0 * (3.0 * r * r - 4.0 * r + 1.0) + dx / H * (6.0 * r - 6.0 * r * r) + v1 * (3.0 * r * r - 2.0 * r);
    if (a) *a = (v0 * (6.0 * r - 4.0) + dx / H * (6.0 - 12.0 * r) + v1 * (6.0 * r - 2.0)) / H;
    if (jk) *jk = 6.0 * (v0 + v1 - 2.0 * dx / H) / (H * H);
}

/* The ghosts' states at the state's time, written into it. */
static void ghosts_now(const eng *E, eng_state *s)
{
    for (size_t k = 0; k < E->ngh; k++) {
        const size_t i = E->gidx[k];
        ghost_at(E, i, s->t - E->gt0, &s->X[i], &s->V[i], &s->A[i], NULL);
    }
}

/* Physical accelerations at the state in the modes mode[]: M a = P + F_ext - K X - C V + W' f,
 * sliding contacts' f their kinetic force at their slip speed, held ones (mode 0 with friction)
 * solved for slip acceleration 0. f out (nc), a out (n). The loads at t must be set. */
/* r -= K x + C v (K first, then C where there is one; y: scratch) */
static ENG_HOT void minus_kc(eng *E, const double *x, const double *v, double *r, double *y)
{
    const size_t n = ENG_N(E);
    ENG_APPLY_K(E, x, y);
    for (size_t i = 0; i < n; i++) r[i] -= y[i];
    if (ENG_HAS_C(E)) {
        ENG_APPLY_C(E, v, y);
        for (size_t i = 0; i < n; i++) r[i] -= y[i];
    }
}

static void phys_accel(eng *E, const eng_state *s, double t, const int *mode, double *a, double *f)
{
    const eng_setup *S = &E->S;
    const size_t nc = ENG_NC(E);
    double *r = E->r, *y = E->y;
    applied_at(E, s, t, r);
    minus_kc(E, s->X, s->V, r, y);
    for (size_t j = 0; j < nc; j++) {
        E->held[j] = mode[j] == 0 && has_friction(E, j);
        f[j] = 0.0;
        if (is_jenk(E, j)) { /* a spring (stuck) or the kinetic force (sliding): never held */
            E->held[j] = 0;
            if (has_friction(E, j)) f[j] = (mode[j] == 0) ? jenk_force(E, j, s) : -mode[j] * E->mukN[j];
            row_axpy(&S->rows[j], f[j], r);
            continue;
        }
        if (has_friction(E, j) && mode[j] != 0) {
            f[j] = -mode[j] * slide_mag(E, j, fabs(slip(E, j, s->V)));
            row_axpy(&S->rows[j], f[j], r);
        }
    }
    if (E->ghost) /* a ghost's acceleration is prescribed (Dirichlet: the solver returns it) */
        for (size_t k = 0; k < E->ngh; k++) r[E->gidx[k]] = s->A[E->gidx[k]];
    held_solve(E, r, E->held, a, f);
}

/* Jerks x''' at the state in its modes (held contacts' slip jerk 0), from the time derivative of the
 * equation of motion with the inputs' rates; a: the physical accelerations (read only with damping
 * or a sliding law: rebase computes them only then). Into j. */
static void jerks(eng *E, const eng_inputs *in, const eng_state *s, const double *a, double *jk)
{
    const eng_setup *S = &E->S;
    const size_t nc = ENG_NC(E);
    double *r = E->r, *y = E->y;
    applied_rate(E, in, s->t, r);
    minus_kc(E, s->V, a, r, y);
    const int rp = ramped(in);
    for (size_t j = 0; j < nc; j++) {
        E->held[j] = s->mode[j] == 0 && has_friction(E, j) && !is_jenk(E, j);
        if (is_jenk(E, j) && has_friction(E, j) && s->mode[j] == 0) { /* the spring's rate */
            row_axpy(&S->rows[j], -S->k_t[j] * slip(E, j, s->V), r);
            continue;
        }
        if (!has_friction(E, j) || s->mode[j] == 0) continue;
        double df = 0.0;
        if (rp) { /* d(mu N)/dt of the normal force's rate */
            const double Ne = poly_at(in->N_ext, in->dN_ext, in, j, s->t);
            const double dN = (S->N[j] + Ne > 0.0) ? poly_rate(in->dN_ext, in, j, s->t) : 0.0;
            df -= s->mode[j] * (is_strib(E, j) ? dfo_friction_mu(&S->law[j], fabs(slip(E, j, s->V))) : S->mu_k[j]) * dN;
        }
        if (is_strib(E, j)) { /* -mode N mu'(u) du/dt, u = mode (w . v - vb) */
            const double u = fabs(slip(E, j, s->V));
            df -= E->Nn[j] * dfo_friction_dmu(&S->law[j], u) * row_dot(&S->rows[j], a);
        }
        row_axpy(&S->rows[j], df, r);
    }
    if (E->ghost)
        for (size_t k = 0; k < E->ngh; k++) ghost_at(E, E->gidx[k], s->t - E->gt0, NULL, NULL, NULL, &r[E->gidx[k]]);
    held_solve(E, r, E->held, jk, E->f2);
}

/* ---- dense friction (the default solver) -------------------------------------------------- */

/* Newton on the Stribeck contacts sliding in mode[] (with the held ones), the others' forces
 * fixed: f_T = -m N mu(max(m v_T, 0)), v = W V1 - vb, V1 = M_hat^-1 (p_hat + W' f); a held
 * contact's slip v + comp_j f_j = 0 (P->comp: a stuck Jenkins element's spring; NULL: none). */
static eng_status stribeck_newton(eng *E, const eng_problem *P, const int *mode, double *V1, double *f)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    /* the set: held contacts and sliding Stribeck ones */
    size_t m = 0;
    for (size_t j = 0; j < nc; j++) {
        const int held = mode[j] == 0 && P->limit[j] > 0.0;
        const int tj = mode[j] != 0 && P->limit[j] > 0.0 && P->law[j].law == DFO_LAW_STRIBECK;
        if (held || tj) E->sel[m++] = (int)j;
    }
    /* columns A^-1 w_j and D of the set; base velocity V0 = A^-1 (p_hat + W' f_other) */
    double *V0 = E->y2;
    for (size_t i = 0; i < n; i++) E->r[i] = P->p_hat[i];
    for (size_t j = 0; j < nc; j++) {
        int in = 0;
        for (size_t a = 0; a < m; a++) in |= E->sel[a] == (int)j;
        if (!in && P->limit[j] > 0.0 && mode[j] != 0) row_axpy(&S->rows[j], f[j], E->r);
    }
    ENG_SOLVE(E, P->slot, E->r, V0);
    const eng_coupling *Cp = coupling_of(E, P->slot);
    if (Cp) {
        Cp->delassus(Cp->ctx, P->slot, E->sel, m, E->D);
    } else {
        columns(E, P->slot, m);
        for (size_t a = 0; a < m; a++)
            for (size_t c = 0; c < m; c++) E->D[a * m + c] = row_dot(&S->rows[E->sel[a]], E->colp[c]);
    }
    double *fs = E->sol, *dlt = E->rhs;
    for (size_t a = 0; a < m; a++) fs[a] = f[E->sel[a]];
    int done = 0;
    for (int it = 0; it < NEWTON_ITERS && !done; it++) {
        /* residual and Jacobian (dense m x m, Gaussian elimination with partial pivoting) */
        for (size_t a = 0; a < m; a++) {
            const size_t j = (size_t)E->sel[a];
            double v = row_dot(&S->rows[j], V0) - (P->vb ? P->vb[j] : 0.0);
            for (size_t c = 0; c < m; c++) v += E->D[a * m + c] * fs[c];
            if (mode[j] == 0) { /* held: slip 0, a Jenkins element's with its spring's comp_j f_j */
                const double cj = P->comp ? P->comp[j] : 0.0;
                E->res[a] = v + cj * fs[a];
                for (size_t c = 0; c < m; c++) E->Jn[a * m + c] = E->D[a * m + c];
                E->Jn[a * m + a] += cj;
            } else {
                const double u = mode[j] * v, up = fmax(u, 0.0);
                E->res[a] = fs[a] + mode[j] * P->N[j] * dfo_friction_mu(&P->law[j], up);
                const double dmu = (u > 0.0) ? dfo_friction_dmu(&P->law[j], u) : 0.0;
                for (size_t c = 0; c < m; c++)
                    E->Jn[a * m + c] = ((a == c) ? 1.0 : 0.0) + P->N[j] * dmu * E->D[a * m + c];
            }
        }
        for (size_t a = 0; a < m; a++) dlt[a] = E->res[a];
        for (size_t k = 0; k < m; k++) {
            size_t p = k;
            for (size_t i = k + 1; i < m; i++)
                if (fabs(E->Jn[i * m + k]) > fabs(E->Jn[p * m + k])) p = i;
            if (p != k) {
                for (size_t c = 0; c < m; c++) {
                    const double t = E->Jn[k * m + c]; E->Jn[k * m + c] = E->Jn[p * m + c]; E->Jn[p * m + c] = t;
                }
                const double t = dlt[k]; dlt[k] = dlt[p]; dlt[p] = t;
            }
            const double piv = E->Jn[k * m + k];
            if (piv == 0.0) return ENG_ERR_FRICTION;
            for (size_t i = k + 1; i < m; i++) {
                const double q = E->Jn[i * m + k] / piv;
                for (size_t c = k; c < m; c++) E->Jn[i * m + c] -= q * E->Jn[k * m + c];
                dlt[i] -= q * dlt[k];
            }
        }
        double dmax = 0.0, fmx = 0.0;
        for (size_t k = m; k-- > 0;) {
            double s = dlt[k];
            for (size_t c = k + 1; c < m; c++) s -= E->Jn[k * m + c] * dlt[c];
            dlt[k] = s / E->Jn[k * m + k];
        }
        for (size_t a = 0; a < m; a++) {
            fs[a] -= dlt[a];
            dmax = fmax(dmax, fabs(dlt[a]));
            fmx = fmax(fmx, fabs(fs[a]));
        }
        done = dmax <= 4.0 * DBL_EPSILON * fmx || dmax == 0.0;
    }
    if (!done) return ENG_ERR_FRICTION;
    for (size_t i = 0; i < n; i++) V1[i] = V0[i];
    if (Cp) {
        for (size_t a = 0; a < m; a++) f[E->sel[a]] = fs[a];
        Cp->respond(Cp->ctx, P->slot, E->sel, m, fs, V1);
        return ENG_OK;
    }
    for (size_t a = 0; a < m; a++) {
        f[E->sel[a]] = fs[a];
        const double *col = E->colp[a];
        for (size_t i = 0; i < n; i++) V1[i] += col[i] * fs[a];
    }
    return ENG_OK;
}

/* The basis solve: sliding contacts at -mode limit, held ones at slip 0 (target vb). */
static eng_status dense_basis(eng *E, const eng_problem *P, const int *mode, double *V1, double *f)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    for (size_t i = 0; i < n; i++) E->rb[i] = P->p_hat[i];
    int strib = 0;
    for (size_t j = 0; j < nc; j++) {
        E->held[j] = mode[j] == 0 && P->limit[j] > 0.0;
        f[j] = 0.0;
        if (P->limit[j] > 0.0 && mode[j] != 0) {
            f[j] = -mode[j] * P->limit[j];
            row_axpy(&S->rows[j], f[j], E->rb);
            strib |= P->law && P->law[j].law == DFO_LAW_STRIBECK;
        }
    }
    csolve(E, P->slot, E->rb, E->held, P->vb ? P->vb : E->zero_nc, P->comp, V1, f);
    /* a held contact on one DOF: its slip exactly 0 (a compliant one's is not) */
    for (size_t j = 0; j < nc; j++) {
        const eng_row *R = &S->rows[j];
        if (E->held[j] && R->nnz == 1 && !(P->comp && P->comp[j] != 0.0))
            V1[R->idx[0]] = (P->vb ? P->vb[j] : 0.0) / R->w[0];
    }
    if (strib) {
        const eng_status st = stribeck_newton(E, P, mode, V1, f);
        if (st != ENG_OK) return st;
        for (size_t j = 0; j < nc; j++) {
            const eng_row *R = &S->rows[j];
            if (E->held[j] && R->nnz == 1 && !(P->comp && P->comp[j] != 0.0))
                V1[R->idx[0]] = (P->vb ? P->vb[j] : 0.0) / R->w[0];
        }
    }
    return ENG_OK;
}

/* The force a held contact may carry in the problem P: its limit, and for a Stribeck contact at
 * least the law's value at rest, N mu(0) (a slide whose speed has no positive root, q below N mu(0),
 * comes to rest and holds: the active set would otherwise flip it between held and sliding). */
static double held_limit(const eng_problem *P, size_t j)
{
    if (!P->law || P->law[j].law != DFO_LAW_STRIBECK) return P->limit[j];
    return fmax(P->limit[j], P->N[j] * dfo_friction_mu(&P->law[j], 0.0));
}

/* The LCP by an active set (principal pivoting on the basis solve): infeasible contacts flipped,
 * at most ACTIVE_SET_ROUNDS per contact: for the Stribeck law, a singular D, and where Lemke fails. */
static eng_status dense_active_set(eng *E, const eng_problem *P, int *mode, double *V1, double *f, int *pivots)
{
    const size_t nc = ENG_NC(E);
    int piv = 0;
    for (size_t round = 0; round < ACTIVE_SET_ROUNDS * nc + 4; round++) {
        const eng_status st = dense_basis(E, P, mode, V1, f);
        if (st != ENG_OK) return st;
        int changed = 0;
        for (size_t j = 0; j < nc; j++) {
            if (!(P->limit[j] > 0.0)) continue;
            double v = row_dot(&E->S.rows[j], V1) - (P->vb ? P->vb[j] : 0.0);
            if (P->comp) v += P->comp[j] * f[j];
            if (mode[j] == 0 && fabs(f[j]) > held_limit(P, j)) { mode[j] = -sgn(f[j]); changed = 1; }
            else if (mode[j] != 0 && mode[j] * v < 0.0) { mode[j] = 0; changed = 1; }
        }
        if (!changed) { if (pivots) *pivots = piv; return ENG_OK; }
        piv++;
    }
    if (pivots) *pivots = piv;
    return ENG_ERR_LCP;
}

/* Whether the grid slot's cached D^-1 (gDinv) is that of problem P's set sel[0..m) and compliances:
 * the slot not refactored since (factor_slot clears gd_ok), the same contacts, the same comp. */
static int dinv_hit(const eng *E, const eng_problem *P, size_t m)
{
    if (!E->gd_ok || E->gd_m != m || E->gd_comp != (P->comp != NULL)) return 0;
    for (size_t a = 0; a < m; a++) {
        const int j = E->sel[a];
        if (E->gd_sel[a] != j) return 0;
        if (P->comp && !(E->gd_cv[a] == P->comp[j])) return 0;
    }
    return 1;
}

/* The key of the grid slot's D^-1 just computed (gDinv; singular: no inverse, the active set) */
static void dinv_keep(eng *E, const eng_problem *P, size_t m, int singular)
{
    for (size_t a = 0; a < m; a++) {
        E->gd_sel[a] = E->sel[a];
        E->gd_cv[a] = P->comp ? P->comp[E->sel[a]] : 0.0;
    }
    E->gd_m = m;
    E->gd_comp = P->comp != NULL;
    E->gd_sing = singular;
    E->gd_ok = 1;
}

ENG_API eng_status ENG_FN(eng_dense_friction)(void *engine, const eng_problem *P, int what, int *mode, double *V1, double *f,
                              int *pivots)
{
    eng *E = (eng *)engine;
    const eng_setup *S = &E->S;
    const size_t nc = ENG_NC(E);
    if (pivots) *pivots = 0;
    if (what == ENG_SOLVE_BASIS) return dense_basis(E, P, mode, V1, f);
    /* the warm basis first: when it solves the LCP, no pivot */
    eng_status st = dense_basis(E, P, mode, V1, f);
    if (st != ENG_OK) return st;
    int feasible = 1;
    for (size_t j = 0; j < nc && feasible; j++) {
        if (!(P->limit[j] > 0.0)) continue;
        double v = row_dot(&S->rows[j], V1) - (P->vb ? P->vb[j] : 0.0);
        if (P->comp) v += P->comp[j] * f[j];
        feasible = (mode[j] == 0) ? fabs(f[j]) <= held_limit(P, j) : mode[j] * v > 0.0;
    }
    if (feasible) return ENG_OK;
    /* the contacts with friction: the 2 m LCP in (u+, u-), w = (l + f, l - f), f = D^-1 (u+ - u- - c) */
    size_t m = 0;
    for (size_t j = 0; j < nc; j++)
        if (P->limit[j] > 0.0) E->sel[m++] = (int)j;
    if (E->any_law) return dense_active_set(E, P, mode, V1, f, pivots);
    /* c = W A^-1 p_hat - vb (frictionless contacts carry no force) */
    ENG_SOLVE(E, P->slot, P->p_hat, E->y);
    for (size_t a = 0; a < m; a++) {
        const size_t j = (size_t)E->sel[a];
        E->rhs[a] = row_dot(&S->rows[j], E->y) - (P->vb ? P->vb[j] : 0.0);
    }
    /* D^-1 (D = W A^-1 W' + the compliances): the grid slot's from its cache where it holds this
     * set and these compliances (dinv_hit), else anew (and kept for the grid slot) */
    const int cache = P->slot == ENG_SLOT_GRID;
    double *Dinv = cache ? E->gDinv : E->Dinv;
    if (!(cache && dinv_hit(E, P, m))) {
        if (cache) E->gd_ok = 0;
        const eng_coupling *Cp = coupling_of(E, P->slot);
        if (Cp)
            Cp->delassus(Cp->ctx, P->slot, E->sel, m, E->D);
        else
            columns(E, P->slot, m);
        for (size_t a = 0; a < m; a++) {
            const size_t j = (size_t)E->sel[a];
            if (!Cp)
                for (size_t c = 0; c < m; c++) E->D[a * m + c] = row_dot(&S->rows[j], E->colp[c]);
            if (P->comp) E->D[a * m + a] += P->comp[j];
        }
        int *dep = E->st2;
        chol(m, E->D, m, E->Lc, dep);
        int singular = 0;
        for (size_t a = 0; a < m; a++) singular |= dep[a] != 0;
        if (!singular)
            for (size_t c = 0; c < m; c++) { /* D^-1 column by column */
                for (size_t a = 0; a < m; a++) E->sol[a] = (a == c) ? 1.0 : 0.0;
                chol_solve(m, E->Lc, m, dep, E->sol, E->sol);
                for (size_t a = 0; a < m; a++) Dinv[a * m + c] = E->sol[a];
            }
        if (cache) dinv_keep(E, P, m, singular);
        if (singular) return dense_active_set(E, P, mode, V1, f, pivots); /* D singular: no inverse */
    } else if (E->gd_sing)
        return dense_active_set(E, P, mode, V1, f, pivots);
    const size_t m2 = 2 * m;
    for (size_t a = 0; a < m; a++) {
        double dc = 0.0;
        for (size_t c = 0; c < m; c++) {
            const double d = Dinv[a * m + c];
            E->lM[a * m2 + c] = d;
            E->lM[a * m2 + m + c] = -d;
            E->lM[(m + a) * m2 + c] = -d;
            E->lM[(m + a) * m2 + m + c] = d;
            dc += d * E->rhs[c];
        }
        const double l = P->limit[E->sel[a]];
        E->lq[a] = l - dc;
        E->lq[m + a] = l + dc;
        E->guess[a] = mode[E->sel[a]] > 0;
        E->guess[m + a] = mode[E->sel[a]] < 0;
    }
    int piv = 0;
    const lcp_status ls = lcp_lemke_warm_ws(E->ws, (int)m2, E->lM, E->lq, E->guess, LEMKE_PIVOTS_PER_N * (int)m2 + 16,
                                            E->lz, E->lw, E->zb, &piv);
    if (pivots) *pivots = piv;
    if (ls == LCP_BAD_INPUT) return ENG_ERR_NONFINITE;
    if (ls != LCP_OK) return dense_active_set(E, P, mode, V1, f, pivots);
    for (size_t a = 0; a < m; a++) {
        const size_t j = (size_t)E->sel[a];
        mode[j] = (E->zb[a] && E->lz[a] > 0.0) ? 1 : (E->zb[m + a] && E->lz[m + a] > 0.0) ? -1 : 0;
    }
    /* the velocities from the active pairs' equations (the basis solve of the modes found) */
    return dense_basis(E, P, mode, V1, f);
}

/* ---- the trial step ----------------------------------------------------------------------------- */

/* The Bossak step of length hh from the state to t1 (loads at t1 set): the kinematics, M_hat's
 * factor (slot), the re-based A0 (method.md section 8), x_pred and p_hat. */
typedef struct {
    dfo_bossak_kin kin;
    int slot;
    double cM, cC, cK;
    const double *sl; /* the sliders of the state the trial starts from (Jenkins contacts' targets) */
} trial;

/* Whether an A of the step length hA is re-based on a step of length hh where alpha is not 0 (tol:
 * the lengths' tolerance, >= 0, so that hh = hA is not: without branches, a loop's test) */
static ENG_HOT int rebases_len(const eng_setup *S, double hA, double hh, double tol)
{
    return (fabs(hh - hA) > tol) & (S->rate_max * max_b(hA, hh) <= 1.0);
}

/* Whether DOF i's A, of the step length s->hA[i], is re-based on a step of length hh (tol: the
 * lengths' tolerance; a held contact's pin aside) */
static ENG_HOT int rebases(const eng *E, const eng_state *s, size_t i, double hh, double tol)
{
    return (E->S.alpha != 0.0) & rebases_len(&E->S, s->hA[i], hh, tol);
}

/* A0 := A re-based where it belongs to another step length than hh (method.md section 8), except on
 * a DOF a held contact pins alone (w_j = e_i: its acceleration and jerk are 0, A stays) and on a
 * ghost (its motion prescribed); E->pin says which are pinned when some A is of another length.
 * The loads end at t1. */
static ENG_HOT int needs_rebase(eng *E, const eng_state *s, double hh)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E);
    if (S->alpha == 0.0) return 0;
    int other = 0;
    for (size_t i = 0; i < n; i++) other |= hh != s->hA[i];
    if (!other) return 0;
    const double tol = 1e-12 * hh + 4.0 * DBL_EPSILON * fabs(s->t);
    int *pin = E->pin;
    memset(pin, 0, n * sizeof(int));
    if (E->ghost)
        for (size_t k = 0; k < E->ngh; k++) pin[E->gidx[k]] = 1;
    for (size_t j = 0; j < ENG_NC(E); j++) /* (the mode's test without a branch) */
        if (S->rows[j].nnz == 1 && !is_jenk(E, j)) pin[S->rows[j].idx[0]] |= (s->mode[j] == 0) & has_friction(E, j);
    /* rebases' test on the DOFs not pinned, without branches (the pins complete: rebase and
     * step_spans read them) */
    int any = 0;
    for (size_t i = 0; i < n; i++) any |= (pin[i] == 0) & rebases(E, s, i, hh, tol);
    return any;
}

/* The jerks of the phase's start into E->jk, once per phase (jk_ok: whatever the trials' lengths);
 * out of line, so that the trials' re-basing stays small enough to inline. The loads end at t. */
static ENG_COLD void phase_jerks(eng *E, const eng_inputs *in, const eng_state *s)
{
    const eng_setup *S = &E->S;
    double *acc = E->acc;
    loads_at(E, in, s->t);
    /* (the physical accelerations: for the jerks' damping and Stribeck terms only; where C is 0,
     * ops.apply_C NULL, a model whose ENG_HAS_C holds applies it to zeros) */
    if ((ENG_HAS_C(E) && S->ops.apply_C) || S->law) phys_accel(E, s, s->t, s->mode, acc, E->f2);
    else if (ENG_HAS_C(E)) memset(acc, 0, ENG_N(E) * sizeof(double));
    jerks(E, in, s, acc, E->jk);
    E->jk_ok = 1;
}

/* The pins of the phase's start into E->rpin (needs_rebase's: the DOFs a held contact pins alone and
 * the ghosts), kept for its further trials (rpin_ok, cleared with jk_ok) where the loads are held (a
 * ramp's limits may change which contacts have friction). */
static ENG_HOT const int *rebase_pins(eng *E, const eng_inputs *in, const eng_state *s)
{
    if (E->rpin_ok) return E->rpin;
    const eng_setup *S = &E->S;
    int *pin = E->rpin;
    memset(pin, 0, ENG_N(E) * sizeof(int));
    if (E->ghost)
        for (size_t k = 0; k < E->ngh; k++) pin[E->gidx[k]] = 1;
    for (size_t j = 0; j < ENG_NC(E); j++) /* (the mode's test without a branch) */
        if (S->rows[j].nnz == 1 && !is_jenk(E, j)) pin[S->rows[j].idx[0]] |= (s->mode[j] == 0) & has_friction(E, j);
    E->rpin_ok = !ramped(in);
    return pin;
}

/* A0 := A re-based on the step length hh (rebase's); the pins it left out in E->rpin where some A
 * is of another length. */
static ENG_HOT void rebase_into(eng *E, const eng_inputs *in, const eng_state *s, double hh, double t1, double *A0)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E);
    const double a = S->alpha, *const A = s->A, *const hA = s->hA;
    const double tol = 1e-12 * hh + 4.0 * DBL_EPSILON * fabs(s->t);
    const int *pin = NULL;
    int any = 0;
    if (a != 0.0) {
        int other = E->rpin_ok; /* (the pins are asked for only where some A is of another length) */
        for (size_t i = 0; i < n && !other; i++) other = hh != hA[i];
        if (other) {
            pin = rebase_pins(E, in, s);
            for (size_t i = 0; i < n && !any; i++) any = (pin[i] == 0) & rebases_len(S, hA[i], hh, tol);
        }
    }
    if (!any) {
        for (size_t i = 0; i < n; i++) A0[i] = A[i];
        return;
    }
    if (!E->jk_ok) phase_jerks(E, in, s);
    loads_at(E, in, t1);
    const double *jk = E->jk;
    for (size_t i = 0; i < n; i++) /* (jk is set for every DOF: both values, one selected, no branch) */
        A0[i] = dfo_select((pin[i] == 0) & rebases_len(S, hA[i], hh, tol), A[i] + a * (hh - hA[i]) * jk[i], A[i]);
}

static ENG_HOT void rebase(eng *E, const eng_inputs *in, const eng_state *s, double hh, double t1)
{
    rebase_into(E, in, s, hh, t1, E->A0);
}

static ENG_HOT eng_status trial_step(eng *E, const eng_inputs *in, const eng_state *s, double hh, double t1, trial *T)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E);
    const double a = S->alpha;
    if (hh == S->h) T->kin = E->kin_grid;
    else dfo_bossak_kin_for(hh, E->g, E->b, &T->kin);
    T->slot = (hh == S->h) ? ENG_SLOT_GRID : ENG_SLOT_TRIAL;
    T->cM = (1.0 - a) * T->kin.c1;
    T->cC = 1.0;
    T->cK = E->b * hh / E->g;
    if (!factor_slot(E, T->slot, T->cM, T->cC, T->cK)) return ENG_ERR_BAD_INPUT;
#if ENG_FUSED_LOCAL /* (the vectors in locals, stored into the engine's arrays at the end) */
    double A0[ENG_FUSED_N], xp[ENG_FUSED_N], r[ENG_FUSED_N], y[ENG_FUSED_N], y2[ENG_FUSED_N], ph[ENG_FUSED_N];
#else
    double *const A0 = E->A0, *const xp = E->xp, *const r = E->r, *const y = E->y, *const y2 = E->y2,
                 *const ph = E->ph;
#endif
    rebase_into(E, in, s, hh, t1, A0);
    T->sl = s->slider;
    const dfo_bossak_kin K = T->kin;
    const double g1 = E->g1;
    /* x_pred, and p_hat = P1 + F_ext - K x_pred + M (-a A0 + (1 - a) (c1 V + g1 A0)) */
    for (size_t i = 0; i < n; i++) {
        xp[i] = s->X[i] + K.pred_V * s->V[i] + K.pred_A * A0[i];
        r[i] = -a * A0[i] + (1.0 - a) * (s->V[i] * K.c1 + g1 * A0[i]);
    }
    if (E->ghost) /* a ghost's x_pred such that x_pred + corr_V V1 is its prescribed end position */
        for (size_t k = 0; k < E->ngh; k++) {
            double xg;
            ghost_at(E, E->gidx[k], s->t - E->gt0 + hh, &xg, &E->gve[k], NULL, NULL);
            xp[E->gidx[k]] = xg - K.corr_V * E->gve[k];
        }
#ifdef ENG_ADD_MK
    (void)y;
    (void)y2;
    applied_at(E, s, t1, ph);
    ENG_ADD_MK(E, r, xp, ph);
#else
    ENG_APPLY_M(E, r, y);
    applied_at(E, s, t1, ph);
    ENG_APPLY_K(E, xp, y2);
    for (size_t i = 0; i < n; i++) ph[i] += y[i] - y2[i];
#endif
    if (E->ghost) /* and its prescribed end velocity in p_hat's entry (Dirichlet) */
        for (size_t k = 0; k < E->ngh; k++) ph[E->gidx[k]] = E->gve[k];
#if ENG_FUSED_LOCAL
    for (size_t i = 0; i < n; i++) {
        E->A0[i] = A0[i];
        E->xp[i] = xp[i];
        E->ph[i] = ph[i];
    }
#endif
    return ENG_OK;
}

/* The friction problem of the trial with limits lim and modes st: the model's solver or the dense one. */
static ENG_HOT eng_status solve_trial(eng *E, const trial *T, int what, int *st, double *V1, double *f, int *pivots)
{
    const eng_setup *S = &E->S;
    eng_problem P;
    P.slot = T->slot;
    P.h = T->kin.h;
    P.cM = T->cM;
    P.cC = ENG_HAS_C(E) ? T->cC : 0.0;
    P.cK = T->cK;
    P.p_hat = E->ph;
    P.vb = E->vb;
    P.limit = E->lim;
    P.N = E->Nn;
    P.law = E->any_law ? S->law : NULL;
    P.comp = NULL;
    if (ENG_HAS_JENKINS(E)) { /* a Jenkins contact's shifted target and compliance (engine.h's eng_problem) */
        const double cV = T->kin.corr_V, hh = T->kin.h;
        for (size_t j = 0; j < ENG_NC(E); j++) {
            E->vbj[j] = E->vb[j];
            E->comp[j] = 0.0;
            if (!is_jenk(E, j)) continue;
            E->vbj[j] = ((T->sl[j] + hh * E->vb[j]) - row_dot(&S->rows[j], E->xp)) / cV;
            E->comp[j] = 1.0 / (S->k_t[j] * cV);
        }
        P.vb = E->vbj;
        P.comp = E->comp;
    }
    if (ENG_HAS_FRICTION(E)) return ENG_FRICTION(E, &P, what, st, V1, f, pivots);
    return ENG_FN(eng_dense_friction)(E, &P, what, st, V1, f, pivots);
}

/* A Jenkins contact's slider at the end of the trial's step with end velocities V1 and forces f, in
 * the step's mode E->st[j]: stuck, moved with its belt; sliding, where its force puts it. */
static double slider_end(const eng *E, const eng_state *s, const trial *T, const double *V1, const double *f, size_t j)
{
    if (has_friction(E, j) && E->st[j] == 0) return s->slider[j] + T->kin.h * E->vb[j];
    const eng_row *R = &E->S.rows[j];
    return (row_dot(R, E->xp) + T->kin.corr_V * row_dot(R, V1)) + f[j] / E->S.k_t[j];
}

/* The energy accounts of the trial's step from s to t1 with end velocities V1 and forces f (before
 * finish moves the state): eng_state's W_applied, W_friction, D_damping. */
static void account(eng *E, eng_state *s, const trial *T, double t1, const double *V1, const double *f)
{
    const size_t n = ENG_N(E);
    const double hh = T->kin.h;
    double *P0 = E->ew, *P1 = E->ew + n, *dX = E->ew + 2 * n;
    applied_at(E, s, s->t, P0);
    applied_at(E, s, t1, P1);
    double Wa = 0.0, Wf = 0.0, D = 0.0;
    for (size_t i = 0; i < n; i++) {
        dX[i] = E->xp[i] + T->kin.corr_V * V1[i] - s->X[i];
        Wa += 0.5 * hh * (P0[i] * s->V[i] + P1[i] * V1[i]);
    }
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (is_jenk(E, j)) { /* the friction's work on the slider: f ds (stuck: trapezoidal, with its belt) */
            const int stuck = has_friction(E, j) && E->st[j] == 0;
            const double ds = slider_end(E, s, T, V1, f, j) - s->slider[j];
            Wf += (stuck ? 0.5 * (s->F[j] + f[j]) : f[j]) * ds;
            if (!stuck && s->mode[j] == 0 && has_friction(E, j)) { /* a breakaway inside the step (paper,
                * consistent): its jump's released energy beyond the kinetic force's work over it */
                const double d = E->Fb[j] - E->mukN[j];
                Wf -= d * d / (2.0 * E->S.k_t[j]);
            }
            continue;
        }
        const double fj = is_strib(E, j) ? 0.5 * (s->F[j] + f[j]) : f[j];
        Wf += fj * row_dot(&E->S.rows[j], dX);
    }
    if (ENG_HAS_C(E)) {
        ENG_APPLY_C(E, s->V, P0);
        ENG_APPLY_C(E, V1, P1);
        for (size_t i = 0; i < n; i++) D += 0.5 * hh * (s->V[i] * P0[i] + V1[i] * P1[i]);
    }
    s->W_applied += Wa;
    s->W_friction += Wf;
    s->D_damping += D;
}

/* Accept the trial with end velocities V1 and forces f: X, V, A, hA, F (not the time, not the modes);
 * the energy accounts when kept (t1: the step's end). */
static ENG_HOT void finish(eng *E, eng_state *s, const trial *T, const double *V1, const double *f, double t1)
{
    const size_t n = ENG_N(E);
    if (E->S.account_energy) account(E, s, T, t1, V1, f);
    if (ENG_HAS_JENKINS(E))
        for (size_t j = 0; j < ENG_NC(E); j++)
            if (is_jenk(E, j)) s->slider[j] = slider_end(E, s, T, V1, f, j);
    for (size_t i = 0; i < n; i++) {
        s->X[i] = E->xp[i] + T->kin.corr_V * V1[i];
        s->A[i] = (V1[i] - s->V[i]) * T->kin.c1 - E->g1 * E->A0[i];
        s->V[i] = V1[i];
        s->hA[i] = T->kin.h;
    }
    for (size_t j = 0; j < ENG_NC(E); j++) s->F[j] = f[j];
}

/* ---- phases, switches, restarts ------------------------------------------------------------- */

/* A phase's start: its time, and for an observer its positions and modes */
static ENG_HOT void begin_phase(eng *E, const eng_state *s, double *ta, const eng_hooks *hk)
{
    *ta = s->t;
    E->jk_ok = 0; /* the jerks of the phase's start: to be computed (trial_step) */
    E->rpin_ok = 0; /* (its pins likewise) */
    E->tjk_ok = 0;  /* (and the tangent's jerks) */
    if (!hk || !hk->obs || !hk->obs->on_phase) return;
    memcpy(E->X0, s->X, ENG_N(E) * sizeof(double));
    if (hk->obs->velocities) memcpy(E->V0, s->V, ENG_N(E) * sizeof(double));
    if (ENG_NC(E)) memcpy(E->mode0, s->mode, ENG_NC(E) * sizeof(int));
}

static ENG_HOT void observe(eng *E, const eng_state *s, double ta, const double *f, const eng_hooks *hk)
{
    if (!hk || !hk->obs || !hk->obs->on_phase) return;
    const eng_observer *o = hk->obs;
    if (s->t < o->t_start || ta > o->t_stop) return;
    eng_phase ph;
    ph.ta = ta;
    ph.tb = s->t;
    ph.X0 = E->X0;
    ph.X1 = s->X;
    ph.mode0 = E->mode0;
    ph.f = f;
    ph.v_belt = (E->vb == E->zero_nc) ? NULL : E->vb;
    ph.V0 = o->velocities ? E->V0 : NULL;
    ph.V1 = o->velocities ? s->V : NULL;
    ENG_OBSERVE(o, &ph, s);
}

static void report(eng_state *s, size_t j, int from, const eng_hooks *hk)
{
    s->switches++;
    s->t_switch = s->t;
    s->stick_tb = NAN; /* (a new stick, or none) */
    if (s->mode[j] == 0) s->t_stick[j] = s->t;
    if (hk && hk->on_switch) hk->on_switch(hk->switch_ctx, s->t, j, s, from, s->mode[j]);
}

/* The modes of the contacts without friction: their slip's direction at the state's velocities, a
 * change reported where the hooks ask for it (eng_hooks.report_turns). */
static ENG_HOT void free_modes(eng *E, eng_state *s, const eng_hooks *hk)
{
    if (E->all_friction) return;
    const int turns = hk && hk->report_turns;
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (has_friction(E, j)) continue;
        const int from = s->mode[j];
        s->mode[j] = sgn(slip(E, j, s->V));
        if (turns && s->mode[j] != from) report(s, j, from, hk);
    }
}

/* The rest rule's order of releases: a before b when its excess is larger, on ties when its index is
 * lower (the contact the one-a-round cascade picks first: a strictly larger excess wins, the first
 * on ties). A strict total order: any sort gives the one result. */
static int release_before(const eng_release *a, const eng_release *b)
{
    return (a->excess != b->excess) ? a->excess > b->excess : a->j < b->j;
}

/* Sorts r[0 .. m-1] into release_before's order: heapsort, in place (no allocation), O(m log m). */
static void sort_releases(eng_release *r, size_t m)
{
    if (m < 2) return;
    for (size_t end = m, start = m / 2;;) {
        if (start > 0) {
            start--; /* build the heap (its root: the last in the order) */
        } else {
            if (--end == 0) return;
            const eng_release t = r[0]; /* the root to the end of the sorted tail */
            r[0] = r[end];
            r[end] = t;
        }
        for (size_t i = start;;) { /* sift r[i] down */
            size_t c = 2 * i + 1;
            if (c >= end) break;
            if (c + 1 < end && release_before(&r[c], &r[c + 1])) c++;
            if (!release_before(&r[i], &r[c])) break;
            const eng_release t = r[i];
            r[i] = r[c];
            r[c] = t;
            i = c;
        }
    }
}

/* The rest rule for the contacts at rest in rest[] (slip 0 now; the held ones stay held): their
 * holding forces solved together with every stuck contact; the one most beyond its limit starts to
 * slide the way it is driven, and the rest are solved again (the causal cascade). Sets mode[] of
 * the resting contacts; f: their holding forces (the stuck ones'). Returns 1 when its last solve
 * (E->y2, E->f: physical accelerations and forces) is of the modes it ends with. */
static int rest_decide(eng *E, const eng_state *s, double t, const int *rest, int *mode)
{
    const size_t nc = ENG_NC(E);
    size_t rigid = 0;
    for (size_t j = 0; j < nc; j++) {
        if (rest[j]) mode[j] = 0;
        rigid += rest[j] && has_friction(E, j) && !is_jenk(E, j);
    }
    /* (the report: where two or more rigid contacts at rest are decided together) */
    const eng_rest_fn tell = rigid >= 2 ? E->S.on_rest : NULL;
    void *ctx = E->S.rest_ctx;
    if (tell) tell(ctx, t, ENG_REST_OPEN, nc, 0, 0.0, rest, mode);
    for (size_t round = 0; round <= nc; round++) {
        phys_accel(E, s, t, mode, E->y2, E->f);
        size_t worst = nc, m = 0;
        double excess = 0.0;
        for (size_t j = 0; j < nc; j++) {
            /* (a slider that comes to rest sticks: its force is the kinetic one, at most on its limit,
             * where jenk_stuck_forces holds it) */
            if (!rest[j] || mode[j] != 0 || !has_friction(E, j) || is_jenk(E, j)) continue;
            const double e = fabs(E->f[j]) - E->Fb[j];
            if (E->rest_apart && e > 0.0) E->rel[m++] = (eng_release){e, j};
            if (e > excess) { excess = e; worst = j; }
        }
        if (worst == nc) {
            if (tell) tell(ctx, t, ENG_REST_SETTLED, nc, 0, 0.0, rest, mode);
            return 1;
        }
        if (!E->rest_apart) { /* the worst only: the others' forces change with its release */
            E->rel[0] = (eng_release){excess, worst};
            m = 1;
        } else if (m > 1) { /* every one, as the rounds would release them: by excess, then index */
            sort_releases(E->rel, m);
        }
        for (size_t k = 0; k < m; k++) {
            const size_t j = E->rel[k].j;
            mode[j] = -sgn(E->f[j]); /* the holding force's opposite: the net applied force's side */
            if (tell) tell(ctx, t, ENG_REST_RELEASE, j, mode[j], E->rel[k].excess, rest, mode);
        }
    }
    return 0;
}

/* The consistent restart of the mode set in s->mode: physical accelerations, hA = 0, forces (a
 * slide from rest at its start magnitude). decided: rest_decide's last solve (E->y2, E->f) is of
 * this state and mode set (its return), so they are taken. */
static void restart(eng *E, eng_state *s, double t, int decided)
{
    const size_t n = ENG_N(E);
    if (decided) {
        memcpy(s->A, E->y2, n * sizeof(double));
        if (ENG_NC(E)) memcpy(s->F, E->f, ENG_NC(E) * sizeof(double));
    } else {
        phys_accel(E, s, t, s->mode, s->A, s->F);
    }
    for (size_t i = 0; i < n; i++) s->hA[i] = 0.0;
    for (size_t j = 0; j < ENG_NC(E); j++)
        if (!has_friction(E, j)) s->F[j] = 0.0;
}

/* ---- the schemes ------------------------------------------------------------------------------ */

/* The held contacts' forces clamped to their limits, the rested ones at rest exactly (one DOF). */
static ENG_HOT void rest_exact(eng *E, eng_state *s)
{
    const eng_setup *S = &E->S;
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (s->mode[j] != 0 || !has_friction(E, j) || is_jenk(E, j)) continue;
        const eng_row *R = &S->rows[j];
        if (R->nnz == 1) {
            s->V[R->idx[0]] = E->vb[j] / R->w[0];
            s->A[R->idx[0]] = 0.0;
            s->hA[R->idx[0]] = 0.0;
        }
    }
}

/* What held_step did: taken (the step done), the trial and its basis solve left as trial_step and
 * the solve leave them (T, E->A0, xp, ph, V1, f) for the general path, not tried, M_hat refused */
enum { ENG_HELD_TAKEN = 1, ENG_HELD_TRIAL = 0, ENG_HELD_UNTRIED = 2, ENG_HELD_ERROR = -1 };

static ENG_HOT int held_step(eng *E, eng_state *s, double t1, trial *T);

/* The model's fused step may take a step of length hh: a grid step of the whole structure, held
 * inputs, no belts */
static ENG_HOT int fused_ok(const eng *E, const eng_inputs *in, double hh)
{
    return ENG_HAS_STEP_HELD(E) && hh == E->S.h && !E->ghost && !ramped(in) && E->vb == E->zero_nc;
}

/* After the model's fused step: the time, the modes of contacts without friction, the rested
 * contacts at rest exactly (rested: the schemes whose stuck contacts rest), the phase observed. */
static ENG_HOT void held_done(eng *E, eng_state *s, double t_end, int rested, double ta, const eng_hooks *hk)
{
    s->solves++;
    s->t = t_end;
    free_modes(E, s, hk);
    if (rested) rest_exact(E, s);
    observe(E, s, ta, s->F, hk);
}

/* The paper scheme (consistent = 0) and the consistent one (1): the LCP from the modes before the
 * step, then the paper's coefficient updates, or the consistent scheme's rest rule at the predicted
 * rest position. */
static ENG_HOT eng_status step_lcp(eng *E, const eng_inputs *in, eng_state *s, double t_end, double hh, int consistent,
                           const eng_hooks *hk)
{
    const eng_setup *S = &E->S;
    const size_t nc = ENG_NC(E);
    double ta;
    begin_phase(E, s, &ta, hk);
    for (size_t j = 0; j < nc; j++) {
        E->st[j] = s->mode[j];
        E->lim[j] = !has_friction(E, j) ? 0.0 : (s->mode[j] == 0) ? E->Fb[j] : E->mukN[j];
    }
    trial T;
    int fused = ENG_HELD_UNTRIED;
    if (fused_ok(E, in, hh) && !E->any_law) {
        /* the model's fused step: where every margin is positive the LCP keeps the warm basis (no
         * pivot, no coefficient update, no judged contact), and the fused step is its solution */
        fused = held_step(E, s, t_end, &T);
        if (fused == ENG_HELD_ERROR) return ENG_ERR_BAD_INPUT;
        if (fused == ENG_HELD_TAKEN) {
            held_done(E, s, t_end, consistent, ta, hk);
            return ENG_OK;
        }
    }
    eng_status st = ENG_OK;
    if (fused != ENG_HELD_TRIAL) st = trial_step(E, in, s, hh, t_end, &T); /* (else the fused step's trial) */
    if (st != ENG_OK) return st;
    int piv = 0, total = 0;
    st = solve_trial(E, &T, ENG_SOLVE_LCP, E->st, E->V1, E->f, &piv);
    s->solves++;
    if (st != ENG_OK) return st;
    total += piv;
    if (!consistent) {
        for (int u = 0; u < S->friction_updates; u++) {
            int update = 0;
            for (size_t j = 0; j < nc; j++) {
                if (!has_friction(E, j)) continue;
                const double l1 = (E->st[j] == 0) ? E->Fb[j] : E->mukN[j];
                if (l1 != E->lim[j]) { E->lim[j] = l1; update = 1; }
            }
            if (!update) break;
            st = solve_trial(E, &T, ENG_SOLVE_LCP, E->st, E->V1, E->f, &piv);
            s->solves++;
            if (st != ENG_OK) return st;
            total += piv;
        }
    } else {
        int update = 0;
        for (size_t j = 0; j < nc; j++) {
            E->frozen[j] = 0;
            if (!has_friction(E, j) || is_jenk(E, j)) continue; /* (a slider: its LCP's mode) */
            const int from = s->mode[j];
            if (from == 0 && E->st[j] != 0) { E->lim[j] = E->mukN[j]; update = 1; }
            if (from != 0 && E->st[j] != from) { E->frozen[j] = 1; update = 1; }
        }
        if (update) {
            /* the judged contacts: their holding force at the predicted rest position x_pred, with
             * the velocities of the step's solution (a judged contact at rest) */
            eng_state at = *s;
            at.X = E->xp;
            at.V = E->V1;
            for (size_t j = 0; j < nc; j++) E->tmode[j] = E->frozen[j] ? 0 : s->mode[j];
            phys_accel(E, &at, t_end, E->tmode, E->y2, E->f2);
            for (size_t j = 0; j < nc; j++) {
                if (!E->frozen[j]) continue;
                const double Sj = -E->f2[j];
                E->st[j] = (fabs(Sj) <= E->Fb[j]) ? 0 : sgn(Sj);
                E->lim[j] = (E->st[j] == 0) ? E->Fb[j] : E->mukN[j];
            }
            for (size_t pass = 0; update && pass <= nc; pass++) {
                st = solve_trial(E, &T, ENG_SOLVE_BASIS, E->st, E->V1, E->f, NULL);
                s->solves++;
                if (st != ENG_OK) return st;
                update = 0;
                for (size_t j = 0; j < nc; j++) {
                    if (!has_friction(E, j) || E->st[j] == 0 || is_jenk(E, j)) continue;
                    if (E->st[j] * slip(E, j, E->V1) > 0.0) continue;
                    if (s->mode[j] == 0 && !E->frozen[j]) continue;
                    E->st[j] = 0;
                    E->lim[j] = E->Fb[j];
                    update = 1;
                }
            }
            total += 1;
        }
        for (size_t j = 0; j < nc; j++)
            if (has_friction(E, j) && E->st[j] == 0) E->f[j] = clamp_lim(E->f[j], E->Fb[j]);
    }
    if (total > 0) s->pivot_steps++;
    finish(E, s, &T, E->V1, E->f, t_end);
    s->t = t_end;
    for (size_t j = 0; j < nc; j++) {
        const int from = s->mode[j];
        s->mode[j] = has_friction(E, j) ? E->st[j] : sgn(slip(E, j, s->V));
        if (s->mode[j] != from && (has_friction(E, j) || (hk && hk->report_turns))) report(s, j, from, hk);
    }
    if (consistent) rest_exact(E, s);
    /* the step's modes are its friction problem's (the modes at its end): the phase's */
    if (nc) memcpy(E->mode0, s->mode, nc * sizeof(int));
    observe(E, s, ta, s->F, hk);
    return ENG_OK;
}

/* How far contact j is from its switch after the trial (> 0: not yet): m v for a sliding contact,
 * Fb - |f| for a held one. */
static ENG_HOT double margin(const eng *E, const int *mode, size_t j, const double *V1, const double *f)
{
    if (mode[j] != 0) return mode[j] * slip(E, j, V1);
    return E->Fb[j] - fabs(f[j]);
}

/* Contact j switches in the trial: a sliding one whose slip stopped or turned (margin <= 0), a held
 * one whose holding force is beyond its limit (margin < 0: a force on the limit holds, the rest
 * rule's |f| <= Fb). */
static ENG_HOT int switches(const eng *E, const int *mode, size_t j, const double *V1, const double *f)
{
    /* (margin's two values, both taken and one selected, without a branch: a structure's contacts mix
     * held and sliding ones, which a branch predictor misses) */
    const int m = mode[j];
    const double gs = m * slip(E, j, V1), gh = E->Fb[j] - fabs(f[j]);
    return ((m != 0) & (gs <= 0.0)) | ((m == 0) & (gh < 0.0));
}

#define MARGIN_LIST 8 /* the candidates margin_fn lists (more: every contact's cand read) */

/* A located trial of length x from the phase's start (the state), loads at its end; its solve in
 * the modes st; returns the smallest margin of the candidates. The phase's last trial is known by
 * its length (x_last, its T at T_last: margin_fn's in Tm), so that a trial asked for again (the
 * root's last point) is taken as it stands in the engine's arrays. */
typedef struct {
    eng *E;
    const eng_inputs *in;
    const eng_state *s;
    double t_step;     /* the internal step's end (the loads' time of a whole remainder) */
    double r;          /* the remainder */
    eng_status err;
    double x_last;     /* the length of the last trial (NaN: none) */
    const trial *T_last; /* where its T was written */
    int hi_last;       /* its margin is not > 0 (a root's end it may return) */
    double x_hi;       /* the length of the last such trial before it, kept in E's trial store (NaN: none) */
    trial T_hi;        /* its T */
    trial Tm;          /* margin_fn's */
    int lim_ok;        /* E->lim is of the phase's modes and of held loads (the trials' limits all alike) */
    int ncl;           /* the candidates in cl (margin_fn's search: E->cand is set), or -1: none listed */
    size_t cl[MARGIN_LIST];
} margin_ctx;

/* The trial's vectors (A0, xp, ph, V1, f) and the trial store's (sA, sX, shA, sV, sF) exchanged */
static ENG_HOT void trial_swap(eng *E)
{
    double *t;
    t = E->A0, E->A0 = E->sA, E->sA = t;
    t = E->xp, E->xp = E->sX, E->sX = t;
    t = E->ph, E->ph = E->shA, E->shA = t;
    t = E->V1, E->V1 = E->sV, E->sV = t;
    t = E->f, E->f = E->sF, E->sF = t;
}

/* The loads and limits of the trial of length x (at its end) */
static ENG_HOT double trial_loads(margin_ctx *c, double x)
{
    eng *E = c->E;
    const double t1 = (x >= c->r) ? c->t_step : c->s->t + x;
    loads_at(E, c->in, t1);
    if (c->lim_ok && c->in && E->loads_for == c->in) return t1; /* (held loads: the limits as they are) */
    for (size_t j = 0; j < ENG_NC(E); j++) E->lim[j] = dfo_select(E->st[j] == 0, E->Fb[j], E->mlN[j]);
    c->lim_ok = c->in && E->loads_for == c->in;
    return t1;
}

/* The stuck sliders' forces at a located phase's start s (E->jf0), clamped to their limits: a slider
 * comes to rest at its kinetic force, which is its limit where mu_k >= mu_s (F_k = F_b), and its
 * force computed from its spring may round a hair beyond. */
static void jenk_phase_forces(eng *E, const eng_state *s)
{
    for (size_t j = 0; j < ENG_NC(E); j++)
        E->jf0[j] = (is_jenk(E, j) && s->mode[j] == 0) ? clamp_lim(jenk_force(E, j, s), E->Fb[j]) : 0.0;
}

/* A located trial's forces f (end velocities V1, from the phase's start s) of the sliders stuck in it:
 * the force at the phase's start (E->jf0) plus the spring's change over the trial, -k_t (dg - h
 * v_belt), rather than the spring force the trial's solve rounds afresh. So a stuck slider's force
 * moves only as its spring does, and it breaks away where its spring is loaded beyond its limit, not
 * where rounding puts its force a hair beyond: one that came to rest on its limit beside a rigid
 * contact that holds the DOF (dg = 0) keeps its force on the limit, held as the rest rule holds a
 * force on its limit (a tie holds). */
static void jenk_stuck_forces(eng *E, const eng_state *s, const trial *T, const double *V1, double *f)
{
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (!is_jenk(E, j) || !has_friction(E, j) || s->mode[j] != 0 || E->st[j] != 0) continue;
        const eng_row *R = &E->S.rows[j];
        const double g1 = row_dot(R, E->xp) + T->kin.corr_V * row_dot(R, V1);
        const double d = (g1 - row_dot(R, s->X)) - T->kin.h * E->vb[j];
        f[j] = E->jf0[j] - E->S.k_t[j] * d;
    }
}

static ENG_HOT double trial_margin(margin_ctx *c, double x, trial *T)
{
    eng *E = c->E;
    if (c->hi_last) { /* the last trial into the store (a root's end the search may return: trial_again) */
        trial_swap(E);
        c->x_hi = c->x_last;
        c->T_hi = *c->T_last;
    }
    const double t1 = trial_loads(c, x);
    eng_status st = trial_step(E, c->in, c->s, x, t1, T);
    if (st == ENG_OK) st = solve_trial(E, T, ENG_SOLVE_BASIS, E->st, E->V1, E->f, NULL);
    if (ENG_HAS_JENKINS(E) && st == ENG_OK) jenk_stuck_forces(E, c->s, T, E->V1, E->f);
    if (st != ENG_OK && c->err == ENG_OK) c->err = st;
    c->x_last = x;
    c->T_last = T;
    double g = INFINITY;
    if (c->ncl >= 0) {
        for (int k = 0; k < c->ncl; k++) {
            const double gj = margin(E, E->st, c->cl[k], E->V1, E->f);
            g = (gj < g) ? gj : g;
        }
    } else {
        for (size_t j = 0; j < ENG_NC(E); j++) {
            if (!E->cand[j]) continue;
            const double gj = margin(E, E->st, j, E->V1, E->f);
            g = (gj < g) ? gj : g; /* fmin's (a NaN margin left out), without its library call */
        }
    }
    c->hi_last = !(g > 0.0) & (st == ENG_OK); /* (no branch: the search's trials alternate) */
    return g;
}

/* A phase's trials from the state s in the modes E->st. */
static ENG_HOT void margin_init(margin_ctx *c, eng *E, const eng_inputs *in, const eng_state *s, double t_step,
                                double r)
{
    c->E = E;
    c->in = in;
    c->s = s;
    c->t_step = t_step;
    c->r = r;
    c->err = ENG_OK;
    c->x_last = NAN;
    c->T_last = NULL;
    c->hi_last = 0;
    c->x_hi = NAN;
    c->lim_ok = 0;
    c->ncl = -1;
}

/* The search's trial (halvings, root): the candidates, set before it and kept through it, listed at
 * its first (in ascending order, as trial_margin's loop over them) */
static double margin_fn(void *ctx, double x)
{
    margin_ctx *c = (margin_ctx *)ctx;
    if (c->ncl == -1) {
        const eng *E = c->E;
        int m = 0;
        for (size_t j = 0; j < ENG_NC(E) && m <= MARGIN_LIST; j++)
            if (E->cand[j]) {
                if (m < MARGIN_LIST) c->cl[m] = j;
                m++;
            }
        c->ncl = (m <= MARGIN_LIST) ? m : -2; /* (-2: too many, the loop over them all, not listed again) */
    }
    return trial_margin(c, x, &c->Tm);
}

/* The phase's trial of length x into T: its last one where it was of that length (the engine's
 * arrays hold it), or the one the trial store holds (its loads, limits and factor made again: the
 * same numbers), else taken. */
static ENG_HOT void trial_again(margin_ctx *c, double x, trial *T)
{
    eng *E = c->E;
    if (x == c->x_last) {
        if (c->T_last != T) *T = *c->T_last;
        return;
    }
    if (!(x == c->x_hi)) {
        trial_margin(c, x, T);
        return;
    }
    trial_swap(E);
    *T = c->T_hi;
    (void)trial_loads(c, x);
    (void)factor_slot(E, T->slot, T->cM, T->cC, T->cK); /* (it was made once: it succeeds) */
    c->x_last = x;
    c->T_last = T;
    c->hi_last = 0;
    c->x_hi = NAN;
}

/* The sliders that broke away (E->smode: their modes before, s->mode after): the force drops from its
 * value to the kinetic one, the slider jumps there, and the spring energy released counts as friction
 * work (with the energy accounts). */
static void jenk_breakaways(eng *E, eng_state *s)
{
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (!is_jenk(E, j) || !has_friction(E, j) || E->smode[j] != 0 || s->mode[j] == 0) continue;
        const double k = E->S.k_t[j], f0 = jenk_force(E, j, s), f1 = -s->mode[j] * E->mukN[j];
        s->slider[j] = row_dot(&E->S.rows[j], s->X) + f1 / k;
        if (E->S.account_energy) s->W_friction -= (f0 * f0 - f1 * f1) / (2.0 * k);
    }
}

/* Switch the candidates whose margin is <= 0 (all of them when immediate): a stopping contact comes
 * to rest and, with every contact at rest, the rest rule decides; a held one breaks away the way it
 * is driven. Then the consistent restart. held: E->y2 and E->f hold phys_accel's solve of this
 * state in its modes at its time (taken for the first contact breaking away). */
static void apply_switches(eng *E, eng_state *s, int immediate, int held, const eng_hooks *hk)
{
    const size_t nc = ENG_NC(E);
    int *rest = E->cand;
    for (size_t j = 0; j < nc; j++) {
        if (!rest[j]) continue;
        if (!immediate && margin(E, s->mode, j, s->V, s->F) > 0.0) { rest[j] = 0; continue; }
    }
    memcpy(E->smode, s->mode, nc * sizeof(int));
    /* held contacts breaking away: their side from their holding force */
    for (size_t j = 0; j < nc; j++) {
        if (!rest[j] || s->mode[j] != 0) continue;
        if (!held) phys_accel(E, s, s->t, s->mode, E->y2, E->f);
        held = 0;
        s->mode[j] = -sgn(E->f[j]);
        if (s->mode[j] == 0) s->mode[j] = -sgn(s->F[j]);
        rest[j] = 0;
    }
    const int decided = rest_decide(E, s, s->t, rest, s->mode);
    for (size_t j = 0; j < nc; j++)
        if (s->mode[j] != E->smode[j]) report(s, j, E->smode[j], hk);
    if (ENG_HAS_JENKINS(E)) jenk_breakaways(E, s);
    restart(E, s, s->t, decided);
    /* a slide from rest starts at its start magnitude (Stribeck: mu_s N) and never against its way */
    for (size_t j = 0; j < nc; j++) {
        if (E->smode[j] == s->mode[j] || s->mode[j] == 0 || !has_friction(E, j)) continue;
        s->F[j] = -s->mode[j] * slide_mag(E, j, 0.0);
    }
}

/* The model's fused grid step in the current modes (eng_sparse.step_held; E->st the modes, E->lim
 * their limits, the loads at t1 set): ENG_HELD_TAKEN, _TRIAL (a contact's margin is not positive:
 * T and the engine's arrays hold the trial and its basis solve), _UNTRIED (A needs re-basing) or
 * _ERROR (M_hat not positive definite). */
static ENG_HOT int held_step(eng *E, eng_state *s, double t1, trial *T)
{
    const eng_setup *S = &E->S;
    const dfo_bossak_kin *K = &E->kin_grid;
    const double a = S->alpha;
    /* (held_ready: held_steps found no re-basing for this state) */
    if (!E->held_ready && needs_rebase(E, s, S->h)) return ENG_HELD_UNTRIED;
    const double cM = (1.0 - a) * K->c1, cK = E->b * S->h / E->g;
    if (!factor_slot(E, ENG_SLOT_GRID, cM, 1.0, cK)) return ENG_HELD_ERROR;
    double cw = 0.0, sw = 0.0;
    if (S->exc.Pc || S->exc.Ps) phase_of(E, s, t1, &cw, &sw);
    const eng_held_step F = {ENG_SLOT_GRID, cM, ENG_HAS_C(E) ? 1.0 : 0.0, cK, K->h, a, E->g1, K->c1, K->pred_V,
                             K->pred_A, K->corr_V, cw, sw, S->exc.Pc, S->exc.Ps, E->u, s->A, E->st, E->lim,
                             E->Fb, E->xp, E->ph, E->V1, E->f, 0};
    if (!E->held_ready && ENG_STEP_HELD(E, &F, s)) return ENG_HELD_TAKEN;
    E->held_ready = 0;
    T->kin = *K;
    T->sl = s->slider;
    T->slot = F.slot;
    T->cM = F.cM;
    T->cC = 1.0;
    T->cK = F.cK;
    memcpy(E->A0, s->A, ENG_N(E) * sizeof(double));
    return ENG_HELD_TRIAL;
}

static ENG_COLD int step_spans(eng *E, const eng_inputs *in, eng_state *s, double t_end, double hh, const trial *T,
                               eng_status *out);

/* The earliest closed-form breakaway of the candidates (eng_sparse.contact_breakaway; each into
 * E->tbk) where every candidate is a held contact with one, held inputs and still belts; NaN else. */
static double closed_breakaways(eng *E, const eng_inputs *in, const eng_state *s)
{
    if (!ENG_HAS_CONTACT_BREAKAWAY(E) || ramped(in) || E->vb != E->zero_nc) return NAN;
    double tb = INFINITY;
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (!E->cand[j]) continue;
        if (E->st[j] != 0) return NAN;
        const double t = ENG_CONTACT_BREAKAWAY(E, j, s, in, E->Fb);
        if (!(t < INFINITY)) return NAN;
        E->tbk[j] = t;
        tb = fmin(tb, t);
    }
    return tb;
}

/* Spans are taken with held inputs and no hooks (a switch callback, an observer or a stop at the
 * first switch step the whole structure). */
static int spans_usable(const eng *E, const eng_inputs *in, const eng_hooks *hk)
{
    return E->sub && !ramped(in) && !(hk && (hk->on_switch || hk->obs || hk->stop_at_switch));
}

/* Every contact held on a still belt, every DOF pinned at rest by a held contact of its own, held
 * inputs: the state the model's closed-form breakaway (ENG_BREAKAWAY) is asked about. The loads
 * must be set. */
static int stuck_pinned(eng *E, const eng_inputs *in, const eng_state *s)
{
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    if (!E->pin_all || ramped(in)) return 0;
    for (size_t j = 0; j < nc; j++)
        if (s->mode[j] != 0 || !has_friction(E, j) || E->vb[j] != 0.0) return 0;
    for (size_t i = 0; i < n; i++)
        if (s->V[i] != 0.0 || s->A[i] != 0.0) return 0;
    return 1;
}

/* stuck_pinned where no contact slides (the test inline: most calls are of a sliding structure) */
static ENG_HOT int stuck_at_rest(eng *E, const eng_inputs *in, const eng_state *s)
{
    for (size_t j = 0; j < ENG_NC(E); j++)
        if (s->mode[j] != 0) return 0;
    return stuck_pinned(E, in, s);
}

static double stuck_breakaway(eng *E, const eng_state *s, const eng_inputs *in);

/* The breakaway of the stick of a structure at rest (stuck_at_rest): the state's (eng_state.stick_tb),
 * asked of the model where the state holds none or one passed. The loads must be set. */
static double stuck_tb(eng *E, const eng_inputs *in, eng_state *s)
{
    if (!(s->stick_tb > s->t))
        s->stick_tb = ENG_HAS_BREAKAWAY(E) ? ENG_BREAKAWAY(E, s, in, E->Fb) : stuck_breakaway(E, s, in);
    return s->stick_tb;
}

/* A stuck step of a structure at rest, as its trial leaves X (V = A = 0: any step's kinematics K) and
 * rest_exact the rest: X through the predictor and corrector with V1 = V, V at its belt (0), A and hA 0
 * (F, the time and the counters the caller's). */
static void stuck_rest(eng *E, eng_state *s, const dfo_bossak_kin *K)
{
    const eng_setup *S = &E->S;
    for (size_t i = 0; i < ENG_N(E); i++)
        s->X[i] = (s->X[i] + K->pred_V * s->V[i] + K->pred_A * s->A[i]) + K->corr_V * s->V[i];
    for (size_t j = 0; j < ENG_NC(E); j++) {
        const eng_row *R = &S->rows[j];
        if (R->nnz == 1) s->V[R->idx[0]] = E->vb[j] / R->w[0];
    }
    for (size_t i = 0; i < ENG_N(E); i++) {
        s->A[i] = 0.0;
        s->hA[i] = 0.0;
    }
}

/* A phase ended by the switches of the candidates (E->cand) at the state's time: the phase observed,
 * the switches applied (held: apply_switches'), the held contacts at rest exactly, the loads of the
 * step's end t_end again. */
static void switch_now(eng *E, const eng_inputs *in, eng_state *s, double ta, double t_end, int held,
                       const eng_hooks *hk)
{
    observe(E, s, ta, s->F, hk);
    apply_switches(E, s, 1, held, hk);
    rest_exact(E, s);
    loads_at(E, in, t_end);
}

#include "engine_tangent.h"

/* The located step (method.md sections 4 and 13): phases in the current modes, each ended at the
 * earliest switch of a contact. */
static ENG_HOT eng_status step_located(eng *E, const eng_inputs *in, eng_state *s, double t_end, double hh,
                               const eng_hooks *hk, int rest_known)
{
    const eng_setup *S = &E->S;
    const size_t nc = ENG_NC(E);
    const int tan = ENG_TANGENTS(E) && s->tan && !s->tan_lost;
    if (S->rate_max * hh > STIFF_STEP) {
        if (tan) s->tan_lost = 1; /* (the consistent test's step: no tangent) */
        return step_lcp(E, in, s, t_end, hh, 1, hk);
    }
    const long max_phases = MAX_PHASES_BASE + 4 * (long)nc;
    const long long sw0 = s->switches;
    const int stop = hk && hk->stop_at_switch;
    for (long phase = 0; s->t < t_end; phase++) {
        if (phase >= max_phases) return ENG_ERR_NO_PROGRESS;
        if (E->ghost) ghosts_now(E, s);
        double ta;
        begin_phase(E, s, &ta, hk);
        if (ENG_HAS_JENKINS(E)) jenk_phase_forces(E, s);
        const double r = (phase == 0) ? hh : t_end - s->t;
        /* a declined fused step of the state as it is (held_steps', fused_steps') has set the modes
         * and limits of its trial as below (the same modes: it switched none) */
        const int ready = phase == 0 && (E->held_ready || E->fused_ready);
        if (ready) {
            if (nc) memset(E->cand, 0, nc * sizeof(int));
        } else {
            for (size_t j = 0; j < nc; j++) {
                E->st[j] = (has_friction(E, j) && s->mode[j] == 0) ? 0 : s->mode[j];
                if (!has_friction(E, j)) E->st[j] = 1; /* (no force: its mode is not read) */
                E->cand[j] = 0;
            }
        }
        /* a structure stuck at rest: its stick ends at the model's closed-form breakaway (ENG_BREAKAWAY),
         * found where the stick first needs it and kept in the state (stuck_tb), as the old stepper
         * ends it. A step that ends before it is a stuck step, taken as the stuck fast path takes one
         * (stuck_rest: X through the predictor and corrector with V = A = 0, to the bits of the
         * trial; F left). Inside the step, the switch is placed there without a trial (the structure
         * rests there, X, V = A = 0 as they are; the holding forces solved at that time and clamped to
         * their limits; the contact most beyond its limit released). Models with their contacts'
         * closed forms split the step at those instead (closed_breakaways, below). */
        const int known = (phase == 0) ? rest_known : 0; /* (eng_advance asked it of this state) */
        if (!tan && ENG_HAS_BREAKAWAY(E) && !ENG_HAS_CONTACT_BREAKAWAY(E) && known >= 0 &&
            (known == 1 || stuck_at_rest(E, in, s))) {
            double tp = (known == 1) ? s->stick_tb : stuck_tb(E, in, s);
            if (tp > t_end) {
                stuck_rest(E, s, &E->kin_grid);
                s->t = t_end;
                s->solves++;
                observe(E, s, ta, s->F, hk);
                return ENG_OK;
            }
            if (tp > s->t) {
                /* (the first time from the closed form's on, by ulps doubling, at which a holding force is
                 * at or beyond its limit, so that the switch's time does not follow the closed form's
                 * rounding; where none is within PLACE_NUDGES, the closed form's last) */
                double ulp = 0.0;
                size_t jmax = nc;
                for (int k = 0;; k++) {
                    s->t = tp;
                    if (E->ghost) ghosts_now(E, s);
                    loads_at(E, in, s->t);
                    phys_accel(E, s, s->t, s->mode, E->y2, E->f);
                    jmax = nc;
                    for (size_t j = 0; j < nc; j++)
                        if (jmax == nc || fabs(E->f[j]) / E->Fb[j] > fabs(E->f[jmax]) / E->Fb[jmax]) jmax = j;
                    if (!(fabs(E->f[jmax]) < E->Fb[jmax]) || k == PLACE_NUDGES || tp == t_end) break;
                    ulp = (ulp == 0.0) ? nextafter(tp, INFINITY) - tp : 2.0 * ulp;
                    tp = (tp + ulp < t_end) ? tp + ulp : t_end;
                }
                for (size_t j = 0; j < nc; j++) s->F[j] = clamp_lim(E->f[j], E->Fb[j]);
                for (size_t j = 0; j < nc; j++) E->cand[j] = j == jmax;
                switch_now(E, in, s, ta, t_end, 1, hk);
                if (stop && s->switches != sw0) return ENG_SWITCHED;
                continue;
            }
        }
        trial T;
        int fused = ENG_HELD_UNTRIED;
        if (phase == 0 && !tan && fused_ok(E, in, hh)) {
            if (!ready)
                for (size_t j = 0; j < nc; j++) E->lim[j] = (E->st[j] == 0) ? E->Fb[j] : E->mlN[j];
            fused = held_step(E, s, t_end, &T);
            if (fused == ENG_HELD_ERROR) return ENG_ERR_BAD_INPUT;
            if (fused == ENG_HELD_TAKEN) {
                held_done(E, s, t_end, 1, ta, hk);
                return ENG_OK;
            }
        }
        margin_ctx mc;
        margin_init(&mc, E, in, s, t_end, r);
        if (phase == 0 && E->fused_ready) { /* fused_steps' trial of this grid step, solved (as held_step's) */
            T.kin = E->kin_grid;
            T.sl = s->slider;
            T.slot = ENG_SLOT_GRID;
            T.cM = (1.0 - S->alpha) * T.kin.c1;
            T.cC = 1.0;
            T.cK = E->b * hh / E->g;
            fused = ENG_HELD_TRIAL;
            if (ENG_HAS_JENKINS(E)) jenk_stuck_forces(E, s, &T, E->V1, E->f);
        }
        E->fused_ready = 0;
        if (fused != ENG_HELD_TRIAL) trial_margin(&mc, r, &T); /* (else the fused step's trial, solved) */
        s->solves++;
        if (mc.err != ENG_OK) return mc.err;
        size_t ncand = 0;
        for (size_t j = 0; j < nc; j++) {
            const int c = has_friction(E, j) & switches(E, E->st, j, E->V1, E->f); /* (cand is 0 here) */
            E->cand[j] = c;
            ncand += (size_t)c;
        }
        if (ncand == 0) {
            if (tan) tan_accept(E, in, s, &T, t_end, 0, 0);
            finish(E, s, &T, E->V1, E->f, t_end);
            s->t = t_end;
            free_modes(E, s, hk);
            rest_exact(E, s);
            if (tan) tan_rest_exact(E, s);
            observe(E, s, ta, s->F, hk);
            return ENG_OK;
        }
        if (phase == 0) s->pivot_steps++;
        if (phase == 0 && !tan && spans_usable(E, in, hk)) {
            eng_status sst;
            if (step_spans(E, in, s, t_end, hh, &T, &sst)) return sst;
        }
        /* held contacts breaking away with closed forms: the step split at the earliest at once (a
         * breakaway at the phase's start itself, e.g. a limit below the rounding of the force, is
         * the margins' root instead: the closed form's time is passed, the force not yet beyond) */
        const double tb = tan ? NAN : closed_breakaways(E, in, s);
        if (tb > s->t && tb <= t_end) {
            const double hs = tb - s->t;
            if (hs > 0.0) {
                trial_margin(&mc, (tb == t_end) ? r : hs, &T);
                s->solves++;
                if (mc.err != ENG_OK) return mc.err;
                finish(E, s, &T, E->V1, E->f, tb);
            }
            s->t = tb;
            if (E->ghost) ghosts_now(E, s);
            for (size_t j = 0; j < nc; j++) E->cand[j] = E->cand[j] && E->tbk[j] == tb;
            loads_at(E, in, s->t);
            switch_now(E, in, s, ta, t_end, 0, hk);
            if (stop && s->switches != sw0) return ENG_SWITCHED;
            continue;
        }
        /* bracket the first switch: (lo, hi] with margin(lo) > 0 >= margin(hi) */
        double hi = r, ghi = INFINITY, lo = 0.0, glo = INFINITY, gscale = 0.0;
        for (size_t j = 0; j < nc; j++) {
            if (!E->cand[j]) continue;
            ghi = fmin(ghi, margin(E, E->st, j, E->V1, E->f));
            glo = (E->st[j] != 0) ? fmin(glo, E->st[j] * slip(E, j, s->V)) : -INFINITY;
            if (S->margin_rounding > 0.0) /* (the margin's terms: the slip's, or the force and its limit) */
                gscale = fmax(gscale, (E->st[j] != 0) ? row_abs_dot(&S->rows[j], E->V1) + fabs(E->vb[j])
                                                      : E->Fb[j] + fabs(E->f[j]));
        }
        if (!(glo > 0.0)) {
            lo = r;
            glo = -INFINITY;
            for (int it = 0; it < HALVINGS && !(glo > 0.0); it++) {
                lo *= 0.5;
                glo = margin_fn(&mc, lo);
                s->solves++;
            }
            if (mc.err != ENG_OK) return mc.err;
        }
        if (!(glo > 0.0)) { /* nothing resolvable before the switch: it happens now */
            /* (to the candidates whose margin is not positive even in the shortest trial: a sliding
             * one that slides on there is not stopping now, and setting its slip to 0 would jump its
             * velocity; it switches in a later phase, found by the search) */
            for (size_t j = 0; j < nc; j++)
                if (E->cand[j] && margin(E, E->st, j, E->V1, E->f) > 0.0) E->cand[j] = 0;
            loads_at(E, in, s->t);
            for (size_t j = 0; j < nc; j++)
                if (E->cand[j] && s->mode[j] != 0 && !is_jenk(E, j)) {
                    const eng_row *R = &S->rows[j];
                    if (R->nnz == 1) s->V[R->idx[0]] = E->vb[j] / R->w[0];
                    if (R->nnz == 1 && tan) /* (its velocity's derivative 0 likewise) */
                        for (size_t c = 0; c < tan_nz(E); c++) s->tan[c * tan_L(E) + TAN_VO(ENG_N(E)) + R->idx[0]] = 0.0;
                }
            apply_switches(E, s, 1, 0, hk);
            if (tan) tan_switched(E, in, s);
            loads_at(E, in, t_end);
            observe(E, s, ta, s->F, hk);
            if (stop && s->switches != sw0) return ENG_SWITCHED;
            continue;
        }
        double hs = dfo_root_bracketed(margin_fn, &mc, s->t, lo, glo, hi, ghi, S->margin_rounding * DBL_EPSILON * gscale);
        if (isnan(hs)) hs = hi; /* (no bracket: only a NaN margin, reported as an error below) */
        trial_again(&mc, hs, &T); /* (the root's last trial where it was of hs) */
        s->solves++;
        if (mc.err != ENG_OK) return mc.err;
        const double t_new = (hs >= r) ? t_end : fmax(s->t + hs, nextafter(s->t, INFINITY));
        const int rooted = tan && t_new < t_end && tan_root(E, in, s, &T, t_new); /* (d hs, the phase's modes) */
        /* a stopping contact ends the sub-step at rest: solved again with it held (its slip 0) */
        int again = 0;
        for (size_t j = 0; j < nc; j++) {
            E->jstop[j] = 0;
            if (E->cand[j] && E->st[j] != 0 && margin(E, E->st, j, E->V1, E->f) <= 0.0 && is_jenk(E, j)) {
                E->jstop[j] = 1; /* a slider stops: the sub-step slid to its end, the slider sticks there */
                continue;
            }
            if (E->cand[j] && E->st[j] != 0 && margin(E, E->st, j, E->V1, E->f) <= 0.0) {
                E->st[j] = 0;
                E->lim[j] = E->Fb[j];
                again = 1;
            }
        }
        if (again) {
            const eng_status st = solve_trial(E, &T, ENG_SOLVE_BASIS, E->st, E->V1, E->f, NULL);
            if (st != ENG_OK) return st;
            if (ENG_HAS_JENKINS(E)) jenk_stuck_forces(E, s, &T, E->V1, E->f);
            for (size_t j = 0; j < nc; j++) /* the stopped ones slide on in the sub-step's account */
                if (E->cand[j] && s->mode[j] != 0) E->f[j] = -s->mode[j] * E->mlN[j];
        }
        if (tan) tan_accept(E, in, s, &T, t_new, t_new < t_end, rooted && !again);
        finish(E, s, &T, E->V1, E->f, t_new);
        s->t = t_new;
        if (E->ghost) ghosts_now(E, s);
        loads_at(E, in, s->t);
        /* the margins at the switch: a stopped contact (slip 0) and a held one beyond its limit */
        for (size_t j = 0; j < nc; j++) {
            if (!E->cand[j]) continue;
            const int stopping = s->mode[j] != 0 && (E->st[j] == 0 || E->jstop[j]);
            const int breaking = s->mode[j] == 0 && !(fabs(E->f[j]) < E->Fb[j]);
            E->cand[j] = stopping || breaking;
        }
        switch_now(E, in, s, ta, t_end, 0, hk);
        if (tan) {
            tan_switched(E, in, s);
            loads_at(E, in, t_end); /* (the loads of the step's end again, as switch_now leaves them) */
        }
        if (stop && s->switches != sw0) return ENG_SWITCHED;
    }
    return ENG_OK;
}

/* ---- spans ---------------------------------------------------------------------------------- */

/* DOF i of state d := DOF k of state s (X, V, A, hA); contact j of d := contact k of s (F, mode,
 * stick start, breakaway and its side). */
static void dof_copy(eng_state *d, size_t i, const eng_state *s, size_t k)
{
    d->X[i] = s->X[k];
    d->V[i] = s->V[k];
    d->A[i] = s->A[k];
    d->hA[i] = s->hA[k];
}

static void contact_copy(eng_state *d, size_t j, const eng_state *s, size_t k)
{
    d->F[j] = s->F[k];
    d->mode[j] = s->mode[k];
    d->t_stick[j] = s->t_stick[k];
    d->t_break[j] = s->t_break[k];
    d->break_dir[j] = s->break_dir[k];
}

/* One located step of the sub-engine (a span): outside step_located, so that the scheme is not
 * inlined into itself. */
static ENG_COLD eng_status step_located_sub(eng *B, const eng_inputs *in, eng_state *b, double t_end, double hh)
{
    return step_located(B, in, b, t_end, hh, NULL, 0); /* (no stuck_until asked of a span) */
}

/* The located step with contacts switching (E->cand) by spans (eng_sparse.span): the whole step in
 * the current modes (the trial T, solved in E->V1, E->f), then each span stepped again on its own by
 * the sub-engine from the step's start, its ghosts interpolated between their states at the step's
 * start and end. Returns 0 when the model gives no span (the whole structure is stepped as it is),
 * else 1 with the step's status in *out. */
static ENG_COLD int step_spans(eng *E, const eng_inputs *in, eng_state *s, double t_end, double hh, const trial *T,
                               eng_status *out)
{
    const eng_setup *S = &E->S;
    const eng_sparse *sp = S->sparse;
    const size_t n = ENG_N(E), nc = ENG_NC(E), L = sp->span_max;
    size_t *dr = E->drng, *cr = E->crng; /* each span's index ranges (its work its own size) */
    const size_t ns = sp->span(S->ops.ctx, E->cand, E->dlab, E->clab, dr, cr);
    if (ns == 0) return 0;
    if (ns > n) { *out = ENG_ERR_BAD_INPUT; return 1; } /* (a span holds a DOF) */
    size_t ncand = 0, inside = 0;
    for (size_t j = 0; j < nc; j++) ncand += (size_t)(E->cand[j] != 0);
    for (size_t k = 0; k < ns; k++) {
        if (!(dr[2 * k] <= dr[2 * k + 1] && dr[2 * k + 1] <= n && cr[2 * k] <= cr[2 * k + 1] && cr[2 * k + 1] <= nc)) {
            *out = ENG_ERR_BAD_INPUT;
            return 1;
        }
        for (size_t j = cr[2 * k]; j < cr[2 * k + 1]; j++) inside += E->cand[j] && E->clab[j] == (int)k + 1;
    }
    if (inside != ncand) return 0; /* a candidate in no span: the whole structure is stepped */
    *out = ENG_OK;
    /* the step's start where the spans read it */
    const eng_state *p = &E->ps;
    for (size_t k = 0; k < ns; k++) {
        for (size_t i = dr[2 * k]; i < dr[2 * k + 1]; i++) dof_copy(&E->ps, i, s, i);
        for (size_t j = cr[2 * k]; j < cr[2 * k + 1]; j++) contact_copy(&E->ps, j, s, j);
    }
    const double t_start = s->t;
    /* everything in the current modes first */
    finish(E, s, T, E->V1, E->f, t_end);
    s->t = t_end;
    if (!E->all_friction)
        for (size_t j = 0; j < nc; j++)
            if (!has_friction(E, j)) s->mode[j] = sgn(slip(E, j, s->V));
    rest_exact(E, s);
    eng *B = E->sub;
    eng_state *b = &E->ss;
    for (size_t k = 0; k < ns; k++) {
        const int lab = (int)k + 1;
        size_t nd = 0, nct = 0;
        for (size_t i = dr[2 * k]; i < dr[2 * k + 1]; i++) {
            if (E->dlab[i] != lab && E->dlab[i] != -lab) continue;
            if (nd == L) { *out = ENG_ERR_BAD_INPUT; return 1; }
            E->gmap[i] = (long)nd;
            E->ldof[nd] = i;
            E->lgh[nd++] = E->dlab[i] < 0;
        }
        for (size_t j = cr[2 * k]; j < cr[2 * k + 1]; j++) {
            if (E->clab[j] != lab && E->clab[j] != -lab) continue;
            if (nct == L) { *out = ENG_ERR_BAD_INPUT; return 1; }
            E->lct[nct++] = j;
        }
        /* the span's contacts: rows in the local numbering, data, inputs */
        for (size_t a = 0; a < nct; a++) {
            const size_t j = E->lct[a];
            const eng_row *R = &S->rows[j];
            const int own = E->clab[j] > 0;
            size_t *idx = E->lidx + a * E->lnnz; /* (lrows[a] points there) */
            double *w = E->lrw + a * E->lnnz;
            for (size_t q = 0; q < R->nnz; q++) {
                const size_t g = R->idx[q]; /* (a label outside the span's range: none) */
                const int dl = (g >= dr[2 * k] && g < dr[2 * k + 1]) ? E->dlab[g] : 0;
                if (dl != lab && dl != -lab) { *out = ENG_ERR_BAD_INPUT; return 1; } /* a row off the span */
                idx[q] = (size_t)E->gmap[R->idx[q]];
                w[q] = R->w[q];
            }
            E->lrows[a].nnz = R->nnz;
            E->lN[a] = own ? S->N[j] : 0.0; /* a carried contact: no friction */
            E->lmus[a] = own ? S->mu_s[j] : 0.0;
            E->lmuk[a] = own ? S->mu_k[j] : 0.0;
            if (S->law) E->llaw[a] = S->law[j];
            B->mu_b[a] = fmax(E->lmus[a], E->lmuk[a]);
            E->lNe[a] = (own && in && in->N_ext) ? in->N_ext[j] : 0.0;
            E->lvb[a] = (in && in->v_belt) ? in->v_belt[j] : 0.0;
            contact_copy(b, a, p, j);
        }
        B->any_law = 0;
        for (size_t a = 0; a < nct; a++) B->any_law |= S->law && E->llaw[a].law == DFO_LAW_STRIBECK && E->lN[a] > 0.0;
        /* the span's DOFs, its ghosts' motion over the step */
        size_t ngh = 0;
        B->gt0 = t_start;
        B->gH = t_end - t_start;
        for (size_t q = 0; q < nd; q++) {
            const size_t i = E->ldof[q];
            if (S->exc.Pc) E->lPc[q] = S->exc.Pc[i];
            if (S->exc.Ps) E->lPs[q] = S->exc.Ps[i];
            E->lF[q] = (in && in->F_ext) ? in->F_ext[i] : 0.0;
            B->ghost[q] = E->lgh[q];
            if (E->lgh[q]) B->gidx[ngh++] = q;
            B->gX0[q] = p->X[i];
            B->gV0[q] = p->V[i];
            B->gX1[q] = s->X[i];
            B->gV1[q] = s->V[i];
            dof_copy(b, q, p, i);
        }
        B->ngh = ngh;
        B->S.n = b->n = nd;
        B->S.nc = b->nc = nct;
        B->loads_for = NULL;
        for (int slot = 0; slot < ENG_NSLOTS; slot++) B->slot_ok[slot] = 0;
        sp->span_bind(S->ops.ctx, E->ldof, E->lgh, nd, E->lct, nct);
        B->pin_all = eng_pin_all(B);
        B->rest_apart = eng_rest_apart(B);
        b->t0 = s->t0;
        b->t = t_start;
        b->n_grid = s->n_grid;
        b->exc_n = s->exc_n;
        b->exc_c = s->exc_c;
        b->exc_s = s->exc_s;
        b->t_switch = s->t_switch;
        b->stick_tb = NAN;
        b->steps = b->solves = b->pivot_steps = b->switches = 0;
        const eng_inputs bin = {E->lF, E->lNe, (in && in->v_belt) ? E->lvb : NULL, {NULL, NULL}, {NULL, NULL},
                                in ? in->t_ref : 0.0};
        loads_at(B, &bin, t_end);
        const eng_status st = step_located_sub(B, &bin, b, t_end, hh);
        if (st != ENG_OK) { *out = st; return 1; }
        /* the span's A re-based on a grid step now, as the next step of the whole structure would
         * (there over all of it) */
        B->jk_ok = B->rpin_ok = 0; /* (the span's state, not a phase of B's) */
        rebase(B, &bin, b, S->h, t_end);
        const double tol = 1e-12 * S->h + 4.0 * DBL_EPSILON * fabs(b->t);
        for (size_t q = 0; q < nd; q++)
            if (!E->lgh[q] && rebases(B, b, q, S->h, tol) && !B->rpin[q]) {
                b->A[q] = B->A0[q];
                b->hA[q] = S->h;
            }
        for (size_t q = 0; q < nd; q++)
            if (!E->lgh[q]) dof_copy(s, E->ldof[q], b, q);
        for (size_t a = 0; a < nct; a++)
            if (E->clab[E->lct[a]] > 0) contact_copy(s, E->lct[a], b, a);
        s->solves += b->solves;
        s->switches += b->switches;
        if (b->switches) s->t_switch = fmax(s->t_switch, b->t_switch);
    }
    return 1;
}

/* ---- the fused steps -------------------------------------------------------------------------- */

/* Every X, V, A finite (|x| <= DBL_MAX is false for infinities and NaN) */
static ENG_HOT int finite_all(size_t n, const double *X, const double *V, const double *A)
{
    int ok = 1;
    for (size_t i = 0; i < n; i++) ok &= (fabs(X[i]) <= DBL_MAX) & (fabs(V[i]) <= DBL_MAX) & (fabs(A[i]) <= DBL_MAX);
    return ok;
}

/* A run of fused steps written back: its time, grid point, excitation cache and counters. */
static ENG_HOT void run_store(eng_state *s, double t, long long ng, long long exc_n, double exc_c, double exc_s,
                              long long steps, long long solves)
{
    s->t = t;
    s->n_grid = ng;
    s->exc_n = exc_n;
    s->exc_c = exc_c;
    s->exc_s = exc_s;
    s->steps += steps;
    s->solves += solves;
}

/* The common step, fused: a whole grid step from a grid point, held inputs, in which the modes hold
 * (located: the trial in the current modes has no switching contact; paper and consistent: the
 * friction problem warm-started from the current modes returns them), taken in a tight loop over
 * the grid points up to t_target with none of the general path's phase bookkeeping. The same
 * arithmetic as step_located's and step_lcp's in the same order, so the same numbers. A model
 * whose sizes are constants (ENG_FUSED_N, ENG_FUSED_NC) gets the loop's state in local arrays,
 * which the compiler keeps in registers; otherwise it works on the state in place. The loop stops,
 * the state untouched by the step it declines, before a step that would switch (the general path
 * takes it), that re-bases A (a step length other than that of A, off a pinned DOF), a stuck
 * structure the stuck fast path may skip (skip), a friction problem that fails, and a step past
 * t_target. The observer is called for the steps that overlap its window, as the general path
 * does. *g_prev: the last grid point reached. declined: the stuck fast path declined the first grid
 * point (the step from it is taken here, to the bits of the general path's). A declined located step
 * leaves its trial, solved, for step_located (fused_ready). */
static ENG_HOT void fused_steps(eng *E, eng_state *s, double t_target, int skip, int declined, const eng_hooks *hk,
                                double *g_prev)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    const double h = S->h, a = S->alpha;
    const int located = S->scheme == DFO_SCHEME_LOCATED, consistent = S->scheme == DFO_SCHEME_CONSISTENT;
    if (located && S->rate_max * h > STIFF_STEP) return;
    const dfo_bossak_kin K = E->kin_grid;
    const double cM = (1.0 - a) * K.c1, cK = E->b * h / E->g;
    if (!factor_slot(E, ENG_SLOT_GRID, cM, 1.0, cK)) return;
    const eng_observer *obs = (hk && hk->obs && hk->obs->on_phase) ? hk->obs : NULL;
    /* the observer's window and the belts, read once (a store through the state may not change them) */
    const double obs_t0 = obs ? obs->t_start : 0.0, obs_t1 = obs ? obs->t_stop : 0.0;
    /* every step observed: the first grid point in the window, t_target at most its end */
    const int obs_all = obs && !(s->t0 + (double)(s->n_grid + 1) * S->h < obs_t0) && !(t_target > obs_t1);
    const int obs_vel = obs && obs->velocities; /* (the phases' velocities asked for) */
    const double *const vb_obs = (E->vb == E->zero_nc) ? NULL : E->vb;
    ENG_OBS_RUN obs_run; /* the observer's values over the run (ENG_OBS_RUN_BEGIN) */
    ENG_OBS_RUN_BEGIN(obs, obs_run, s);
    const eng_harmonic *H = &S->exc;
    eng_problem P;
    P.slot = ENG_SLOT_GRID;
    P.h = K.h;
    P.cM = cM;
    P.cC = ENG_HAS_C(E) ? 1.0 : 0.0;
    P.cK = cK;
    P.vb = E->vb;
    P.N = E->Nn;
    P.law = E->any_law ? S->law : NULL;
    P.comp = NULL; /* (no Jenkins contact in a run of fused steps) */
#if ENG_FUSED_LOCAL
    double X[ENG_FUSED_N], V[ENG_FUSED_N], A[ENG_FUSED_N], hA[ENG_FUSED_N], X0[ENG_FUSED_N];
    double xp[ENG_FUSED_N], r[ENG_FUSED_N], y[ENG_FUSED_N], y2[ENG_FUSED_N], ph[ENG_FUSED_N], V1[ENG_FUSED_N];
    double X1[ENG_FUSED_N], F1[ENG_FUSED_NC + 1]; /* the observed phase's end (copies: X, F stay in registers) */
    double V0o[ENG_FUSED_N], V1o[ENG_FUSED_N];    /* (and its velocities at both ends) */
    double F[ENG_FUSED_NC + 1], f[ENG_FUSED_NC + 1], lim[ENG_FUSED_NC + 1];
    int mode[ENG_FUSED_NC + 1], st[ENG_FUSED_NC + 1], mode0[ENG_FUSED_NC + 1], pin[ENG_FUSED_N];
    /* the state's arrays, their addresses read once (a store through one may not change them) */
    double *const sX = s->X, *const sV = s->V, *const sA = s->A, *const shA = s->hA, *const sF = s->F;
    int *const smode = s->mode;
    for (size_t i = 0; i < n; i++) {
        X[i] = s->X[i];
        V[i] = s->V[i];
        A[i] = s->A[i];
        hA[i] = s->hA[i];
    }
    for (size_t j = 0; j < nc; j++) {
        F[j] = s->F[j];
        mode[j] = s->mode[j];
    }
#define ENG_FUSED_STORE_()                                                                                          \
    do {                                                                                                            \
        for (size_t i_ = 0; i_ < n; i_++) {                                                                         \
            sX[i_] = X[i_];                                                                                         \
            sV[i_] = V[i_];                                                                                         \
            sA[i_] = A[i_];                                                                                         \
            shA[i_] = hA[i_];                                                                                       \
        }                                                                                                           \
        for (size_t j_ = 0; j_ < nc; j_++) {                                                                        \
            sF[j_] = F[j_];                                                                                         \
            smode[j_] = mode[j_];                                                                                   \
        }                                                                                                           \
    } while (0)
#else
    double *const X = s->X, *const V = s->V, *const A = s->A, *const hA = s->hA, *const X0 = E->X0;
    const double *const X1 = s->X, *const F1 = s->F, *const V1o = s->V;
    double *const V0o = E->V0;
    double *const xp = E->xp, *const r = E->r, *const y = E->y, *const y2 = E->y2, *const ph = E->ph, *const V1 = E->V1;
    double *const F = s->F, *const f = E->f, *const lim = E->lim;
    int *const mode = s->mode, *const st = E->st, *const mode0 = E->mode0, *const pin = E->pin;
#define ENG_FUSED_STORE_() ((void)0)
#endif
    P.p_hat = ph;
    P.limit = lim;
    long long ng = s->n_grid, steps = 0, solves = 0, pivot_steps = 0;
    long long exc_n = s->exc_n;
    /* the turns of contacts without friction, where reported (eng_hooks.report_turns): the modes
     * before the run's last step (scratch: smode) */
    const int turns = hk && hk->report_turns && !E->all_friction;
    int turned = 0, *const turn_from = E->smode;
    double exc_c = s->exc_c, exc_s = s->exc_s, t = s->t;
    /* (located: the modes and limits of the run's basis solves, which do not change them; the others
     * set theirs per step) */
    for (size_t j = 0; j < nc; j++) {
        st[j] = !has_friction(E, j) ? 1 : mode[j];
        lim[j] = (st[j] == 0) ? E->Fb[j] : E->mlN[j];
    }
    int held_modes = 0; /* every contact held on a still belt, every DOF pinned by one of them */
    int rest_pins = 0;  /* (located, consistent) a held contact pins a DOF alone: rest_exact's */
    const int free_any = !E->all_friction; /* contacts without friction: their modes follow their slips */
    for (;;) {
        const double grid = s->t0 + (double)(ng + 1) * h;
        if (!(grid <= t_target) || !(grid > t)) break;
        if ((steps & 15) == 15 && !finite_all(n, X, V, A)) break; /* (overflowed: eng_advance fails) */
        /* held and pinned: the stuck fast path's to try (but where it declined: this grid point's step);
         * a step length to re-base A on: the general path's. Both from the run's first step: its modes
         * hold over the run (a step that would switch one ends it), and after a taken step A is of the
         * grid's length, or 0 on a pinned DOF, so that only the first may re-base. */
        if (steps == 0) {
            int rebase = 0;
            held_modes = 1;
            rest_pins = 0;
            for (size_t i = 0; i < n; i++) pin[i] = 0;
            for (size_t j = 0; j < nc; j++) {
                const int held = mode[j] == 0 && has_friction(E, j);
                held_modes &= held && E->vb[j] == 0.0;
                if (held && S->rows[j].nnz == 1) {
                    pin[S->rows[j].idx[0]] = 1;
                    rest_pins = located || consistent;
                }
            }
            const double tol = 1e-12 * h + 4.0 * DBL_EPSILON * fabs(t);
            for (size_t i = 0; i < n; i++) {
                held_modes &= pin[i];
                rebase |= !pin[i] && a != 0.0 && rebases_len(S, hA[i], h, tol);
            }
            if (rebase) break;
        }
        if (skip && held_modes && !(declined && steps == 0)) {
            int rest = 1;
            for (size_t i = 0; i < n; i++) rest &= V[i] == 0.0 && A[i] == 0.0;
            if (rest) break;
        }
        /* the excitation at the grid point: the cache's rotation (dfo_grid_phase) */
        double cw, sw;
        dfo_grid_phase(H->omega, H->phi0, s->t0, h, E->rot_c, E->rot_s, exc_n, exc_c, exc_s, ng + 1, &cw, &sw);
        /* the trial (trial_step, A0 = A) */
        for (size_t i = 0; i < n; i++) {
            xp[i] = X[i] + K.pred_V * V[i] + K.pred_A * A[i];
            r[i] = -a * A[i] + (1.0 - a) * (V[i] * K.c1 + E->g1 * A[i]);
        }
        ENG_APPLY_M(E, r, y);
        {
            const double cwc = dfo_clamp1(cw), swc = dfo_clamp1(sw);
            for (size_t i = 0; i < n; i++) {
                double p = E->u[i];
                if (H->Pc) p += H->Pc[i] * cwc;
                if (H->Ps) p -= H->Ps[i] * swc;
                ph[i] = p;
            }
        }
        ENG_APPLY_K(E, xp, y2);
        for (size_t i = 0; i < n; i++) ph[i] += y[i] - y2[i];
        /* the friction problem in the current modes */
        int piv = 0;
        eng_status fs;
        if (located) {
            fs = ENG_HAS_FRICTION(E) ? ENG_FRICTION(E, &P, ENG_SOLVE_BASIS, st, V1, f, NULL)
                                     : ENG_FN(eng_dense_friction)(E, &P, ENG_SOLVE_BASIS, st, V1, f, NULL);
            if (fs != ENG_OK) break;
            int sw_any = 0;
            for (size_t j = 0; j < nc; j++) sw_any |= has_friction(E, j) & switches(E, st, j, V1, f);
            if (sw_any) { /* the trial, solved, for step_located's phase 0 (fused_ready) */
#if ENG_FUSED_LOCAL
                for (size_t i = 0; i < n; i++) {
                    E->xp[i] = xp[i];
                    E->ph[i] = ph[i];
                    E->V1[i] = V1[i];
                }
                for (size_t j = 0; j < nc; j++) {
                    E->f[j] = f[j];
                    E->st[j] = st[j];
                    E->lim[j] = lim[j];
                }
#endif
                for (size_t i = 0; i < n; i++) E->A0[i] = A[i];
                E->fused_ready = 1;
                break;
            }
        } else {
            for (size_t j = 0; j < nc; j++) {
                st[j] = mode[j];
                lim[j] = !has_friction(E, j) ? 0.0 : (mode[j] == 0) ? E->Fb[j] : E->mukN[j];
            }
            fs = ENG_HAS_FRICTION(E) ? ENG_FRICTION(E, &P, ENG_SOLVE_LCP, st, V1, f, &piv)
                                     : ENG_FN(eng_dense_friction)(E, &P, ENG_SOLVE_LCP, st, V1, f, &piv);
            if (fs != ENG_OK) break;
            int changed = 0;
            for (size_t j = 0; j < nc; j++) changed |= has_friction(E, j) && st[j] != mode[j];
            if (changed) break;
            if (consistent)
                for (size_t j = 0; j < nc; j++)
                    if (has_friction(E, j) && st[j] == 0) f[j] = clamp_lim(f[j], E->Fb[j]);
        }
        /* the step is taken: the grid point, its excitation cache, the counters */
        const double ta = t;
        const int observed = obs_all || (obs && !(grid < obs_t0) && !(ta > obs_t1));
        if (observed) {
            for (size_t i = 0; i < n; i++) X0[i] = X[i];
            if (obs_vel)
                for (size_t i = 0; i < n; i++) V0o[i] = V[i];
            for (size_t j = 0; j < nc; j++) mode0[j] = mode[j];
        }
        ng++;
        exc_n = ng;
        exc_c = cw;
        exc_s = sw;
        steps++;
        solves++;
        pivot_steps += piv > 0;
        /* finish */
        for (size_t i = 0; i < n; i++) {
            X[i] = xp[i] + K.corr_V * V1[i];
            A[i] = (V1[i] - V[i]) * K.c1 - E->g1 * A[i];
            V[i] = V1[i];
            hA[i] = K.h;
        }
        for (size_t j = 0; j < nc; j++) F[j] = f[j];
        t = grid;
        for (size_t j = 0; j < nc && free_any; j++) { /* (a turn to report ends the run: after it, its report) */
            if (has_friction(E, j)) continue;
            const int m = sgn(slip(E, j, V));
            turn_from[j] = mode[j];
            turned |= turns & (m != mode[j]);
            mode[j] = m;
        }
        if (rest_pins) /* rest_exact */
            for (size_t j = 0; j < nc; j++) {
                if (mode[j] != 0 || !has_friction(E, j)) continue;
                const eng_row *R = &S->rows[j];
                if (R->nnz == 1) {
                    V[R->idx[0]] = E->vb[j] / R->w[0];
                    A[R->idx[0]] = 0.0;
                    hA[R->idx[0]] = 0.0;
                }
            }
        if (observed) {
#if ENG_FUSED_LOCAL
            for (size_t i = 0; i < n; i++) X1[i] = X[i];
            if (obs_vel)
                for (size_t i = 0; i < n; i++) V1o[i] = V[i];
            for (size_t j = 0; j < nc; j++) F1[j] = F[j];
#else
            s->t = t;
            s->n_grid = ng;
#endif
            const eng_phase phs = {ta, t, X0, X1, mode0, F1, vb_obs, obs_vel ? V0o : NULL, obs_vel ? V1o : NULL};
            ENG_OBS_RUN_PHASE(obs, obs_run, &phs, s);
        }
        if (turned) break;
    }
    ENG_OBS_RUN_END(obs, obs_run);
    ENG_FUSED_STORE_();
#undef ENG_FUSED_STORE_
    run_store(s, t, ng, exc_n, exc_c, exc_s, steps, solves);
    s->pivot_steps += pivot_steps;
    if (steps > 0) *g_prev = t;
    if (turned)
        for (size_t j = 0; j < nc; j++)
            if (!has_friction(E, j) && s->mode[j] != turn_from[j]) report(s, j, turn_from[j], hk);
}

/* The model's fused grid step (eng_sparse.step_held) in a tight loop: the located scheme's grid
 * steps in which no contact switches, held inputs, no belts, no ghosts, one after the other, with
 * the general path's bookkeeping of such a step (eng_advance's grid point, step_located's phase of
 * one trial, held_step, held_done) done once where a taken step leaves it unchanged: the modes and
 * limits (a taken step switches no contact with friction), M_hat's factor, the re-basing test (after
 * a taken step A is of the grid's length, or 0 on a pinned DOF: only the run's first step may be
 * re-based, by trial_step's rebase). One run of the model's steps (eng_held_step.run: the model may
 * take F's data into its own layout once). The same arithmetic in the same order, so the same
 * numbers. Stops, the state untouched by the step it declines, before a step the model declines (the
 * general path takes it from there, from the declined trial unless it was re-based), a stuck
 * structure the stuck fast path may skip (skip), and a step past t_target. *g_prev: the last grid
 * point reached. */
static ENG_COLD void held_steps(eng *E, const eng_inputs *in, eng_state *s, double t_target, int skip,
                               const eng_hooks *hk, double *g_prev)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    const double h = S->h, a = S->alpha;
    if (S->rate_max * h > STIFF_STEP || !fused_ok(E, in, h)) return;
    /* the held contacts: rest_exact's (pinning a DOF alone, in its order, rl) and their DOFs (E->pin);
     * then needs_rebase's test on the other DOFs */
    int *const rl = E->tmode, *const pin = E->pin; /* (tmode: step_lcp's; rebase's calls use held) */
    size_t nrl = 0;
    int all_held = skip; /* the stuck fast path's pattern: every contact held, every DOF pinned */
    int frictionless = 0; /* contacts whose modes follow their slip */
    memset(pin, 0, n * sizeof(int));
    /* (and the steps' modes and limits, as step_located sets them, in the same pass) */
    for (size_t j = 0; j < nc; j++) {
        const int fr = has_friction(E, j), held = s->mode[j] == 0 && fr;
        frictionless |= !fr;
        all_held &= held;
        E->st[j] = !fr ? 1 : s->mode[j];
        E->lim[j] = held ? E->Fb[j] : E->mlN[j];
        if (held && S->rows[j].nnz == 1) {
            rl[nrl++] = (int)j;
            pin[S->rows[j].idx[0]] = 1;
        }
    }
    int rb = 0; /* the first step's A re-based (E->A0, by rebase as trial_step's) */
    if (a != 0.0) {
        int other = 0; /* (a DOF not pinned whose A is of another length: then rebases' test) */
        for (size_t i = 0; i < n; i++) other |= (h != s->hA[i]) & (pin[i] == 0);
        const double tol = 1e-12 * h + 4.0 * DBL_EPSILON * fabs(s->t);
        for (size_t i = 0; i < n && other && !rb; i++) rb = h != s->hA[i] && !pin[i] && rebases(E, s, i, h, tol);
    }
    const dfo_bossak_kin *K = &E->kin_grid;
    const double cM = (1.0 - a) * K->c1, cK = E->b * h / E->g;
    if (!factor_slot(E, ENG_SLOT_GRID, cM, 1.0, cK)) return;
    if (all_held) {
        for (size_t i = 0; i < n; i++) E->pin[i] = 0;
        for (size_t j = 0; j < nc; j++)
            if (S->rows[j].nnz == 1) E->pin[S->rows[j].idx[0]] = 1;
        for (size_t i = 0; i < n; i++) all_held &= E->pin[i];
    }
    const eng_observer *obs = (hk && hk->obs && hk->obs->on_phase) ? hk->obs : NULL;
    const double obs_t0 = obs ? obs->t_start : 0.0, obs_t1 = obs ? obs->t_stop : 0.0;
    const eng_harmonic *H = &S->exc;
    const int trig = H->Pc || H->Ps;
    eng_held_step F = {ENG_SLOT_GRID, cM, ENG_HAS_C(E) ? 1.0 : 0.0, cK, K->h, a, E->g1, K->c1, K->pred_V,
                       K->pred_A, K->corr_V, 0.0, 0.0, H->Pc, H->Ps, E->u, s->A, E->st, E->lim,
                       E->Fb, E->xp, E->ph, E->V1, E->f, 1};
    /* the state's time, grid index and excitation cache kept here, in s where the loop ends and for
     * the observer */
    const double t0 = s->t0, rc = E->rot_c, rs = E->rot_s;
    double t = s->t, ec = s->exc_c, es = s->exc_s;
    long long ng = s->n_grid, en = s->exc_n, steps = 0;
    const long long ng0 = ng;
    for (;;) {
        const double grid = t0 + (double)(ng + 1) * h;
        if (!(grid <= t_target) || !(grid > t)) break;
        if ((steps & 15) == 15 && !finite_all(n, s->X, s->V, s->A)) break; /* (overflowed: eng_advance fails) */
        if (all_held) { /* at rest: the stuck fast path's to try */
            int rest = 1;
            for (size_t i = 0; i < n; i++) rest &= s->V[i] == 0.0 && s->A[i] == 0.0;
            if (rest) break;
        }
        double c, sn; /* the grid point's excitation cache, as eng_advance's */
        dfo_grid_phase(H->omega, H->phi0, t0, h, rc, rs, en, ec, es, ng + 1, &c, &sn);
        if (trig) {
            F.cw = dfo_clamp1(c);
            F.sw = dfo_clamp1(sn);
        }
        const double ta = t;
        if (obs) {
            memcpy(E->X0, s->X, n * sizeof(double));
            if (nc) memcpy(E->mode0, s->mode, nc * sizeof(int));
        }
        if (rb) { /* a phase's start: its jerks afresh (begin_phase), the state's grid point and
                   * excitation cache the step's end, as eng_advance's step holds them (the loop's
                   * end restores them where the step is declined) */
            s->n_grid = ng + 1;
            s->exc_n = ng + 1;
            s->exc_c = c;
            s->exc_s = sn;
            E->jk_ok = 0;
            rebase(E, in, s, h, grid);
            F.A0 = E->A0;
        }
        if (!ENG_STEP_RUN(E, &F, s)) { /* declined: its trial for the general path's held_step (not
                                        * a re-based one: held_step takes A0 = A) */
            E->held_ready = !rb;
            break;
        }
        rb = 0;
        F.A0 = s->A;
        F.run = 2;
        ng++;
        en = ng;
        ec = c;
        es = sn;
        steps++;
        t = grid;
        if (frictionless)
            for (size_t j = 0; j < nc; j++)
                if (!has_friction(E, j)) s->mode[j] = sgn(slip(E, j, s->V));
        for (size_t k = 0; k < nrl; k++) { /* rest_exact */
            const eng_row *R = &S->rows[rl[k]];
            s->V[R->idx[0]] = E->vb[rl[k]] / R->w[0];
            s->A[R->idx[0]] = 0.0;
            s->hA[R->idx[0]] = 0.0;
        }
        if (obs && !(grid < obs_t0) && !(ta > obs_t1)) {
            run_store(s, t, ng, en, ec, es, steps, steps);
            steps = 0;
            observe(E, s, ta, s->F, hk);
        }
    }
    run_store(s, t, ng, en, ec, es, steps, steps);
    if (ng > ng0) *g_prev = t;
}

/* ---- driving -------------------------------------------------------------------------------- */

ENG_API void ENG_FN(eng_start)(eng *E, const eng_inputs *in, double t0, const double *x0, const double *v0, eng_state *s)
{
    E->loads_for = NULL;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    s->t0 = s->t = t0;
    s->n_grid = 0;
    s->exc_n = -1;
    s->exc_c = s->exc_s = 0.0;
    s->t_switch = -INFINITY;
    s->stick_tb = NAN;
    s->steps = s->solves = s->pivot_steps = s->switches = 0;
    s->W_applied = s->W_friction = s->D_damping = 0.0;
    for (size_t i = 0; i < n; i++) {
        s->X[i] = x0[i];
        s->V[i] = v0[i];
        s->hA[i] = 0.0;
    }
    loads_at(E, in, t0);
    for (size_t j = 0; j < nc; j++) {
        /* (a slip within rounding of 0, of the row's terms and the belt's speed, is at rest: a state
         * handed over by a host's arithmetic, e.g. a Newton step of a stuck contact's orbit) */
        double v = slip(E, j, s->V), scale = fabs(E->vb[j]);
        const eng_row *R = &E->S.rows[j];
        for (size_t k = 0; k < R->nnz; k++) scale += fabs(R->w[k] * s->V[R->idx[k]]);
        if (fabs(v) <= START_REST_EPS * DBL_EPSILON * scale) v = 0.0;
        s->mode[j] = sgn(v);
        E->cand[j] = has_friction(E, j) && v == 0.0;
        if (is_jenk(E, j)) { /* a slider starts stuck, its spring relaxed */
            s->slider[j] = row_dot(&E->S.rows[j], x0);
            s->mode[j] = has_friction(E, j) ? 0 : s->mode[j];
            E->cand[j] = 0;
        }
        s->t_stick[j] = t0;
        s->t_break[j] = NAN;
        s->break_dir[j] = 0;
    }
    restart(E, s, t0, rest_decide(E, s, t0, E->cand, s->mode));
    for (size_t j = 0; j < nc; j++)
        if (E->cand[j] && s->mode[j] != 0) s->F[j] = -s->mode[j] * slide_mag(E, j, 0.0);
    if (ENG_TANGENTS(E) && s->tan) tan_seed(E, in, s);
    if (s->J) {
        for (size_t i = 0; i < 4 * n * n; i++) s->J[i] = 0.0;
        for (size_t i = 0; i < 2 * n; i++) s->J[i * 2 * n + i] = 1.0;
    }
}

static double snap_tol(const eng *E, double t)
{
    const eng_setup *S = &E->S;
    return min_b(S->snap_max_rel_h * S->h, max_b(S->snap_eps_t * DBL_EPSILON * fabs(t), S->snap_min_rel_h * S->h));
}

ENG_API int ENG_FN(eng_set_sliders)(eng *E, const eng_inputs *in, eng_state *s, const double *s0, const int *slide)
{
    E->loads_for = NULL;
    loads_at(E, in, s->t);
    for (size_t j = 0; j < ENG_NC(E); j++) { /* (a force on its limit, rounded a hair beyond, holds) */
        const int sl = (slide && has_friction(E, j)) ? slide[j] : 0;
        if (is_jenk(E, j) && (sl < -1 || sl > 1)) return 0;
        if (is_jenk(E, j) && sl == 0 &&
            !(fabs(E->S.k_t[j] * (row_dot(&E->S.rows[j], s->X) - s0[j])) <= E->Fb[j] * (1.0 + 1e-12)))
            return 0;
    }
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (!is_jenk(E, j)) continue;
        const int sl = (slide && has_friction(E, j)) ? slide[j] : 0;
        if (sl != 0) { /* sliding: its spring at the kinetic force against the slip's side */
            s->mode[j] = sl;
            s->slider[j] = row_dot(&E->S.rows[j], s->X) - sl * E->mukN[j] / E->S.k_t[j];
            continue;
        }
        s->slider[j] = s0[j];
        s->mode[j] = has_friction(E, j) ? 0 : s->mode[j];
    }
    restart(E, s, s->t, 0);
    if (ENG_TANGENTS(E) && s->tan) tan_seed(E, in, s);
    return 1;
}

ENG_API double ENG_FN(eng_snap_target)(const eng *E, const eng_state *s, double t_target)
{
    return dfo_grid_snap(s->t0, E->S.h, s->n_grid, s->t, t_target, snap_tol(E, t_target));
}

/* The stuck contacts' holding forces, clamped to their limits, at the state (schemes at rest). */
static void rest_forces(eng *E, eng_state *s)
{
    phys_accel(E, s, s->t, s->mode, E->y2, E->f);
    for (size_t j = 0; j < ENG_NC(E); j++)
        if (s->mode[j] == 0 && has_friction(E, j)) s->F[j] = clamp_lim(E->f[j], E->Fb[j]);
}

/* ---- the stuck fast path ------------------------------------------------------------------- */

/* The largest grid index m >= s->n_grid with t0 + m h < x (incl: <= x), the grid points computed as
 * eng_advance computes them; s->n_grid when there is none. x finite. */
static long long grid_below(const eng_state *s, double h, double x, int incl)
{
    if (!(x > s->t)) return s->n_grid;
    long long m = (long long)floor((x - s->t0) / h);
    if (m < s->n_grid) m = s->n_grid;
#define ENG_BELOW_(k) (incl ? s->t0 + (double)(k) * h <= x : s->t0 + (double)(k) * h < x)
    while (m > s->n_grid && !ENG_BELOW_(m)) m--;
    while (ENG_BELOW_(m + 1)) m++;
#undef ENG_BELOW_
    return m;
}

/* A stuck structure's next breakaway from its contacts' (eng_sparse.contact_breakaway): the earliest,
 * NaN where one is unknown. */
static double stuck_breakaway(eng *E, const eng_state *s, const eng_inputs *in)
{
    double tb = INFINITY;
    for (size_t j = 0; j < ENG_NC(E); j++) {
        const double t = ENG_CONTACT_BREAKAWAY(E, j, s, in, E->Fb);
        if (isnan(t)) return NAN;
        tb = fmin(tb, t);
    }
    return tb;
}

/* The stuck fast path (eng_setup.fast_paths with the model's ops.breakaway, or its contacts'
 * eng_sparse.contact_breakaway; the located scheme on a
 * grid it resolves, held inputs): on a grid point, with every contact held, every DOF pinned at rest
 * by a contact of its own and the belts still, the whole grid steps that end before the model's
 * breakaway (at least one grid step before its contacts' breakaways) and at or before t_target
 * change nothing but the time and the
 * counters (the observer sees them as one phase at rest, which ends inside its window where it began
 * before the window's end: the positions, modes and forces it sees are those of each of them).
 * Returns the last grid index they reach (s->n_grid: none). */
static long long stuck_until(eng *E, const eng_inputs *in, eng_state *s, double t_target, const eng_hooks *hk,
                             int *at_rest)
{
    const eng_setup *S = &E->S;
    const double h = S->h;
    loads_at(E, in, s->t);
    *at_rest = 0;
    if (!stuck_at_rest(E, in, s)) return s->n_grid;
    const double tb = stuck_tb(E, in, s);
    if (isnan(tb)) return s->n_grid;
    *at_rest = 1;
    /* A model's breakaway of the whole structure (ENG_BREAKAWAY): step_located takes every step that
     * ends before it as a stuck step without a trial (stuck_rest), as these are taken: all of them
     * here. Its contacts' breakaways: the last whole step before the breakaway is left to a trial
     * (its margins, where the closed forms' rounding may put a breakaway a hair early). */
    const long long margin_steps = (ENG_HAS_BREAKAWAY(E) && !ENG_HAS_CONTACT_BREAKAWAY(E)) ? 0 : 1;
    /* none unless a whole grid step ends before the breakaway, by margin_steps grid steps (grid_below's
     * bound below is then past the next grid point: its grid points rise with their index) */
    if (!(s->t0 + (double)(s->n_grid + 1 + margin_steps) * h < min_b(tb, t_target + 2.0 * h))) return s->n_grid;
    long long m = grid_below(s, h, t_target, 1);
    const long long mb = grid_below(s, h, min_b(tb, t_target + 2.0 * h), 0) - margin_steps;
    if (mb < m) m = mb;
    if (hk && hk->obs && hk->obs->on_phase && s->t < hk->obs->t_stop) { /* a stretch in the window ends in it */
        const long long mo = grid_below(s, h, min_b(hk->obs->t_stop, t_target + 2.0 * h), 1);
        if (mo < m) m = mo;
    }
    return (m > s->n_grid) ? m : s->n_grid;
}

/* Take the stuck grid steps up to the grid index m at once, as the located scheme's steps one by
 * one leave them: X through one step's predictor and corrector with V1 = V (the held solve), V at
 * its belt (0), A and hA 0, the excitation's grid cache at m (a function of m alone), the steps and
 * solves counted. (F is left: every path sets or reads it afresh after the steps.) */
static void stuck_skip(eng *E, eng_state *s, long long m)
{
    const eng_setup *S = &E->S;
    const dfo_bossak_kin *K = &E->kin_grid;
    const long long k = m - s->n_grid;
    for (int pass = 0; pass < ((k > 1) ? 2 : 1); pass++) stuck_rest(E, s, K);
    double c, sn;
    dfo_grid_phase(S->exc.omega, S->exc.phi0, s->t0, S->h, E->rot_c, E->rot_s, s->exc_n, s->exc_c, s->exc_s, m, &c,
                   &sn);
    s->exc_n = m;
    s->exc_c = c;
    s->exc_s = sn;
    s->n_grid = m;
    s->t = s->t0 + (double)m * S->h;
    s->steps += k;
    s->solves += k;
}

ENG_API eng_status ENG_FN(eng_advance)(eng *E, const eng_inputs *in, eng_state *s, double t_target, const eng_hooks *hk)
{
    E->loads_for = NULL;
    E->held_ready = 0;
    const eng_setup *S = &E->S;
    const double h = S->h;
    t_target = ENG_FN(eng_snap_target)(E, s, t_target);
    double g_prev = s->t0 + (double)s->n_grid * h;
    int switched = 0;
    E->fused_ready = 0;
    const long long sw0 = s->switches;
    const int skip = !ENG_TANGENTS(E) && S->fast_paths && (ENG_HAS_BREAKAWAY(E) || ENG_HAS_CONTACT_BREAKAWAY(E)) &&
                     S->scheme == DFO_SCHEME_LOCATED &&
                     S->rate_max * h <= STIFF_STEP && !ramped(in);
    if (!(hk && hk->stick_kept)) s->stick_tb = NAN;
    /* (a model's own fused step: in the schemes; the energy accounts: the general path's) */
    const int fuse = !ramped(in) && !ENG_HAS_STEP_HELD(E) && !S->account_energy && !ENG_HAS_JENKINS(E) &&
                     !ENG_TANGENTS(E);
    const int fuse_held = !ramped(in) && ENG_HAS_STEP_HELD(E) && !S->account_energy &&
                          S->scheme == DFO_SCHEME_LOCATED &&
                          !(hk && hk->report_turns && !E->all_friction); /* (turns: the general path's) */
    /* the finiteness of the state: tested by the general path every 16 grid points, by the runs of
     * fused steps every 16 of their steps and after a run where 16 grid points passed since the last
     * test (n_checked), and at the end; a step's error on a state that overflowed is the overflow */
    long long n_checked = s->n_grid;
    while (s->t < t_target) {
        int declined = 0; /* the stuck fast path declined this grid point */
        int at_rest = 0;  /* and the structure rests there, its breakaway known (stuck_until) */
        if (skip && s->t == g_prev) {
            const long long m = stuck_until(E, in, s, t_target, hk, &at_rest);
            declined = 1;
            if (m > s->n_grid) {
                double ta;
                begin_phase(E, s, &ta, hk);
                stuck_skip(E, s, m);
                g_prev = s->t;
                observe(E, s, ta, s->F, hk);
                continue;
            }
        }
        /* (a structure at rest whose model gives its breakaway, the step declined: step_located's,
         * which takes it as a stuck step or places the breakaway in it without a trial) */
        const int rest_step = at_rest && ENG_HAS_BREAKAWAY(E) && !ENG_HAS_CONTACT_BREAKAWAY(E);
        /* stuck_until's answer, for step_located's phase 0 where no fused step moves the state first: 1 at
         * rest with its breakaway in stick_tb, -1 not at rest (or its breakaway unknown), 0 not asked */
        int rest_known = declined ? (at_rest ? 1 : -1) : 0;
        /* (a state whose A is re-based on the grid step: the general path's, which fused_steps would
         * leave to it before its first step) */
        if (fuse && s->t == g_prev && !rest_step && !needs_rebase(E, s, h)) {
            rest_known = 0;
            loads_at(E, in, s->t);
            fused_steps(E, s, t_target, skip, declined, hk, &g_prev);
            if (s->n_grid - n_checked >= 16) { /* (runs test every 16 of their steps; short ones here) */
                if (!finite_all(ENG_N(E), s->X, s->V, s->A)) return ENG_ERR_NONFINITE;
                n_checked = s->n_grid;
            }
            if (!(s->t < t_target)) break;
        }
        /* (a structure at rest whose breakaway is known: held_steps' run would end before its first
         * step, left to the stuck path's step_located) */
        if (fuse_held && s->t == g_prev && !at_rest) {
            rest_known = 0;
            loads_at(E, in, s->t);
            held_steps(E, in, s, t_target, skip, hk, &g_prev);
            if (s->n_grid - n_checked >= 16) {
                if (!finite_all(ENG_N(E), s->X, s->V, s->A)) return ENG_ERR_NONFINITE;
                n_checked = s->n_grid;
            }
            if (!(s->t < t_target)) break;
        }
        const double grid = s->t0 + (double)(s->n_grid + 1) * h;
        const int from_grid = (s->t == g_prev);
        double t_end = t_target;
        if (grid <= t_target) {
            t_end = grid;
            s->n_grid++;
            g_prev = grid;
            double c, sn;
            dfo_grid_phase(S->exc.omega, S->exc.phi0, s->t0, h, E->rot_c, E->rot_s,
                           s->exc_n, s->exc_c, s->exc_s, s->n_grid, &c, &sn);
            s->exc_n = s->n_grid;
            s->exc_c = c;
            s->exc_s = sn;
        }
        if (!(t_end > s->t)) return ENG_ERR_RESOLUTION;
        const double hh = (from_grid && t_end == grid) ? h : t_end - s->t;
        s->steps++;
        loads_at(E, in, t_end);
        eng_status st;
        if (S->scheme == DFO_SCHEME_LOCATED) st = step_located(E, in, s, t_end, hh, hk, rest_known);
        else st = step_lcp(E, in, s, t_end, hh, S->scheme == DFO_SCHEME_CONSISTENT, hk);
        E->held_ready = 0;
        E->fused_ready = 0;
        switched = s->switches != sw0;
        if (st == ENG_SWITCHED || (hk && hk->stop_at_switch && switched)) {
            if (s->t < t_end && t_end == grid) s->n_grid--;
            loads_at(E, in, s->t);
            if (S->scheme != DFO_SCHEME_PAPER) rest_forces(E, s);
            return ENG_SWITCHED;
        }
        if (st != ENG_OK) return finite_all(ENG_N(E), s->X, s->V, s->A) ? st : ENG_ERR_NONFINITE;
        if ((s->n_grid & 15) == 0 && !finite_all(ENG_N(E), s->X, s->V, s->A)) return ENG_ERR_NONFINITE;
    }
    loads_at(E, in, s->t);
    if (S->scheme != DFO_SCHEME_PAPER) rest_forces(E, s);
    for (size_t i = 0; i < ENG_N(E); i++)
        if (!(fabs(s->X[i]) <= DBL_MAX && fabs(s->V[i]) <= DBL_MAX && fabs(s->A[i]) <= DBL_MAX))
            return ENG_ERR_NONFINITE;
    return ENG_OK;
}

/* The Jenkins contacts under the new normal forces (the loads set): a sliding slider whose spring
 * force is below the new kinetic force sticks; one above it has its force drop to it; a stuck one
 * beyond the new breakaway limit breaks away; without friction the force is 0 and the mode follows
 * the slip. Where the force drops the slider jumps, the spring energy released counted as friction
 * work (with the energy accounts). Switches reported; each force's jump into E->f2. */
static void jenk_new_loads(eng *E, eng_state *s, const eng_hooks *hk)
{
    for (size_t j = 0; j < ENG_NC(E); j++) {
        E->f2[j] = 0.0;
        if (!is_jenk(E, j)) continue;
        const double k = E->S.k_t[j], f0 = jenk_force(E, j, s);
        const int from = s->mode[j];
        int m = from;
        double f1 = f0;
        if (!has_friction(E, j)) {
            m = sgn(slip(E, j, s->V));
            f1 = 0.0;
        } else if (m != 0 && fabs(f0) < E->mukN[j]) {
            m = 0;
        } else if (m != 0) {
            f1 = -m * E->mukN[j];
        } else if (fabs(f0) > E->Fb[j]) {
            m = -sgn(f0);
            f1 = -m * E->mukN[j];
        }
        if (f1 != f0) {
            s->slider[j] = row_dot(&E->S.rows[j], s->X) + f1 / k;
            if (E->S.account_energy) s->W_friction -= (f0 * f0 - f1 * f1) / (2.0 * k);
        }
        E->f2[j] = f1 - s->F[j];
        s->F[j] = f1;
        s->mode[j] = m;
        if (m != from && has_friction(E, j)) report(s, j, from, hk);
    }
}

ENG_API void ENG_FN(eng_new_inputs)(eng *E, const eng_inputs *old_in, const eng_inputs *new_in, eng_state *s, const eng_hooks *hk)
{
    if (ENG_TANGENTS(E) && s->tan) s->tan_lost = 1; /* (the map's tangent is of held inputs) */
    E->loads_for = NULL;
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    s->stick_tb = NAN; /* (of the old inputs) */
    /* belts: a contact whose belt changed takes the mode of its new slip; one the belt meets the rest rule */
    loads_at(E, new_in, s->t);
    if (ENG_HAS_JENKINS(E)) jenk_new_loads(E, s, hk);
    int belt_changed = 0;
    memcpy(E->smode, s->mode, nc * sizeof(int));
    for (size_t j = 0; j < nc; j++) {
        const double vo = (old_in && old_in->v_belt) ? old_in->v_belt[j] : 0.0;
        const double vn = (new_in && new_in->v_belt) ? new_in->v_belt[j] : 0.0;
        E->cand[j] = 0;
        if (vo == vn || !has_friction(E, j) || is_jenk(E, j)) continue; /* (a stuck slider moves with its belt) */
        belt_changed = 1;
        const double v = slip(E, j, s->V);
        s->mode[j] = sgn(v);
        E->cand[j] = v == 0.0;
    }
    if (belt_changed) {
        const int decided = rest_decide(E, s, s->t, E->cand, s->mode);
        for (size_t j = 0; j < nc; j++)
            if (s->mode[j] != E->smode[j]) report(s, j, E->smode[j], hk);
        restart(E, s, s->t, decided);
        return;
    }
    /* the sliding contacts' force jumps, and the external forces': the acceleration jumps by
     * M^-1 (dF_ext + W' df), the stuck contacts held */
    double *r = E->r;
    for (size_t i = 0; i < n; i++) r[i] = E->u[i];
    loads_at(E, old_in, s->t);
    for (size_t i = 0; i < n; i++) r[i] -= E->u[i];
    loads_at(E, new_in, s->t);
    int any = 0;
    for (size_t i = 0; i < n; i++) any |= r[i] != 0.0;
    for (size_t j = 0; j < nc; j++) {
        E->held[j] = s->mode[j] == 0 && has_friction(E, j) && !is_jenk(E, j);
        if (is_jenk(E, j)) { /* its force's jump: jenk_new_loads' */
            if (E->f2[j] != 0.0) { row_axpy(&S->rows[j], E->f2[j], r); any = 1; }
            continue;
        }
        if (s->mode[j] == 0 || !has_friction(E, j)) continue;
        const double fnew = -s->mode[j] * slide_mag(E, j, fabs(slip(E, j, s->V)));
        const double df = fnew - s->F[j];
        if (df != 0.0) { row_axpy(&S->rows[j], df, r); any = 1; }
        s->F[j] = fnew;
    }
    if (!any) return;
    held_solve(E, r, E->held, E->y, E->f);
    for (size_t i = 0; i < n; i++) s->A[i] += E->y[i];
}

ENG_API void ENG_FN(eng_accelerations)(eng *E, const eng_inputs *in, const eng_state *s, double *a)
{
    E->loads_for = NULL;
    loads_at(E, in, s->t);
    const int paper = E->S.scheme == DFO_SCHEME_PAPER;
    if (!paper && !E->any_law) {
        phys_accel(E, s, s->t, s->mode, a, E->f);
        return;
    }
    /* the state's forces where the scheme has them: a Stribeck slide's (at its solved speed, not at
     * the rounding of its slip), and the paper scheme's stuck contact, which is not at rest (Bossak's
     * A throughout: it creeps with the force of its LCP) */
    const eng_setup *S = &E->S;
    const size_t nc = ENG_NC(E);
    double *r = E->r, *y = E->y;
    applied_at(E, s, s->t, r);
    minus_kc(E, s->X, s->V, r, y);
    for (size_t j = 0; j < nc; j++) {
        E->held[j] = !paper && s->mode[j] == 0 && has_friction(E, j) && !is_jenk(E, j);
        if (!has_friction(E, j) || E->held[j]) continue;
        /* a Coulomb slide's force follows the current loads (the inputs' feed-through) */
        const double fj = (s->mode[j] != 0 && !is_strib(E, j)) ? -s->mode[j] * slide_mag(E, j, 0.0) : s->F[j];
        row_axpy(&S->rows[j], fj, r);
    }
    held_solve(E, r, E->held, a, E->f);
}

ENG_API void ENG_FN(eng_contact_forces)(eng *E, const eng_inputs *in, const eng_state *s, double *f)
{
    E->loads_for = NULL;
    loads_at(E, in, s->t);
    phys_accel(E, s, s->t, s->mode, E->y2, f);
    for (size_t j = 0; j < ENG_NC(E); j++)
        if (s->mode[j] == 0 && has_friction(E, j)) f[j] = clamp_lim(f[j], E->Fb[j]);
}
