/* The friction engine: the Bossak-Newmark schemes of method.md (sections 2-4, 8, 9, 12, 13)
 * written once, for any structure with friction contacts, over operators the model supplies.
 *
 *     M x'' + C x' + K x = P(t) + F_ext(t) + W' f,      n degrees of freedom, nc contacts,
 *     P_i(t) = Pc_i cos(omega t + phi0) - Ps_i sin(omega t + phi0),
 *     contact j: slip velocity g_j' = w_j . x' - v_belt_j, force f_j along w_j,
 *       stuck  (mode 0):  g_j' = 0,  |f_j| <= Fb_j = max(mu_s_j, mu_k_j) N_j,
 *       sliding (+1/-1):  f_j = -mode_j N_j mu_j(|g_j'|)  (Coulomb: mu_k_j; Stribeck: friction.h),
 *       N_j = max(N_j + N_ext_j(t), 0);
 *     or a Jenkins element (eng_setup.k_t): f_j = -k_t_j (w_j . x - s_j), its massless slider s_j
 *       stuck (mode 0: s_j' = v_belt_j, |f_j| <= Fb_j) or sliding (f_j = -mode_j mu_k_j N_j).
 *
 * The model owns M, C, K and the contact rows W (sparse: a few entries each); it hands the engine
 *   - operators (eng_ops): y = K x, y = C v, y = M a, and "factor c_M M + c_C C + c_K K, then solve
 *     with it" in a few slots (scalar, tridiagonal, banded or dense: the model's choice), and
 *     optionally its own solver of the friction problem of a step (eng_friction_fn): the chain its
 *     O(n) tridiagonal box LCP, the oscillator its scalar 2 x 2 fast path; without one the engine
 *     forms the Delassus matrix D = W M_hat^-1 W' (nc x nc) and solves the contacts' LCP by Lemke
 *     (eng_dense_friction, also callable from a model's solver as its fallback);
 *   - data (eng_setup): sizes, contact rows, normal forces and coefficients, the friction law per
 *     contact, the harmonic excitation, the Bossak parameter, the step, the scheme.
 * The engine owns the time grid t0 + n h (snapped requested times, shortened last steps, the
 * re-basing of Bossak's A on a new step length: method.md section 8), the excitation's grid cache,
 * the three schemes (paper, consistent, located), the warm start of the friction problem from the
 * previous modes, the located switch placement (the earliest switch inside the step by a
 * bracketed root of the sub-step length, the step split there, the rest rule of friction.h per
 * contact, the restart with the consistent accelerations of the new mode set), input derivatives
 * (ramps: loads taken at each (sub-)step's end), belts (carried in the inputs, per contact), the
 * Stribeck law, and calls the model's hooks: a switch callback, an observer of phases.
 *
 * State passes through the arguments: eng_state (the trajectory, serialisable: scalars plus arrays)
 * and eng_inputs (the inputs of the current communication step, belts included). The engine object
 * (eng) holds the setup and workspace only: no field of it carries a value from one call to the
 * next, except the operators' factorisations, which are caches keyed by their coefficients, and
 * what eng_dense_friction derives from the grid slot's (the columns A^-1 w_j, D^-1 of the contacts
 * with friction), dropped when that slot is refactored.
 *
 * Memory: every array through the caller's allocation callbacks (eng_alloc), sized at eng_create
 * (O(n + nc^2) with the dense default, O(n + nc) with a model's friction solver). No global
 * state. Plain C99, no FMI types. */
#ifndef DFO_ENGINE_H
#define DFO_ENGINE_H

#include "bossak.h"   /* dfo_scheme, the Bossak coefficients, the default step rule */
#include "friction.h" /* dfo_friction_law, the rest rule */

#include <stddef.h>

/* ---- status -------------------------------------------------------------------------------- */

typedef enum {
    ENG_OK = 0,
    ENG_ERR_LCP = 1,          /* the friction problem could not be solved (Lemke, or the model's solver) */
    ENG_ERR_NO_PROGRESS = 2,  /* too many switches inside one internal step */
    ENG_ERR_NONFINITE = 3,    /* the state overflowed */
    ENG_ERR_RESOLUTION = 4,   /* a step would not advance time (h below the resolution of t) */
    ENG_SWITCHED = 5,         /* stopped at the first switch (eng_hooks.stop_at_switch): s->t is its time */
    ENG_ERR_FRICTION = 6,     /* the Stribeck law's implicit solve did not converge */
    ENG_ERR_BAD_INPUT = 7     /* a setup or argument out of range (eng_create's *err says which) */
} eng_status;

const char *eng_status_text(eng_status st);

/* ---- memory ---------------------------------------------------------------------------------- */

/* Allocation callbacks (zero-filled memory, as FMI's calloc); env is passed through. The same shape
 * as chain_alloc. */
typedef struct {
    void *(*allocate)(void *env, size_t nobj, size_t size);
    void (*release)(void *env, void *obj);
    void *env;
} eng_alloc;

/* ---- what the model supplies ------------------------------------------------------------------ */

/* The factor slots of eng_ops.factor / solve: the engine refactors a slot only when its
 * coefficients change (it remembers them), so a model keeps one factorisation per slot. M, C and
 * K themselves are taken as fixed for the engine's life: a model whose matrices change makes a new
 * engine. */
enum {
    ENG_SLOT_GRID = 0,   /* M_hat of a whole grid step h (factored once per run) */
    ENG_SLOT_TRIAL = 1,  /* M_hat of any other step length (shortened steps, switch searches) */
    ENG_SLOT_MASS = 2,   /* M itself (physical accelerations: start-up, restarts, outputs) */
    ENG_NSLOTS = 3
};

/* Contact j's row w_j of W: nnz entries w[k] at degrees of freedom idx[k] (e_i: DOF i against the
 * ground; e_i - e_k: the slip between DOFs i and k). The arrays are the model's, read while the
 * engine lives. */
typedef struct {
    size_t nnz;
    const size_t *idx;
    const double *w;
} eng_row;

/* The friction problem of one (trial) step, handed to a friction solver:
 *     M_hat V1 = p_hat + W' f,   v = W V1 - vb  (the contacts' slip velocities at the step's end),
 * with, per contact j and its mode m_j:
 *     m_j = 0 (held):   v_j = 0 and |f_j| <= limit_j (for a basis solve: v_j = 0, f_j unknown);
 *     m_j = +1/-1:      f_j = -m_j limit_j and m_j v_j >= 0 (basis solve: f_j = -m_j limit_j);
 *     limit_j = 0:      no friction at j: f_j = 0 whatever its mode (its mode out: the sign of v_j).
 * With law != NULL, a sliding contact j with law[j].law == DFO_LAW_STRIBECK has the implicit force
 * f_j = -m_j N_j mu_j(max(m_j v_j, 0)) instead of -m_j limit_j (limit_j is then N_j min(mu_s, mu_k),
 * where every speed stops it: the modes are decided with it, then the speed solved; friction.h's
 * dfo_stribeck_speed for one contact). */
typedef struct {
    int slot;               /* the factorisation of M_hat to solve with (ENG_SLOT_GRID or _TRIAL) */
    double h;               /* the step's length (M_hat = (1 - a) M / (g h) + C + (b h / g) K) */
    double cM, cC, cK;      /* M_hat's coefficients, as passed to factor */
    const double *p_hat;    /* n: the right-hand side */
    const double *vb;       /* nc: belt speeds (NULL: 0) */
    const double *limit;    /* nc: held contacts' limit Fb, sliding ones' kinetic magnitude */
    const double *N;        /* nc: normal forces (read with law only) */
    const dfo_friction_law *law;  /* nc, or NULL: no Stribeck contact in this problem */
    /* nc compliances, or NULL: all 0 (rigid). A Jenkins contact (eng_setup.k_t) is the same problem
     * with its slip v_j = w_j . V1 - vb_j + comp_j f_j (comp_j = 1 / (k_t corr_V), vb_j its shifted
     * target (s_j + h v_belt_j - w_j . x_pred) / corr_V: v_j is its slider's slip over the step / corr_V):
     * its Delassus diagonal gains comp_j. Only the default solver takes it (eng_dense_friction). */
    const double *comp;
} eng_problem;

/* What a friction solver is asked. */
enum {
    ENG_SOLVE_BASIS = 0,  /* solve with the modes as given (no test of the inequalities): the located
                           * scheme's trial, O(1) solves; *mode is not changed */
    ENG_SOLVE_LCP = 1     /* find the modes: the LCP, warm-started from *mode (the previous step's),
                           * *mode out the solution's; *pivots the pivots done (0: the warm basis held) */
};

/* A friction solver: the problem P, the modes mode[nc] (in; out with ENG_SOLVE_LCP), into V1[n] and
 * f[nc]. Returns ENG_OK, ENG_ERR_LCP (no solution found), ENG_ERR_NONFINITE (non-finite data) or
 * ENG_ERR_FRICTION (Stribeck). ctx is eng_ops.ctx. */
typedef eng_status (*eng_friction_fn)(void *ctx, const eng_problem *P, int what, int *mode, double *V1, double *f,
                                      int *pivots);

struct eng_harmonic_s;
struct eng_state_s;
struct eng_inputs_s;

/* A stuck structure's next breakaway in closed form (optional: the stuck fast path of the located
 * scheme, with eng_setup.fast_paths). Asked only when every contact holds (mode 0, with friction), every
 * DOF is pinned at rest by a held contact of its own (w_j = e_i, V = A = 0), the inputs are held (no
 * ramps) and the belts still: exc the excitation, s the state, in the inputs, Fb (nc) the contacts'
 * breakaway limits under them. Returns a time tb such that no contact's holding force reaches its
 * limit on [s->t, tb) (+INFINITY: never; NaN: unknown). The scheme then takes at once the whole grid
 * steps that end at least one grid step before tb (one phase for the observer), to the bits
 * of taking them one by one, provided the model's friction solver returns V1 = V exactly on a held
 * pinned DOF (the scalar solver of one contact does; the dense default need not: no hook with it). */
typedef double (*eng_breakaway_fn)(void *ctx, const struct eng_harmonic_s *exc, const struct eng_state_s *s,
                                   const struct eng_inputs_s *in, const double *Fb);

/* The model's operators. Every vector of length n unless said; y and x never alias. */
typedef struct {
    void *ctx;
    void (*apply_K)(void *ctx, const double *x, double *y);  /* y = K x */
    void (*apply_C)(void *ctx, const double *v, double *y);  /* y = C v; NULL: C = 0 */
    void (*apply_M)(void *ctx, const double *a, double *y);  /* y = M a */
    /* Factor A = cM M + cC C + cK K into slot; 0 when A is not positive definite (then the step is
     * refused with ENG_ERR_BAD_INPUT). cC is 0 when apply_C is NULL. */
    int (*factor)(void *ctx, int slot, double cM, double cC, double cK);
    /* x = A_slot^-1 b with the slot's last factorisation (b and x may be the same array). */
    void (*solve)(void *ctx, int slot, const double *b, double *x);
    /* The model's friction solver; NULL: eng_dense_friction. */
    eng_friction_fn friction;
    /* The model's closed-form breakaway of a stuck structure; NULL: none (every stuck step taken). */
    eng_breakaway_fn breakaway;
    /* The model's friction solver calls eng_dense_friction for some problems (its fallback): the
     * engine keeps the dense workspace, O(n nc + nc^2), which it allocates only for that, without a
     * model solver, or without the held basis solve (eng_sparse.held_basis). */
    int dense_fallback;
} eng_ops;

/* Optional operators of the contacts' coupling through M_hat (eng_setup.coupling; NULL: none, the
 * engine's columns). Without them the default friction solver (eng_dense_friction) and the engine's
 * constrained solves form the Delassus matrix of a set S of contacts from the columns A_slot^-1 w_j
 * (one solve each, kept per factor slot until it is refactored: O(|S| n^2) with a dense solve, anew
 * after every refactorisation). A model that has A_slot^-1 in a cheaper form (the system's modal
 * backend: A^-1 = Phi diag(d) Phi', the contact rows in modal coordinates U = W Phi kept) offers
 *   delassus   D (m x m, row-major) := W_S A_slot^-1 W_S', S the contacts sel[0 .. m-1] (in that
 *              order; each once), with the slot's last factorisation; symmetric to the bit
 *   respond    y (n) += A_slot^-1 W_S' f, f (m) the forces of the contacts sel[0 .. m-1]
 * each O(m^2 n) and O(m n + n^2) with the modal form, for the slots flagged in slots (bit 1 << s for
 * slot s): the slots refactored often (ENG_SLOT_TRIAL: every trial sub-step of a switch search),
 * whereas the columns of a slot factored once a run (ENG_SLOT_GRID, ENG_SLOT_MASS) are solved once
 * and then cost O(m nnz) a Delassus row and O(m n) a response. For those slots the engine calls them
 * where it used the columns: the constrained solves (csolve: basis solves, physical accelerations and
 * jerks), Stribeck's Newton (stribeck_newton) and the Delassus matrix of the LCP (eng_dense_friction).
 * Both or neither; ctx is theirs (not eng_ops.ctx). A model's own friction solver (eng_ops.friction)
 * and the spans do not use them (a span's sub-engine has none). */
typedef struct {
    unsigned slots;
    void *ctx;
    void (*delassus)(void *ctx, int slot, const int *sel, size_t m, double *D);
    void (*respond)(void *ctx, int slot, const int *sel, size_t m, const double *f, double *y);
} eng_coupling;

/* The harmonic excitation P_i(t) = Pc[i] cos(omega t + phi0) - Ps[i] sin(omega t + phi0) (Pc, Ps:
 * n each; NULL: 0). On the grid t0 + k h the phase comes from the state's cache (excitation.h's
 * dfo_grid_phase: a pure function of k), elsewhere it is evaluated (dmath's dfo_cos / dfo_sin). */
typedef struct eng_harmonic_s {
    double omega, phi0;
    const double *Pc, *Ps;
} eng_harmonic;

/* Optional operators of a sparse structure (eng_setup.sparse; NULL: none, the dense model's paths).
 * A model whose contacts couple few DOFs offers them so that the engine's work per step follows
 * the structure's sparsity instead of nc^3:
 *   held_basis   the model's friction solver (eng_ops.friction, then required) also solves
 *                ENG_SOLVE_BASIS problems of ENG_SLOT_MASS (cM = 1, cC = cK = 0, law NULL): the
 *                engine's held solves (physical accelerations, jerks and input jumps: M y = r + W_H' f_H
 *                with W_H y = 0 on the held contacts H) go through it instead of the Delassus matrix
 *                of the held contacts (Cholesky, O(|H|^3)).
 *   spans        the located scheme's local switch placement. Where contacts would switch in a step,
 *                the engine takes the whole step in the current modes, then steps again, on its own,
 *                each span around the switching contacts: its DOFs from the step's start, switches
 *                placed inside it, its boundary DOFs (ghosts: the DOFs outside it that its DOFs
 *                couple to through M, C, K or a contact row) moving as prescribed over the step, by
 *                cubic Hermite interpolation of their states at the step's start and end. A span
 *                reaches as far as a contact's switch moves the solution by more than rounding (the
 *                model's judgement: M_hat^-1's decay); the span costs O(its size), not O(n).
 *     span_max   the most DOFs (ghosts included) and contacts one span holds (0: no spans)
 *     span       the spans around the candidate contacts (cand: nc flags): labels per DOF (dof_lab,
 *                n) and per contact (ct_lab, nc): 0 outside every span, s + 1 in span s, -(s + 1) a
 *                ghost of span s (a DOF), or a contact carried by span s without friction (its row
 *                on the span's DOFs and ghosts: a model may keep its numbering so); and each span's
 *                index ranges: span s's labels lie in the DOFs [dof_rng[2 s], dof_rng[2 s + 1]) and
 *                the contacts [ct_rng[2 s], ct_rng[2 s + 1]) (2 n entries each). Labels are read only
 *                inside these ranges, so the model writes those only (its work the spans' size, not
 *                the structure's). Every candidate in a span (label > 0), a ghost of one span in no
 *                other, spans disjoint. Returns the number of spans; 0: step the whole structure (a
 *                small one).
 *     span_bind  make span_ops act on the span whose DOFs (ghosts included, ascending) are dofs[nd],
 *                ghost[k] saying which are ghosts, and whose contacts are cts[nct] (ascending), in
 *                that local numbering
 *     span_ops   the operators of the bound span (local numbering): apply_K, apply_C, apply_M give
 *                the span's rows (a ghost's row is not read); factor and the friction solver are for
 *                the span's rows with the ghosts' entries prescribed: the friction problem's p_hat
 *                holds a ghost's prescribed end velocity in its entry, and V1 returns it there
 *                (Dirichlet rows). held_basis holds for them too.
 *   contact_breakaway  (optional) held contact j's next breakaway in closed form, the structure
 *                elsewhere where it is: the first time >= its stick's start s->t_stick[j] at which its
 *                holding force reaches its limit Fb[j] under the inputs in (held inputs, still belts),
 *                or NaN where the model's closed form does not hold (e.g. a DOF coupled to contact j's
 *                moves). Where every contact that would switch in a (sub-)step is held and has a
 *                breakaway there, the located scheme splits the step at the earliest of them at once
 *                (no root finding); else as without. Without ops.breakaway the stuck fast path takes
 *                the earliest of the contacts' as the structure's.
 *   step_held    (optional) a whole grid step in the current modes, fused: the trial step (x_pred,
 *                p_hat), the basis solve in the modes st with the limits lim, every contact's margin,
 *                and where none would switch, the step's acceptance; in the model's own sweeps (the
 *                chain: one forward and one backward sweep with its kept factorisation), written in
 *                the engine's arithmetic and order (so the same bits as its trial, solve and finish;
 *                eng_held_step says what each is). Returns 1 when taken (s->X, V, A, hA, F set as the
 *                engine's finish sets them), 0 when some contact's margin is <= 0 (s untouched; the
 *                trial and its solve in F's xp, ph, V1, f: the engine goes on from them its general
 *                way). Asked by the located scheme on a grid step
 *                with held inputs and no belts (A0: A, or re-based where the step is a run's first). */
typedef struct eng_held_step_s eng_held_step;
typedef struct {
    int held_basis;
    int (*step_held)(void *ctx, const eng_held_step *F, struct eng_state_s *s);
    double (*contact_breakaway)(void *ctx, size_t j, const struct eng_harmonic_s *exc, const struct eng_state_s *s,
                                const struct eng_inputs_s *in, const double *Fb);
    size_t span_max;
    size_t (*span)(void *ctx, const int *cand, int *dof_lab, int *ct_lab, size_t *dof_rng, size_t *ct_rng);
    void (*span_bind)(void *ctx, const size_t *dofs, const int *ghost, size_t nd, const size_t *cts, size_t nct);
    eng_ops span_ops;
} eng_sparse;

/* eng_sparse.span for a row of n DOFs, DOF i with contact i and coupled to its neighbours only (a
 * chain of blocks): w DOFs either side of each candidate, spans merged when less than 3 DOFs
 * apart (distinct ghosts), the DOFs next to a span its ghosts (their contacts carried: a span's
 * contacts are its DOFs'), labelled over its range only. None (0) where w is 0 or n <= 2 w + 3. */
static inline size_t eng_row_spans(size_t n, size_t w, const int *cand, int *dof_lab, int *ct_lab, size_t *dof_rng,
                                   size_t *ct_rng)
{
    if (w == 0 || n <= 2 * w + 3) return 0;
    size_t ns = 0, pa = 0, pb = 0;
    for (size_t c = 0; c <= n; c++) {
        if (c < n && !cand[c]) continue;
        const size_t a = (c > w) ? c - w : 0, b = (c + w + 1 < n) ? c + w + 1 : n;
        if (c < n && ns > 0 && a <= pb + 2) { pb = b; continue; }
        if (ns > 0) { /* label the span [pa, pb) and its ghosts, its contacts as its DOFs */
            const size_t lo = (pa > 0) ? pa - 1 : 0, hi = (pb < n) ? pb + 1 : n, k = ns - 1;
            for (size_t i = lo; i < hi; i++) ct_lab[i] = dof_lab[i] = (i < pa || i >= pb) ? -(int)ns : (int)ns;
            dof_rng[2 * k] = ct_rng[2 * k] = lo;
            dof_rng[2 * k + 1] = ct_rng[2 * k + 1] = hi;
        }
        if (c == n) break;
        pa = a;
        pb = b;
        ns++;
    }
    return ns;
}

/* What eng_sparse.step_held is given: the step's arithmetic as the engine's trial_step, its solve
 * and finish do it, per DOF i and contact j:
 *   xp_i = X_i + pred_V V_i + pred_A A0_i
 *   r_i = -alpha A0_i + (1 - alpha) (V_i c1 + g1 A0_i)
 *   p_i = u_i, then p_i += Pc_i cw, then p_i -= Ps_i sw (the terms of non-NULL arrays)
 *   p_hat_i = p_i + ((M r)_i - (K xp)_i)              (apply_M, apply_K as the model's)
 *   V1, f: the basis solve (eng_problem, ENG_SOLVE_BASIS) of p_hat in the modes st with limits lim
 *   margin_j = st_j (w_j . V1) for st_j != 0, Fb_j - |f_j| for st_j = 0 (contacts with Fb_j > 0 only)
 *   (xp, p_hat, V1 and f out in F's arrays, taken or not)
 *   taken when every margin is > 0: X_i = xp_i + corr_V V1_i, A_i = (V1_i - V_i) c1 - g1 A0_i,
 *   V_i = V1_i, hA_i = h, F_j = f_j. */
struct eng_held_step_s {
    int slot;                   /* the factored slot of M_hat (ENG_SLOT_GRID), with cM, cC, cK */
    double cM, cC, cK;
    double h, alpha, g1, c1, pred_V, pred_A, corr_V;
    double cw, sw;              /* cos and sin of the excitation's phase at the step's end */
    const double *Pc, *Ps;      /* n: the excitation (NULL: 0) */
    const double *u;            /* n: external forces */
    const double *A0;           /* n: Bossak's A for the step (s->A, or the engine's re-based A0) */
    const int *st;              /* nc: modes (0 held, +1/-1 sliding; a contact without friction: 1) */
    const double *lim;          /* nc: held contacts' breakaway limit, sliding ones' kinetic magnitude */
    const double *Fb;           /* nc: breakaway limits (0: no friction, never a candidate) */
    double *xp, *ph, *V1, *f;   /* n, n, n, nc: out, x_pred, p_hat and the basis solve's V1 and f (the
                                 * engine's workspace: where the step is not taken it goes on from them) */
    int run;                    /* 0: a step on its own; 1: the first step of a run whose F differs from
                                 * step to step only in cw, sw and A0 (the other arrays, their contents
                                 * and the slot's factor unchanged while the run lasts); 2: a later step
                                 * of that run, the last one taken (the model may keep what it took from
                                 * F at the run's first step, in its own layout, and read that instead) */
};

/* The rest rule's steps at an event where it decides two or more rigid contacts with friction at rest
 * together (the causal cascade from "all at rest held", method.md section 13): stage ENG_REST_OPEN
 * (contact = nc) with rest[] the contacts at rest; ENG_REST_RELEASE for each contact it releases, the
 * most beyond its limit (by excess, its holding force's magnitude over its breakaway limit), to slide
 * the way mode says; ENG_REST_SETTLED (contact = nc) with modes[] the set it ends with (0: held).
 * For a model's event log (eng_setup.on_rest; ctx: eng_setup.rest_ctx), at the start too. */
enum { ENG_REST_OPEN = 0, ENG_REST_RELEASE = 1, ENG_REST_SETTLED = 2 };
typedef void (*eng_rest_fn)(void *ctx, double t, int stage, size_t contact, int mode, double excess,
                            const int *rest, const int *modes);

/* Everything set before a run. Arrays are the caller's and must outlive the engine (eng_create
 * copies none of them: a model keeps its parameters in its own struct and points at them). */
typedef struct {
    size_t n;                   /* degrees of freedom, >= 1 */
    size_t nc;                  /* contacts, >= 0 */
    eng_ops ops;
    const eng_row *rows;        /* nc contact rows */
    eng_harmonic exc;
    const double *N;            /* nc normal forces (without N_ext), >= 0 */
    const double *mu_s, *mu_k;  /* nc static and kinetic coefficients (breakaway: max of the two) */
    const dfo_friction_law *law;  /* nc sliding laws (friction.h), or NULL: Coulomb with mu_k */
    /* nc tangential stiffnesses, or NULL: every contact rigid. k_t[j] > 0: contact j is a Jenkins
     * element (method.md section 13), a spring k_t in series with a massless slider at s_j (the state's
     * slider[j]), f_j = -k_t (w_j . x - s_j): stuck (mode 0) the slider moves with its belt and
     * |f_j| <= Fb; sliding |f_j| = mu_k N against the slider's slip (mode: its side). It never constrains
     * the accelerations. At a breakaway the force drops from Fb to mu_k N: the slider jumps by
     * (Fb - mu_k N) / k_t and the spring energy released counts in W_friction. Coulomb law only, the
     * default friction solver only (no model solver, no sparse operators, no closed-form breakaway). */
    const double *k_t;
    double h;                   /* internal step > 0 (bossak.h's dfo_step_rule) */
    double alpha;               /* Bossak parameter in [-1/3, 0] */
    int scheme;                 /* DFO_SCHEME_PAPER, _CONSISTENT or _LOCATED */
    int friction_updates;       /* paper: coefficient updates (re-solves) per step, >= 0 */
    int account_energy;         /* keep eng_state's energy accounts (O(n) per step; no stuck fast path) */
    int fast_paths;             /* skip work a run does not need, to the same numbers: the located scheme's
                                 * stuck fast path where the model supplies ops.breakaway */
    /* the relative rounding of a trial's velocities and forces, in DBL_EPSILON of their magnitudes
     * (0: a few ulps); the located switch search treats margins within it as zero (roots.h's fnoise:
     * a search stops where its bracket's signs are rounding, not at the ulps of the time) */
    double margin_rounding;
    double rate_max;            /* the model's fastest rate (1/s): a step with rate_max h > 10 does not
                                 * resolve the motion (located hands it to the consistent test), and
                                 * A is re-based on a new step length only where rate_max h <= 1 */
    /* the snap of a requested time to the grid: within
     *   min(snap_max_rel_h h, max(snap_min_rel_h h, snap_eps_t DBL_EPSILON |t|))
     * of a grid point is that grid point (the oscillator: 1e-5, 1e-7, 2^16; the chain: 1e-7, 1e-7, 0) */
    double snap_max_rel_h, snap_min_rel_h, snap_eps_t;
    const eng_sparse *sparse;   /* the model's sparse-structure operators, or NULL (read while the engine lives) */
    const eng_coupling *coupling; /* the contacts' coupling operators, or NULL: the columns (read while the
                                 * engine lives) */
    eng_rest_fn on_rest;        /* the rest rule's report (NULL: none), with its context */
    void *rest_ctx;
    /* M is diagonal and the model's solves of the mass slot keep it so to the bit (a held contact's
     * force then reads its own DOFs only): where the contact rows also lie on distinct DOFs, their
     * holding forces do not depend on one another's modes, and the rest rule releases every contact
     * beyond its limit in one round, in the cascade's order (ENG_REST_RELEASE reports and modes as
     * one a round), two solves instead of one per release. 0: unknown (one a round). */
    int mass_diagonal;
    /* Propagate the located scheme's tangent: the derivative of the state (X, V, the sliders s) with
     * respect to the state at the run's start (eng_start), through every step in its modes, every
     * located switch (its time's derivative from its margin: the saltation) and every consistent
     * restart; read with eng_jacobian. The located scheme only, Coulomb law, the default friction
     * solver, no sparse operators (eng_check_setup says which); the schemes then take their
     * general path (no fast paths: the same numbers). The state needs its tangent (eng_state_init). */
    int tangent;
} eng_setup;

/* ---- inputs ---------------------------------------------------------------------------------- */

/* Inputs held over a communication step (NULL arrays: 0, never read), optionally varying over it as
 * polynomials (ramps): u(t) = u + du[0] (t - t_ref) + du[1] (t - t_ref)^2 / 2. Belts are inputs:
 * v_belt is carried here, per contact, and never stored by the engine. A belt is held over the
 * step (no derivative); the friction of contact j acts on g_j' - v_belt[j], and a stuck contact
 * moves with its belt. */
typedef struct eng_inputs_s {
    const double *F_ext;        /* n external forces */
    const double *N_ext;        /* nc normal-force inputs */
    const double *v_belt;       /* nc belt speeds (NULL: fixed supports) */
    const double *dF_ext[2];    /* n: first and second derivatives of F_ext at t_ref (NULL: 0) */
    const double *dN_ext[2];    /* nc: the same for N_ext */
    double t_ref;
} eng_inputs;

/* ---- state ------------------------------------------------------------------------------------ */

/* The trajectory: scalars plus arrays (n or nc long). Serialise the scalars and the arrays; copy
 * with eng_state_copy. */
typedef struct eng_state_s {
    size_t n, nc;
    double t0, t;               /* start time; current time */
    long long n_grid;           /* the last grid point reached is t0 + n_grid h */
    double *X, *V, *A;          /* n: positions, velocities, Bossak acceleration variables */
    double *hA;                 /* n: the step length that produced A (0: a physical acceleration) */
    double *F;                  /* nc: contact forces f at t (W' f acts on the DOFs) */
    double *slider;             /* nc: a Jenkins contact's slider position s_j (eng_setup.k_t; a rigid
                                 * contact's entry is not read: 0) */
    int *mode;                  /* nc: -1 / +1 sliding, 0 stuck (without friction: the sign of the slip) */
    double *t_stick;            /* nc: when the contact's current stick phase began */
    double *t_break;            /* nc: a stuck contact's next breakaway, if known (NaN: to be found; the
                                 * engine's schemes find breakaways by root finding and keep NaN here) */
    int *break_dir;             /* nc: its side */
    double t_switch;            /* the time of the last switch (-inf: none) */
    double stick_tb;            /* a structure stuck at rest (every contact held, every DOF pinned at
                                 * rest): its stick's breakaway (ops.breakaway, or its contacts' earliest),
                                 * found where the stick first needs it and kept while it lasts (NaN: to
                                 * be found). Every switch and eng_new_inputs forget it; eng_advance too,
                                 * at its start, unless its hooks say the caller checked it
                                 * (eng_hooks.stick_kept): so that a run split into calls places the
                                 * breakaway where one call does. */
    long long steps, solves, pivot_steps, switches;  /* counters */
    /* energy accounts since the start (J), kept with eng_setup.account_energy: the work of the applied
     * forces (excitation + F_ext, trapezoidal rule per (sub-)step), of friction (the step's force, or
     * for Stribeck the mean of its ends, times the DOFs' displacement along w_j; a Jenkins contact's:
     * its force times its slider's displacement (stuck: the mean of its ends), less the spring energy
     * released at its breakaways, so that its spring's energy 0.5 k_t (w_j . X - s_j)^2 counts in the
     * mechanical energy) and the dissipation in
     * C (trapezoidal); so that the mechanical energy's change is W_applied + W_friction - D_damping to
     * the scheme's error */
    double W_applied, W_friction, D_damping;
    long long exc_n;            /* excitation cache: cos, sin of omega (t0 + exc_n h) + phi0 (-1: empty) */
    double exc_c, exc_s;
    double *J;                  /* (2n)^2 row-major d(X, V)/d(X, V)(t_ref), or NULL: not propagated (eng_caps) */
    /* the located map's tangent (eng_setup.tangent; NULL without): 2 n + nc columns, one per start
     * value (x0, v0, the sliders'), each of 4 n + nc + 1 entries, the derivatives of X, V, A, hA, the
     * sliders and the time; read with eng_jacobian. tan_lost: a switch it could not follow (a margin
     * whose rate is 0 at its root: a grazing), from then on not computed. */
    double *tan;
    int tan_lost;
} eng_state;

/* ---- hooks ------------------------------------------------------------------------------------- */

/* A contact's change of mode: time, contact, the state there (positions and velocities at the
 * switch), from and to. */
typedef void (*eng_switch_fn)(void *ctx, double t, size_t contact, const eng_state *s, int from, int to);

/* One phase of the motion [ta, tb] with the contacts' modes constant over it (a step, a sub-step
 * between switches, or a stretch of stuck steps taken at once): what an observer needs to keep
 * extremes, stick times, transitions and dissipated energy. */
typedef struct {
    double ta, tb;
    const double *X0;           /* n: positions at ta */
    const double *X1;           /* n: positions at tb */
    const int *mode0;           /* nc: modes during the phase (located: those of its start; paper and
                                 * consistent: the step's friction problem's, those at its end) */
    const double *f;            /* nc: the contact forces over it (for the work: the step's end value, or
                                 * for Stribeck the mean of its ends) */
    const double *v_belt;       /* nc: belts (NULL: fixed) */
    const double *V0;           /* n: velocities at ta (with V1: a smooth motion's cubic between its ends, for
                                 * an observer's extremes inside the phase; NULL: not asked for,
                                 * eng_observer.velocities, or a model's own observer call) */
    const double *V1;           /* n: velocities at tb (NULL with V0) */
} eng_phase;

/* The observer: on_phase is called only for phases that overlap [t_start, t_stop] (so a run that
 * observes nothing pays one comparison per phase); every internal step, and every sub-step
 * between switches, is a phase. It reads the phase (ph) and the state s after it; in a model's
 * specialised fused steps (engine_step.h's ENG_FUSED_N) the state is written back only when a run
 * of them ends, so that there s's time and arrays are those of the run's start (ph->tb and ph->X1
 * are the phase's end). Such a model may also keep its observer's values in locals over the run
 * (engine_step.h's optional ENG_OBS_RUN hooks; by default on_phase is called for every phase). */
typedef struct {
    double t_start, t_stop;
    void (*on_phase)(void *ctx, const eng_phase *ph, const eng_state *s);
    void *ctx;
    int velocities;             /* the phases carry their velocities at both ends (eng_phase.V0, V1); 0:
                                 * NULL there, and the steps do not copy them */
} eng_observer;

typedef struct {
    eng_switch_fn on_switch;    /* NULL: none */
    void *switch_ctx;
    const eng_observer *obs;    /* NULL: none */
    int stop_at_switch;         /* return ENG_SWITCHED at the first switch, the state complete there */
    int report_turns;           /* a contact without friction reports each change of its mode (its slip's
                                 * direction) as a switch, at the end of the step that holds it (a
                                 * model that counts such a block's turns, as its closed form does);
                                 * else its mode follows its slip silently */
    int stick_kept;             /* the state's stick_tb is of this call's inputs and of the state's stick
                                 * (a caller that changed neither since it was found, or that checked it
                                 * against what it was found for): kept; else forgotten on entry */
} eng_hooks;

/* ---- the engine ---------------------------------------------------------------------------------- */

typedef struct eng eng;

/* eng_setup.margin_rounding for a model whose trials solve dense systems of size n (Cholesky or
 * modal): 16 ulps a DOF of the margins' terms (n = 128: 1e-13 of a slip velocity's terms measured,
 * 4.5e-13 given); 0 for n = 1 (a scalar solve rounds at an ulp, inside the time's tolerance: a
 * one-DOF structure stays the oscillator to the bit). */
static inline double eng_dense_margin_rounding(size_t n) { return (n > 1) ? 16.0 * (double)n : 0.0; }

/* Check a setup; NULL when valid, else a sentence naming the field and value, written to buf. */
const char *eng_check_setup(const eng_setup *S, char *buf, size_t len);

/* Create the engine (copies the setup struct, not its arrays; allocates its workspace); NULL on a
 * failed allocation or an invalid setup (then *err, if not NULL, says why). */
eng *eng_create(const eng_setup *S, const eng_alloc *al, const char **err);
void eng_destroy(eng *E);
const eng_setup *eng_setup_of(const eng *E);

/* What a scheme offers beyond the trajectory: ENG_CAP_SENSITIVITY, it propagates s->J when that
 * is not NULL. No Bossak scheme of the engine does yet (0 for every scheme; eng_start sets J to the
 * identity): a model asks before it offers the map's Jacobian. */
enum { ENG_CAP_SENSITIVITY = 1 };
int eng_caps(int scheme);

/* The located map's Jacobian d(X, V, s)(t)/d(X, V, s)(t0) of the state's tangent (eng_setup.tangent)
 * into J ((2 n + nc)^2, row-major: rows and columns x 1..n, v 1..n, then the contacts' sliders; a
 * rigid contact's row and column 0). Returns 0 (J untouched) where the state has no tangent or it
 * was lost (eng_state.tan_lost). */
int eng_jacobian(const eng_state *s, double *J);

/* The tangent's length (eng_state.tan): 2 n + nc columns of 4 n + nc + 1 */
static inline size_t eng_tan_size(size_t n, size_t nc) { return (2 * n + nc) * (4 * n + nc + 1); }

/* State arrays through the engine's callbacks (with_jacobian: J too; the tangent where the engine
 * propagates it); 0 on failure. */
int eng_state_init(const eng *E, eng_state *s, int with_jacobian);
void eng_state_free(const eng *E, eng_state *s);
/* The same for n DOFs and nc contacts through al, without an engine (a saved state; with_jacobian
 * bit 1: J, bit 2: the tangent); release with eng_state_release and the same al. */
int eng_state_alloc(const eng_alloc *al, size_t n, size_t nc, int with_jacobian, eng_state *s);
void eng_state_release(const eng_alloc *al, eng_state *s);
/* dst (initialised for the same sizes) := src, arrays included (J only when both have it). */
void eng_state_copy(eng_state *dst, const eng_state *src);

/* Consistent start-up at t0 from x0, v0 (n each): a contact whose slip is 0 is at rest, and the
 * rest rule of the contacts at rest together (their stuck forces solved jointly, a contact beyond
 * its limit released in the direction it is driven, repeated: the causal cascade from "all
 * stuck", method.md section 13) decides stick or slide; accelerations consistent with the modes. */
void eng_start(eng *E, const eng_inputs *in, double t0, const double *x0, const double *v0, eng_state *s);

/* After eng_start: the Jenkins contacts' sliders at s0 (nc; a rigid contact's entry not read), each
 * stuck (its spring force -k_t (w_j . x - s0_j) within its breakaway limit, 1e-12 of it beyond
 * allowed: a force on the limit rounded), or where slide (nc, NULL: none) is -1 or +1 sliding that
 * way with its force the kinetic one (its slider where that puts it, s0 not read); the accelerations
 * and forces consistent again, the tangent seeded anew. Returns 0 (s untouched) where a stuck
 * slider's force is beyond its limit or a slide is not -1, 0 or +1. */
int eng_set_sliders(eng *E, const eng_inputs *in, eng_state *s, const double *s0, const int *slide);

/* The time eng_advance ends on for t_target: the grid point it snaps to, else t_target. */
double eng_snap_target(const eng *E, const eng_state *s, double t_target);

/* Advance to t_target > s->t with the inputs in (held, or ramped). On ENG_OK s->t is exactly
 * eng_snap_target(E, s_before, t_target); on ENG_SWITCHED the time of the first switch. hooks may
 * be NULL. */
eng_status eng_advance(eng *E, const eng_inputs *in, eng_state *s, double t_target, const eng_hooks *hooks);

/* Inputs changed at the communication point s->t (from old_in to new_in, held over the next step):
 * a sliding contact's DOFs take the jump of the physical acceleration and its force the new
 * kinetic force; a belt that changed makes each contact's mode that of its new slip (one the belt
 * meets takes the rest rule), and the new mode set restarts consistently (switches reported). */
void eng_new_inputs(eng *E, const eng_inputs *old_in, const eng_inputs *new_in, eng_state *s,
                    const eng_hooks *hooks);

/* Physical accelerations (n) at the state in its modes (stuck contacts' slip acceleration 0). */
void eng_accelerations(eng *E, const eng_inputs *in, const eng_state *s, double *a);
/* The contact forces (nc) at the state as the schemes whose stuck contacts rest report them: a
 * sliding contact's kinetic force, a stuck one's holding force (clamped to its limit). */
void eng_contact_forces(eng *E, const eng_inputs *in, const eng_state *s, double *f);

/* The default friction solver: the Delassus matrix of the held contacts through ops.solve, the
 * basis solve by Cholesky, the LCP (ENG_SOLVE_LCP) in its standard 2 nc form by Lemke (lcp.h),
 * warm-started from *mode. A model's solver may call it as its fallback (ctx: the engine). */
eng_status eng_dense_friction(void *engine, const eng_problem *P, int what, int *mode, double *V1, double *f,
                              int *pivots);

/* The entry points above as a model's specialisation of the schemes names them (engine_step.h with
 * ENG_FN(name) = prefix##name, ENG_API empty): ENG_DECLARE_SCHEMES(osc_) in the model's header
 * declares osc_eng_start, osc_eng_advance, ... */
#define ENG_DECLARE_SCHEMES(prefix)                                                                                  \
    void prefix##eng_start(eng *E, const eng_inputs *in, double t0, const double *x0, const double *v0,               \
                           eng_state *s);                                                                            \
    double prefix##eng_snap_target(const eng *E, const eng_state *s, double t_target);                               \
    eng_status prefix##eng_advance(eng *E, const eng_inputs *in, eng_state *s, double t_target,                      \
                                   const eng_hooks *hooks);                                                          \
    void prefix##eng_new_inputs(eng *E, const eng_inputs *old_in, const eng_inputs *new_in, eng_state *s,            \
                                const eng_hooks *hooks);                                                             \
    void prefix##eng_accelerations(eng *E, const eng_inputs *in, const eng_state *s, double *a);                     \
    void prefix##eng_contact_forces(eng *E, const eng_inputs *in, const eng_state *s, double *f);                    \
    eng_status prefix##eng_dense_friction(void *engine, const eng_problem *P, int what, int *mode, double *V1,       \
                                          double *f, int *pivots)

#endif
