/* A chain of n blocks with dry friction. See chain.h and method.md section 9. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain.h"

#include "bossak.h"
#include "dmath.h"
#include "friction.h"
#include "oscillator.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define EXC_ANCHOR 64           /* grid points between exact evaluations of the excitation phase */
#define SNAP_REL_H 1e-7         /* a requested time this close (in h) to a grid point is that point */
#define HALVINGS 60             /* search for a sub-step before the first switch */
#define STIFF_STEP 10.0         /* rate_max h above which a step does not resolve the motion */

/* The fast path of a grid step is inlined into the stepping loop (as the oscillator's step). */
#if defined(__GNUC__)
#define HOT_INLINE inline __attribute__((always_inline))
#define COLD_CALL __attribute__((noinline))
#else
#define HOT_INLINE inline
#define COLD_CALL
#endif

/* A block's data for the fused grid step (step_fast, solve_kept), together in memory: copies of its
 * constants (d, e: M_hat of a whole grid step) and of its loads (loads_init), and the factorisation
 * of that M_hat with the held rows replaced by V_i = 0 (Thomas: cp and 1 / den), kept for the held
 * pattern of fh (0: none yet, 1 free, 2 held); see step_fast. */
typedef struct {
    double Pc, Ps, u, am, am1, Kd, Ko, d, e, Fb, mukN;
    double cp, inv;
    int fh, pad;
} fast_row;

struct chain_model {
    chain_alloc al;
    size_t n;
    double k_end, c_end, omega, h, alpha, gamma, beta, g1, rate_max;
    double T_min;               /* the shortest period of the dynamics (chain_shortest_period) */
    double rot_c, rot_s;        /* cos and sin of omega h: the excitation phase's advance per step */
    double phi0;                /* the phase every block shares (then Pc = P0, Ps = 0: each block's excitation
                                 * is P0 cos(omega t + phi0), evaluated as the oscillator's), else 0 */
    int scheme, energy, damped;
    int stuck_ok;               /* the stuck fast path may apply (stuck_until): located, no energy
                                 * accounts, a grid step resolving the motion, friction on every block */
    /* per block (length n) */
    double *m, *am, *am1, *Pc, *Ps, *P0, *phi, *N, *mu_k, *mu_b, *x0, *v0;
    double *Kd, *Ko, *Cd, *Co;  /* K and C: diagonal, and Ko[i], Co[i] coupling i and i + 1 */
    double *dF, *eF;            /* M_hat of a whole grid step */
    fast_row *rows;             /* per block, for the fused grid step */
    /* workspace */
    double *d, *e;              /* M_hat of the current trial step (when it is not a grid step) */
    double *A0, *xp, *ph, *Vt, *Ft, *cp, *dp, *u, *mukN, *Fb, *S, *l;
    double *sX, *sV, *sA, *sF, *shA;  /* blocks' states saved around a cluster (step_located) */
    double *J;                  /* jerks at the current state (trial's re-basing), when jerk_valid */
    int jerk_valid;
    double *box;                /* 2n: the box LCP's work */
    int *frozen, *st, *smode;
    size_t *cand, *clu;         /* candidates (n), clusters (2n) */
    size_t w;                   /* a cluster's half-width (step_located) */
    /* the current trial */
    const double *cd, *ce;      /* its M_hat */
    const double *A0p;          /* its re-based A0: A0, or the state's A when nothing is re-based */
    int any_frozen;             /* frozen may hold a 1 */
    dfo_bossak_kin kin, kinF;   /* the trial's kinematics; a grid step's */
    double cw1, sw1;            /* cos, sin of omega t at its end */
    size_t ncand;
    chain_status err;
    int switched;
};

/* ---- parameters ------------------------------------------------------------------------------ */

static const char *bad(char *buf, size_t len, const char *name, size_t i, double v, const char *range)
{
    snprintf(buf, len, "invalid value %g for %s[%zu] (valid: %s)", v, name, i + 1, range);
    return buf;
}

static const char *bad_scalar(char *buf, size_t len, const char *name, double v, const char *range)
{
    snprintf(buf, len, "invalid value %g for %s (valid: %s)", v, name, range);
    return buf;
}

const char *chain_check_params(const chain_params *p, char *buf, size_t len)
{
    if (p->n < 1) { snprintf(buf, len, "invalid value %zu for n (valid: >= 1)", p->n); return buf; }
    for (size_t i = 0; i < p->n; i++) {
        if (!(p->m[i] > 0.0 && isfinite(p->m[i]))) return bad(buf, len, "m", i, p->m[i], "> 0, finite");
        if (!(p->k[i] >= 0.0 && isfinite(p->k[i]))) return bad(buf, len, "k", i, p->k[i], ">= 0, finite");
        if (!(p->c[i] >= 0.0 && isfinite(p->c[i]))) return bad(buf, len, "c", i, p->c[i], ">= 0, finite");
        if (!isfinite(p->P0[i])) return bad(buf, len, "P0", i, p->P0[i], "finite");
        if (!isfinite(p->phi[i])) return bad(buf, len, "phi", i, p->phi[i], "finite");
        if (!(p->N[i] >= 0.0 && isfinite(p->N[i]))) return bad(buf, len, "N", i, p->N[i], ">= 0, finite");
        if (!(p->mu_s[i] >= 0.0 && isfinite(p->mu_s[i]))) return bad(buf, len, "mu_s", i, p->mu_s[i], ">= 0, finite");
        if (!(p->chi[i] >= 0.0 && isfinite(p->chi[i]))) return bad(buf, len, "chi", i, p->chi[i], ">= 0, finite");
        if (!isfinite(p->x0[i])) return bad(buf, len, "x0", i, p->x0[i], "finite");
        if (!isfinite(p->v0[i])) return bad(buf, len, "v0", i, p->v0[i], "finite");
    }
    if (!(p->k_end >= 0.0 && isfinite(p->k_end))) return bad_scalar(buf, len, "k_end", p->k_end, ">= 0, finite");
    if (!(p->c_end >= 0.0 && isfinite(p->c_end))) return bad_scalar(buf, len, "c_end", p->c_end, ">= 0, finite");
    if (!(p->omega >= 0.0 && isfinite(p->omega))) return bad_scalar(buf, len, "omega", p->omega, ">= 0, finite");
    if (!(p->h > 0.0 && isfinite(p->h))) return bad_scalar(buf, len, "h", p->h, "> 0, finite");
    if (!(p->alpha >= -1.0 / 3.0 && p->alpha <= 0.0)) return bad_scalar(buf, len, "alpha", p->alpha, "[-1/3, 0]");
    if (p->scheme < DFO_SCHEME_PAPER || p->scheme > DFO_SCHEME_LOCATED) {
        snprintf(buf, len, "invalid value %d for scheme (valid: 1 paper, 2 consistent, 3 located)", p->scheme);
        return buf;
    }
    return NULL;
}

static double *dalloc(const chain_alloc *al, size_t n) { return (double *)al->allocate(al->env, n, sizeof(double)); }

/* Gershgorin bounds of the largest eigenvalues of M^-1 K and M^-1 C: each row's diagonal plus its
 * off-diagonals, over its mass (one block: its own). */
static void gershgorin(const chain_params *p, double *kmax, double *cmax)
{
    const size_t n = p->n;
    *kmax = *cmax = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double kr = (i + 1 < n) ? p->k[i + 1] : p->k_end, cr = (i + 1 < n) ? p->c[i + 1] : p->c_end;
        const double kl = (i > 0) ? p->k[i] : 0.0, cl = (i > 0) ? p->c[i] : 0.0;
        const double kd = p->k[i] + kr, cd = p->c[i] + cr;
        *kmax = fmax(*kmax, (n == 1 ? kd : kd + kl + ((i + 1 < n) ? kr : 0.0)) / p->m[i]);
        *cmax = fmax(*cmax, (n == 1 ? cd : cd + cl + ((i + 1 < n) ? cr : 0.0)) / p->m[i]);
    }
}

/* 2 pi over the fastest of sqrt(kmax), cmax (a rate taken as an angular frequency) and |omega|. */
static double shortest_period(double kmax, double cmax, double omega)
{
    const double fastest = fmax(fmax(sqrt(kmax), cmax), fabs(omega));
    return fastest > 0.0 ? 2.0 * DFO_PI / fastest : INFINITY;
}

chain_model *chain_create(const chain_params *p, const chain_alloc *al, const char **err)
{
    static const char *const oom = "out of memory";
    char buf[160];
    const char *msg = chain_check_params(p, buf, sizeof buf);
    if (msg) { if (err) *err = "invalid parameters (chain_check_params names the first one)"; return NULL; }
    chain_model *M = (chain_model *)al->allocate(al->env, 1, sizeof(chain_model));
    if (!M) { if (err) *err = oom; return NULL; }
    const size_t n = p->n;
    M->al = *al;
    M->n = n;
    /* one block of doubles for all per-block arrays (39 of them, the last, box, 2n long), one for
     * the ints, one for the candidates and clusters */
    enum { NARR = 39 };
    double *blk = dalloc(al, (NARR + 1) * n);
    int *iblk = (int *)al->allocate(al->env, 3 * n, sizeof(int));
    M->cand = (size_t *)al->allocate(al->env, 3 * n, sizeof(size_t));
    M->rows = (fast_row *)al->allocate(al->env, n, sizeof(fast_row));
    if (!blk || !iblk || !M->cand || !M->rows) {
        if (blk) al->release(al->env, blk);
        if (iblk) al->release(al->env, iblk);
        if (M->cand) al->release(al->env, M->cand);
        if (M->rows) al->release(al->env, M->rows);
        al->release(al->env, M);
        if (err) *err = oom;
        return NULL;
    }
    double **arr[NARR] = {&M->m, &M->am, &M->am1, &M->Pc, &M->Ps, &M->P0, &M->phi, &M->N, &M->mu_k, &M->mu_b,
                          &M->x0, &M->v0,
                          &M->Kd, &M->Ko, &M->Cd, &M->Co, &M->dF, &M->eF, &M->d, &M->e, &M->A0, &M->xp,
                          &M->ph, &M->Vt, &M->Ft, &M->cp, &M->dp, &M->u, &M->mukN, &M->Fb, &M->S, &M->l,
                          &M->sX, &M->sV, &M->sA, &M->sF, &M->shA, &M->J, &M->box};
    for (int j = 0; j < NARR; j++) *arr[j] = blk + (size_t)j * n;
    M->frozen = iblk;
    M->st = iblk + n;
    M->smode = iblk + 2 * n;
    M->clu = M->cand + n;
    M->k_end = p->k_end;
    M->c_end = p->c_end;
    M->omega = p->omega;
    M->h = p->h;
    M->rot_c = dfo_cos(p->omega * p->h);
    M->rot_s = dfo_sin(p->omega * p->h);
    M->phi0 = p->phi[0];
    for (size_t i = 1; i < n; i++)
        if (p->phi[i] != p->phi[0]) M->phi0 = 0.0;
    M->alpha = p->alpha;
    M->gamma = dfo_bossak_gamma(p->alpha);
    M->beta = dfo_bossak_beta(p->alpha);
    M->g1 = (1.0 - M->gamma) / M->gamma;
    M->scheme = p->scheme;
    M->energy = p->account_energy;
    M->damped = p->c_end != 0.0;
    double kmax = 0.0, cmax = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double kr = (i + 1 < n) ? p->k[i + 1] : p->k_end, cr = (i + 1 < n) ? p->c[i + 1] : p->c_end;
        M->m[i] = p->m[i];
        M->am[i] = p->alpha * p->m[i];
        M->am1[i] = (1.0 - p->alpha) * p->m[i];
        M->Pc[i] = p->P0[i] * dfo_cos(p->phi[i] - M->phi0);
        M->Ps[i] = (M->phi0 == p->phi[i]) ? 0.0 : p->P0[i] * dfo_sin(p->phi[i]);
        M->P0[i] = p->P0[i];
        M->phi[i] = p->phi[i];
        M->N[i] = p->N[i];
        M->mu_k[i] = p->chi[i] * p->mu_s[i];
        M->mu_b[i] = fmax(p->mu_s[i], M->mu_k[i]);
        M->x0[i] = p->x0[i];
        M->v0[i] = p->v0[i];
        M->Kd[i] = p->k[i] + kr;
        M->Cd[i] = p->c[i] + cr;
        M->Ko[i] = (i + 1 < n) ? -kr : 0.0;
        M->Co[i] = (i + 1 < n) ? -cr : 0.0;
        if (p->c[i] != 0.0) M->damped = 1;
    }
    gershgorin(p, &kmax, &cmax);
    M->rate_max = sqrt(kmax) + cmax + fabs(p->omega);
    M->T_min = shortest_period(kmax, cmax, p->omega);
    dfo_bossak_kin_for(p->h, M->gamma, M->beta, &M->kinF);
    M->kin = M->kinF;
    const double c1 = M->kin.c1, bhg = M->beta * p->h / M->gamma;
    for (size_t i = 0; i < n; i++) {
        /* (k b) h / g, associated as the oscillator's m_hat (n = 1 gives its bits there) */
        M->dF[i] = M->am1[i] * c1 + M->Kd[i] * M->beta * p->h / M->gamma + M->Cd[i];
        M->eF[i] = M->Ko[i] * bhg + M->Co[i];
    }
    for (size_t i = 0; i < n; i++) {
        fast_row *R = &M->rows[i];
        R->Pc = M->Pc[i]; R->Ps = M->Ps[i]; R->am = M->am[i]; R->am1 = M->am1[i];
        R->Kd = M->Kd[i]; R->Ko = M->Ko[i]; R->d = M->dF[i]; R->e = M->eF[i];
        R->u = R->Fb = R->mukN = 0.0;  /* (loads_init) */
        R->fh = 0;
    }
    /* beyond w blocks the influence of a block inside one step is below 2^-56: M_hat^-1 decays like
     * q^distance with q = (sqrt(kappa) - 1) / (sqrt(kappa) + 1) (Demko, Moss and Smith, 1984), kappa
     * <= (1 + rho) / (1 - rho) the condition number of the diagonally scaled M_hat by Gershgorin,
     * rho the largest ratio of a row's off-diagonal sum to its diagonal (shorter steps: smaller) */
    double rho = 0.0;
    for (size_t i = 0; i < n; i++) rho = fmax(rho, (fabs(i > 0 ? M->eF[i - 1] : 0.0) + fabs(M->eF[i])) / M->dF[i]);
    const double sk = sqrt((1.0 + rho) / (1.0 - fmin(rho, 0.5))), q = (sk - 1.0) / (sk + 1.0);
    /* the smallest w with q^w <= 2^-56, by products (no libm log2: the same bits everywhere and
     * no newer glibc symbol); q <= 0.27 here, so at most 30 products */
    size_t w = 1;
    if (rho >= 0.5) w = n;
    else if (rho > 0.0)
        for (double qw = q; qw > 0x1p-56; qw *= q) w++;
    M->w = w;
    if (err) *err = NULL;
    return M;
}

double chain_shortest_period(const chain_model *M) { return M->T_min; }

double chain_step(const chain_model *M) { return M->h; }

double chain_shortest_period_of(const chain_params *p)
{
    double kmax, cmax;
    gershgorin(p, &kmax, &cmax);
    return shortest_period(kmax, cmax, p->omega);
}

double chain_step_size(const chain_params *p)
{
    return p->h > 0.0 ? p->h : dfo_step_rule(0.0, chain_shortest_period_of(p));
}

void chain_destroy(chain_model *M)
{
    if (!M) return;
    const chain_alloc al = M->al;
    al.release(al.env, M->m);
    al.release(al.env, M->frozen);
    al.release(al.env, M->cand);
    al.release(al.env, M->rows);
    al.release(al.env, M);
}

size_t chain_size(const chain_model *M) { return M->n; }

int chain_state_init(const chain_model *M, chain_state *s) { return chain_state_alloc(&M->al, M->n, s); }

void chain_state_free(const chain_model *M, chain_state *s) { chain_state_release(&M->al, s); }

void chain_state_copy(chain_state *dst, const chain_state *src)
{
    double *X = dst->X, *V = dst->V, *A = dst->A, *F = dst->F, *hA = dst->hA, *ts = dst->t_stick;
    int *mode = dst->mode;
    const size_t n = src->n;
    *dst = *src;
    dst->X = X; dst->V = V; dst->A = A; dst->F = F; dst->hA = hA; dst->t_stick = ts; dst->mode = mode;
    memcpy(hA, src->hA, n * sizeof *hA);
    memcpy(ts, src->t_stick, n * sizeof *ts);
    memcpy(X, src->X, n * sizeof *X);
    memcpy(V, src->V, n * sizeof *V);
    memcpy(A, src->A, n * sizeof *A);
    memcpy(F, src->F, n * sizeof *F);
    memcpy(mode, src->mode, n * sizeof *mode);
}

/* ---- forces ---------------------------------------------------------------------------------- */

static int sgn(double x) { return (x > 0.0) - (x < 0.0); }

static void loads_init(chain_model *M, const chain_inputs *in)
{
    int all_friction = 1;
    for (size_t i = 0; i < M->n; i++) {
        const double N = (in && in->N_ext) ? fmax(M->N[i] + in->N_ext[i], 0.0) : M->N[i];
        M->u[i] = (in && in->F_ext) ? in->F_ext[i] : 0.0;
        M->mukN[i] = M->mu_k[i] * N;
        M->Fb[i] = M->mu_b[i] * N;
        M->rows[i].u = M->u[i];
        M->rows[i].mukN = M->mukN[i];
        M->rows[i].Fb = M->Fb[i];
        all_friction &= (M->Fb[i] > 0.0);
    }
    M->stuck_ok = M->scheme == DFO_SCHEME_LOCATED && !M->energy && M->rate_max * M->h <= 1.0 && all_friction;
}

/* rotations keep c^2 + s^2 = 1 only to rounding: a cosine or sine never exceeds 1 (as the
 * oscillator's excitation) */
static double clamp1(double x) { return x > 1.0 ? 1.0 : x < -1.0 ? -1.0 : x; }

/* cos and sin of omega t at the grid point g of the state (cached, see chain_state) */
static void grid_phase(const chain_model *M, chain_state *s, long long g, double *cw, double *sw)
{
    const double rc = M->rot_c, rs = M->rot_s;
    double c, sn;
    long long i;
    if (s->exc_n >= 0 && s->exc_n == g - 1 && g % EXC_ANCHOR != 0) {
        c = s->exc_c; sn = s->exc_s; i = g - 1;
    } else {
        i = g - g % EXC_ANCHOR;
        const double th = M->omega * (s->t0 + (double)i * M->h) + M->phi0;
        c = dfo_cos(th); sn = dfo_sin(th);
    }
    for (; i < g; i++) {
        const double cn = c * rc - sn * rs;
        sn = sn * rc + c * rs;
        c = cn;
    }
    s->exc_n = g;
    s->exc_c = c;
    s->exc_s = sn;
    *cw = clamp1(c);
    *sw = clamp1(sn);
}

static void phase_of(const chain_model *M, const chain_state *s, double t, double *cw, double *sw)
{
    if (s->exc_n >= 0 && t == s->t0 + (double)s->exc_n * M->h) {
        *cw = clamp1(s->exc_c);
        *sw = clamp1(s->exc_s);
        return;
    }
    *cw = dfo_cos(M->omega * t + M->phi0);
    *sw = dfo_sin(M->omega * t + M->phi0);
}

static double (P_at)(const chain_model *M, size_t i, double cw, double sw) { return M->Pc[i] * cw - M->Ps[i] * sw; }

/* (K x)_i and (C v)_i */
static double Kx(const chain_model *M, const double *x, size_t i)
{
    double f = M->Kd[i] * x[i];
    if (i > 0) f += M->Ko[i - 1] * x[i - 1];
    if (i + 1 < M->n) f += M->Ko[i] * x[i + 1];
    return f;
}
static double Cv(const chain_model *M, const double *v, size_t i)
{
    if (!M->damped) return 0.0;
    double f = M->Cd[i] * v[i];
    if (i > 0) f += M->Co[i - 1] * v[i - 1];
    if (i + 1 < M->n) f += M->Co[i] * v[i + 1];
    return f;
}

/* A span of blocks [a, b) stepped on its own: the whole chain, or a cluster around switching
 * blocks (see step_located). A cluster's outside neighbours a - 1 and b are ghosts: their motion
 * over the step, interpolated (cubic Hermite) between their states at its start and end, is
 * written into the state arrays at the current time. */
typedef struct {
    size_t a, b;
    int has[2];       /* ghost a - 1 (0), ghost b (1) present */
    size_t idx[2];
    double t_start, H;
    double X0[2], V0[2], X1[2], V1[2];
    double gV[2];     /* the ghosts' velocities at the end of the current trial (Dirichlet rows) */
} span;

static void ghost_at(const span *G, int k, double tau, double *x, double *v, double *acc)
{
    const double H = G->H, r = tau / H, dx = G->X1[k] - G->X0[k], v0 = G->V0[k], v1 = G->V1[k];
    *x = G->X0[k] + v0 * H * (r * r * r - 2.0 * r * r + r) + dx * (3.0 * r * r - 2.0 * r * r * r) +
         v1 * H * (r * r * r - r * r);
    *v = v0 * (3.0 * r * r - 4.0 * r + 1.0) + dx / H * (6.0 * r - 6.0 * r * r) + v1 * (3.0 * r * r - 2.0 * r);
    *acc = (v0 * (6.0 * r - 4.0) + dx / H * (6.0 - 12.0 * r) + v1 * (6.0 * r - 2.0)) / H;
}

/* Write the ghosts' state at the current time into the state arrays. */
static void set_ghosts(chain_model *M, chain_state *s, const span *G)
{
    M->jerk_valid = 0;
    for (int k = 0; k < 2; k++)
        if (G->has[k]) ghost_at(G, k, s->t - G->t_start, &s->X[G->idx[k]], &s->V[G->idx[k]], &s->A[G->idx[k]]);
}

/* Net applied force on the span's blocks at the state (excitation, inputs, springs, dampers). */
static void net_forces(chain_model *M, const chain_state *s, const span *G, double *S)
{
    double cw, sw;
    phase_of(M, s, s->t, &cw, &sw);
    for (size_t i = G->a; i < G->b; i++) S[i] = P_at(M, i, cw, sw) + M->u[i] - Kx(M, s->X, i) - Cv(M, s->V, i);
}

static int has_friction(const chain_model *M, size_t i) { return M->Fb[i] > 0.0; }

/* held at rest in the current step: stuck (schemes whose stuck blocks rest) */
static int held(const chain_model *M, const chain_state *s, size_t i)
{
    return s->mode[i] == 0 && has_friction(M, i);
}

/* Physical accelerations at the state: stuck blocks 0, the others from the equation of motion. */
static void accelerations(chain_model *M, const chain_state *s, const span *G, double *a)
{
    double cw, sw;
    phase_of(M, s, s->t, &cw, &sw);
    for (size_t i = G->a; i < G->b; i++) {
        if (held(M, s, i)) { a[i] = 0.0; continue; }
        const double F = has_friction(M, i) ? -s->mode[i] * M->mukN[i] : 0.0;
        /* summed as the oscillator's accel_of */
        a[i] = (P_at(M, i, cw, sw) + M->u[i] - Kx(M, s->X, i) + F - Cv(M, s->V, i)) / M->m[i];
    }
}

/* The same, and the net applied forces into M->S. */
static void physical_accel(chain_model *M, const chain_state *s, const span *G, double *a)
{
    net_forces(M, s, G, M->S);
    accelerations(M, s, G, a);
}

static span whole(const chain_model *M, const chain_state *s)
{
    span G;
    memset(&G, 0, sizeof G);
    G.a = 0;
    G.b = M->n;
    G.t_start = s->t;
    return G;
}

void chain_accelerations(chain_model *M, const chain_inputs *in, const chain_state *s0, double *a)
{
    loads_init(M, in);
    /* the excitation in closed form at s->t, as the oscillator's output a (dfo_acceleration): the
     * state's grid cache would round otherwise where omega t + phi does (a large phi) */
    chain_state copy = *s0;
    copy.exc_n = -1;
    const chain_state *s = &copy;
    const span G = whole(M, s);
    physical_accel(M, s, &G, a);
    if (M->scheme != DFO_SCHEME_PAPER) return;
    /* the paper's stuck block is not at rest: it creeps with the force of its LCP (Bossak's A
     * throughout), as the oscillator reports it */
    double cw, sw;
    phase_of(M, s, s->t, &cw, &sw);
    for (size_t i = 0; i < M->n; i++)
        if (held(M, s, i))
            a[i] = (P_at(M, i, cw, sw) + M->u[i] - Kx(M, s->X, i) + s->F[i] - Cv(M, s->V, i)) / M->m[i];
}

double chain_energy(const chain_model *M, const chain_state *s)
{
    double E = 0.0;
    for (size_t i = 0; i < M->n; i++) {
        const double ext = s->X[i] - (i > 0 ? s->X[i - 1] : 0.0);
        const double kl = M->Kd[i] + ((i + 1 < M->n) ? M->Ko[i] : -M->k_end);
        E += 0.5 * M->m[i] * s->V[i] * s->V[i] + 0.5 * kl * ext * ext;
    }
    E += 0.5 * M->k_end * s->X[M->n - 1] * s->X[M->n - 1];
    return E;
}

/* v^T C v */
static double damping_power(const chain_model *M, const double *v)
{
    double D = 0.0;
    for (size_t i = 0; i < M->n; i++) {
        const double dv = v[i] - (i > 0 ? v[i - 1] : 0.0);
        const double cl = M->Cd[i] + ((i + 1 < M->n) ? M->Co[i] : -M->c_end);
        D += cl * dv * dv;
    }
    return D + M->c_end * v[M->n - 1] * v[M->n - 1];
}

/* ---- one trial step ------------------------------------------------------------------------- */

/* The step of length hh of the span's blocks from the state to t1 (cw1, sw1: the excitation phase
 * at t1): M_hat, the re-based A0, the predicted position xp and p_hat (method.md sections 2, 8
 * and 9); a ghost's xp and velocity at t1 from its interpolation. */
static void trial(chain_model *M, const chain_state *s, span *G, double hh, double cw1, double sw1)
{
    const size_t n = M->n, a0 = G->a, b0 = G->b;
    if (hh == M->h) {
        M->kin = M->kinF;
        M->cd = M->dF;
        M->ce = M->eF;
    } else {
        dfo_bossak_kin_for(hh, M->gamma, M->beta, &M->kin);
        const double c1 = M->kin.c1, bhg = M->beta * hh / M->gamma;
        const size_t lo = a0 - (size_t)G->has[0], hi = b0 + (size_t)G->has[1];
        for (size_t i = lo; i < hi; i++) {
            M->d[i] = M->am1[i] * c1 + M->Kd[i] * M->beta * hh / M->gamma + M->Cd[i];
            M->e[i] = M->Ko[i] * bhg + M->Co[i];
        }
        M->cd = M->d;
        M->ce = M->e;
    }
    M->cw1 = cw1;
    M->sw1 = sw1;
    const double a = M->alpha;
    /* Bossak's A belongs to the step length hA: re-based on hh with the jerk (section 8) */
    int rebase = 0;
    if (a != 0.0) {
        for (size_t i = a0; i < b0 && !rebase; i++) {
            const double hA = s->hA[i];
            rebase = hh != hA && fabs(hh - hA) > 1e-12 * hh + 4.0 * DBL_EPSILON * fabs(s->t) &&
                     M->rate_max * fmax(hh, hA) <= 1.0;
        }
    }
    if (rebase && !M->jerk_valid) {
        /* jerk_i = (P'_i - (K V)_i - (C a)_i) / m_i for the moving blocks, 0 for the held ones; a
         * function of the state only, kept for the further trials from it (root finding) */
        /* the excitation's rate -P0 omega sin(omega t + phi), as the oscillator's */
        const double cw = dfo_cos(M->omega * s->t + M->phi0), sw = dfo_sin(M->omega * s->t + M->phi0);
        accelerations(M, s, G, M->A0);  /* physical accelerations, in A0 for now */
        for (int k = 0; k < 2; k++)
            if (G->has[k]) M->A0[G->idx[k]] = s->A[G->idx[k]];
        for (size_t i = a0; i < b0; i++) {
            double j = 0.0;
            if (!held(M, s, i)) {
                const double Pd = -M->Pc[i] * M->omega * sw + -M->Ps[i] * M->omega * cw;
                j = (Pd - Kx(M, s->V, i) - Cv(M, M->A0, i)) / M->m[i];
            }
            M->J[i] = j;
        }
        M->jerk_valid = 1;
    }
    if (rebase) {
        for (size_t i = a0; i < b0; i++) {
            const double hA = s->hA[i];
            const int ri = hh != hA && fabs(hh - hA) > 1e-12 * hh + 4.0 * DBL_EPSILON * fabs(s->t) &&
                           M->rate_max * fmax(hh, hA) <= 1.0;
            M->A0[i] = ri ? s->A[i] + a * (hh - hA) * M->J[i] : s->A[i];
        }
        M->A0p = M->A0;
    } else {
        M->A0p = s->A;
    }
    const double c1 = M->kin.c1, pV = M->kin.pred_V, pA = M->kin.pred_A, g1 = M->g1;
    const double *X = s->X, *V = s->V, *A0 = M->A0p;
    double *xp = M->xp, *ph = M->ph;
    for (size_t i = a0; i < b0; i++) xp[i] = X[i] + pV * V[i] + pA * A0[i];
    for (int k = 0; k < 2; k++) {
        if (!G->has[k]) continue;
        double xg, vg, ag;
        ghost_at(G, k, s->t - G->t_start + hh, &xg, &vg, &ag);
        xp[G->idx[k]] = xg - M->kin.corr_V * vg;  /* so that xp + corr_V V1 is the ghost's x */
        G->gV[k] = vg;
    }
    for (size_t i = a0; i < b0; i++) {
        double kx = M->Kd[i] * xp[i];
        if (i > 0) kx += M->Ko[i - 1] * xp[i - 1];
        if (i + 1 < n) kx += M->Ko[i] * xp[i + 1];
        ph[i] = M->Pc[i] * cw1 - M->Ps[i] * sw1 + M->u[i] - M->am[i] * A0[i] +
                M->am1[i] * (V[i] * c1 + g1 * A0[i]) - kx;
    }
}

/* Tridiagonal solve of M_hat V = p + F over [lo, hi) with rows in mode 0 (and l > 0) held at V = 0
 * and the others sliding with F = -mode l (l = 0: free, F = 0); ghost rows (gl, gr: present) fixed
 * at their velocities vl, vr. Held rows get F = (M_hat V)_i - p_i. */
static void solve_rows(size_t lo, size_t hi, int gl, double vl, int gr, double vr, const double *d, const double *e,
                       const double *p, const double *l, const int *mode, double *V, double *F, double *cp, double *dp)
{
    double cprev = 0.0, dprev = 0.0;
    for (size_t i = lo; i < hi; i++) {
        if ((gl && i == lo) || (gr && i == hi - 1)) {
            cp[i] = 0.0;
            dp[i] = (gl && i == lo) ? vl : vr;
        } else if (mode[i] == 0 && l[i] > 0.0) {
            cp[i] = 0.0;
            dp[i] = 0.0;
        } else {
            const double lo_e = (i > lo) ? e[i - 1] : 0.0;
            const double rhs = p[i] - ((l[i] > 0.0) ? mode[i] * l[i] : 0.0);
            const double den = d[i] - lo_e * cprev;
            const double inv = 1.0 / den;
            cp[i] = (i + 1 < hi) ? e[i] * inv : 0.0;  /* e has hi - 1 entries */
            dp[i] = (rhs - lo_e * dprev) * inv;
        }
        cprev = cp[i];
        dprev = dp[i];
    }
    double vn = 0.0;
    for (size_t j = hi; j-- > lo;) {
        vn = dp[j] - cp[j] * vn;
        V[j] = vn;
    }
    const size_t a = lo + (size_t)gl, b = hi - (size_t)gr;
    for (size_t i = a; i < b; i++) {
        if (mode[i] == 0 && l[i] > 0.0) {
            V[i] = 0.0;
            double f = -p[i];
            if (i > lo) f += e[i - 1] * V[i - 1];
            if (i + 1 < hi) f += e[i] * V[i + 1];
            F[i] = f;
        } else {
            F[i] = (l[i] > 0.0) ? 0.0 - mode[i] * l[i] : 0.0;
        }
    }
}

static void solve_held(size_t n, const double *d, const double *e, const double *p, const double *l,
                       const int *mode, double *V, double *F, double *cp, double *dp)
{
    solve_rows(0, n, 0, 0.0, 0, 0.0, d, e, p, l, mode, V, F, cp, dp);
}

/* Principal pivoting from the modes: all infeasible rows flipped for three rounds, then the least
 * index only (Murty's rule). Returns the pivots, or -1 when the budget ran out. */
static long pivoting(size_t n, const double *d, const double *e, const double *p, const double *l, int *mode,
                     double *V, double *F, double *work, long max_it, double tol)
{
    double *cp = work, *dp = work + n;
    for (long it = 0; it < max_it; it++) {
        solve_held(n, d, e, p, l, mode, V, F, cp, dp);
        double vs = 0.0, fs = 0.0;
        if (tol > 0.0)
            for (size_t i = 0; i < n; i++) { vs = fmax(vs, fabs(V[i])); fs = fmax(fs, fabs(p[i]) + l[i]); }
        int flipped = 0;
        for (size_t i = 0; i < n; i++) {
            if (!(l[i] > 0.0)) { mode[i] = sgn(V[i]); continue; }
            int to = mode[i];
            if (mode[i] != 0 && mode[i] * V[i] < -tol * vs) to = 0;
            else if (mode[i] == 0 && F[i] > l[i] + tol * fs) to = -1;
            else if (mode[i] == 0 && F[i] < -l[i] - tol * fs) to = 1;
            if (to != mode[i] && (it < 3 || !flipped)) {
                mode[i] = to;
                flipped = 1;
            }
        }
        if (!flipped) return it;
    }
    return -1;
}

int chain_box_lcp(size_t n, const double *d, const double *e, const double *p, const double *l, int *mode,
                  double *V, double *F, double *work)
{
    const long budget = 8 * (long)n + 32;
    long piv = pivoting(n, d, e, p, l, mode, V, F, work, budget, 0.0);
    if (piv >= 0) return (int)piv;
    /* Stiff steps (M_hat far from diagonal dominance) can make the pivoting wander: projected
     * Gauss-Seidel (coordinate descent on the strictly convex problem min V'M V / 2 - p'V +
     * sum l |V|, convergent for M_hat positive definite) finds the modes, the pivoting polishes. */
    for (size_t i = 0; i < n; i++) V[i] = 0.0;
    for (long sweep = 0; sweep < 1000000; sweep++) {
        double dv = 0.0, vs = 0.0;
        for (size_t i = 0; i < n; i++) {
            double r = p[i];
            if (i > 0) r -= e[i - 1] * V[i - 1];
            if (i + 1 < n) r -= e[i] * V[i + 1];
            const double v = (r > l[i]) ? (r - l[i]) / d[i] : (r < -l[i]) ? (r + l[i]) / d[i] : 0.0;
            dv = fmax(dv, fabs(v - V[i]));
            vs = fmax(vs, fabs(v));
            V[i] = v;
        }
        if (dv <= 1e-15 * vs) break;
    }
    for (size_t i = 0; i < n; i++) mode[i] = sgn(V[i]);
    /* the polish accepts infeasibilities of rounding size (1e-10 of the problem's scale): on an
     * ill-conditioned M_hat they would make the exact rule cycle */
    piv = pivoting(n, d, e, p, l, mode, V, F, work, budget, 1e-10);
    return (piv >= 0) ? (int)(piv + budget) : -1;
}

/* Accept the trial for the span's blocks with end velocities V1 and friction forces F1 (constant
 * over the step for the moving blocks with friction): X, V, A, F, hA, the energy accounts (whole
 * chain only); not the time. */
static void finish(chain_model *M, chain_state *s, const span *G, const double *V1, const double *F1)
{
    M->jerk_valid = 0;
    const double c1 = M->kin.c1, cV = M->kin.corr_V, g1 = M->g1, hh = M->kin.h;
    if (M->energy && G->a == 0 && G->b == M->n) {
        const size_t n = M->n;
        double cw0, sw0, W = 0.0, Wf = 0.0;
        phase_of(M, s, s->t, &cw0, &sw0);
        for (size_t i = 0; i < n; i++) {
            const double X1 = M->xp[i] + cV * V1[i];
            W += 0.5 * hh * ((P_at(M, i, cw0, sw0) + M->u[i]) * s->V[i] +
                             (P_at(M, i, M->cw1, M->sw1) + M->u[i]) * V1[i]);
            Wf += F1[i] * (X1 - s->X[i]);
        }
        s->W_applied += W;
        s->W_friction += Wf;
        s->D_damping += 0.5 * hh * (damping_power(M, s->V) + damping_power(M, V1));
    }
    for (size_t i = G->a; i < G->b; i++) {
        s->X[i] = M->xp[i] + cV * V1[i];
        s->A[i] = (V1[i] - s->V[i]) * c1 - g1 * M->A0p[i];
        s->V[i] = V1[i];
        s->F[i] = F1[i];
        s->hA[i] = hh;
    }
}

/* ---- the located scheme ---------------------------------------------------------------------- */

/* Row i of the kept factorisation, refreshed when its held state differs from the one it was made
 * for (fh) or a free row follows a refreshed one (refac); cprev: row i - 1's cp. A held row has
 * cp = 0; a free one inv = 1 / den, cp = e inv (+0 on the last row, e[n - 1] = +0, as solve_rows'
 * 0.0). Returns whether the row was refreshed (the next row's refac). */
static HOT_INLINE int refactor_row(fast_row *R, size_t i, int hold, double cprev, int refac)
{
    if (R[i].fh == 1 + hold && !(refac && !hold)) return 0;
    R[i].fh = 1 + hold;
    if (hold) {
        R[i].cp = 0.0;
    } else {
        const double den = (i > 0) ? R[i].d - R[i - 1].e * cprev : R[i].d - 0.0 * cprev;
        R[i].inv = 1.0 / den;
        R[i].cp = R[i].e * R[i].inv;
    }
    return 1;
}

/* solve_rows on the whole chain with a whole grid step's M_hat (dF, eF), by its factorisation kept
 * for the held pattern (M->rows; see step_fast): the same operations, so the same bits. */
static void solve_kept(chain_model *M)
{
    const size_t n = M->n;
    const double *restrict p = M->ph, *restrict l = M->l;
    const int *restrict mode = M->st;
    fast_row *restrict R = M->rows;
    double *restrict dp = M->dp, *restrict V = M->Vt, *restrict F = M->Ft;
    double cprev = 0.0, dprev = 0.0;
    int refac = 0;
    for (size_t i = 0; i < n; i++) {
        const int hold = (mode[i] == 0 && l[i] > 0.0);
        refac = refactor_row(R, i, hold, cprev, refac);
        double dpi = 0.0;
        if (!hold) {
            const double lo_e = (i > 0) ? R[i - 1].e : 0.0;
            const double rhs = p[i] - ((l[i] > 0.0) ? mode[i] * l[i] : 0.0);
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
            double f = -p[i];
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
    solve_rows(lo, hi, G->has[0], G->gV[0], G->has[1], G->gV[1], M->cd, M->ce, M->ph, M->l, M->st, M->Vt, M->Ft,
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
    phase_of(M, s, s->t + x, &cw, &sw);
    trial(M, s, c->G, x, cw, sw);
    solve_modes(M, c->G);
    double g = INFINITY;
    for (size_t k = 0; k < M->ncand; k++) g = fmin(g, switch_margin(M, s, M->cand[k]));
    return g;
}

/* After a switch: the consistent restart of the span's new mode set (physical accelerations,
 * hA = 0) and the friction forces of its stuck blocks. */
static void restart(chain_model *M, chain_state *s, const span *G)
{
    M->jerk_valid = 0;
    physical_accel(M, s, G, s->A);
    for (size_t i = G->a; i < G->b; i++) {
        s->hA[i] = 0.0;
        if (!has_friction(M, i)) continue;
        if (s->mode[i] == 0) s->F[i] = -fmax(-M->Fb[i], fmin(M->Fb[i], M->S[i]));
        else s->F[i] = -s->mode[i] * M->mukN[i];
    }
}

static void report(chain_model *M, chain_state *s, size_t i, int from, chain_switch_fn fn, void *ctx)
{
    s->switches++;
    M->switched = 1;
    if (fn) fn(ctx, s->t, i, s->X[i], from, s->mode[i]);
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
        if (!immediate && switch_margin(M, s, i) > 0.0) continue;
        M->cand[nsw++] = i;
        if (s->mode[i] != 0) {
            /* a slide from rest that cannot move in double precision: held to the step's end */
            if (immediate && s->V[i] == 0.0) M->frozen[i] = M->any_frozen = 1;
            s->V[i] = 0.0;
        }
    }
    M->ncand = nsw;
    net_forces(M, s, G, M->S);
    for (size_t k = 0; k < nsw; k++) {
        const size_t i = M->cand[k];
        const int from = s->mode[i];
        const double S = M->S[i];
        if (M->frozen[i]) s->mode[i] = 0;
        else if (from != 0) s->mode[i] = (fabs(S) <= M->Fb[i]) ? 0 : sgn(S);
        else s->mode[i] = (sgn(S) != 0) ? sgn(S) : -sgn(M->Ft[i]);
        if (s->mode[i] == 0 && from != 0) s->t_stick[i] = s->t;
        if (s->mode[i] != from) report(M, s, i, from, fn, ctx);
    }
    restart(M, s, G);
    /* the consistent acceleration of a slide from rest never points against it (friction.h) */
    for (size_t k = 0; k < nsw; k++) {
        const size_t i = M->cand[k];
        const int dir = s->mode[i];
        if (dir != 0) s->A[i] = dir * fmax(fmax(dir * M->S[i], M->Fb[i]) - M->mukN[i], 0.0) / M->m[i];
    }
}

/* The next breakaway of block i, stuck at X with its neighbours where they are, by the oscillator's
 * closed form (friction.h): its excitation as a single block's, its static offset u - (K x)_i. */
static double block_breakaway(const chain_model *M, const chain_state *s, size_t i, int *dir)
{
    dfo_model bm;
    memset(&bm, 0, sizeof bm);
    bm.p.omega = M->omega;
    bm.p.P0 = M->P0[i];
    bm.p.phi = M->phi[i];
    bm.P_amp = fabs(M->P0[i]);
    bm.P_phase = M->phi[i] + (M->P0[i] < 0.0 ? DFO_PI : 0.0);
    dfo_loads L;
    L.F_ext = M->u[i];
    L.N = 0.0;
    L.muk_N = M->mukN[i];
    L.Fb = M->Fb[i];
    return dfo_next_breakaway(&bm, &L, M->u[i] - Kx(M, s->X, i), s->t_stick[i], dir);
}

/* Block i stuck with X frozen and every neighbour at rest: its static force is its excitation
 * plus a constant, and its next breakaway after the stick phase's start is known in closed form
 * (friction.h, as the oscillator's); INFINITY when it does not apply. */
static double closed_breakaway(const chain_model *M, const chain_state *s, const span *G, size_t i, int *dir)
{
    for (int side = -1; side <= 1; side += 2) {
        if ((side < 0 && i == 0) || (side > 0 && i + 1 >= M->n)) continue;
        const size_t j = (side < 0) ? i - 1 : i + 1;
        const int inside = j >= G->a && j < G->b;
        if (!(held(M, s, j) || (inside && M->frozen[j]))) return INFINITY;
    }
    return block_breakaway(M, s, i, dir);
}

/* The located step of a span from s->t to t_end (first phase of length hh): phases in the current
 * modes, each ended at the earliest switch of a block of the span (method.md section 9). */
static void located_span(chain_model *M, chain_state *s, span *G, double t_end, double hh, chain_switch_fn fn,
                         void *ctx, int stop_at_switch)
{
    const long max_phases = 64 + 4 * (long)(G->b - G->a);
    for (long phase = 0; s->t < t_end; phase++) {
        if (phase >= max_phases) { M->err = CHAIN_ERR_NO_PROGRESS; return; }
        set_ghosts(M, s, G);
        const double r = (phase == 0) ? hh : t_end - s->t;
        for (size_t i = G->a; i < G->b; i++) {
            M->st[i] = (held(M, s, i) || M->frozen[i]) ? 0 : s->mode[i];
            M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mukN[i];
        }
        double cw1, sw1;
        phase_of(M, s, t_end, &cw1, &sw1);
        trial(M, s, G, r, cw1, sw1);
        solve_modes(M, G);
        s->solves++;
        M->ncand = 0;
        for (size_t i = G->a; i < G->b; i++) {
            if (!has_friction(M, i) || M->frozen[i]) continue;
            if (switch_margin(M, s, i) <= 0.0) M->cand[M->ncand++] = i;
        }
        if (M->ncand == 0) {  /* the warm basis solves the LCP: the whole remainder in these modes */
            finish(M, s, G, M->Vt, M->Ft);
            for (size_t i = G->a; i < G->b; i++)
                if (!has_friction(M, i)) s->mode[i] = sgn(s->V[i]);
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
                phase_of(M, s, tb, &c1w, &s1w);
                trial(M, s, G, (tb == t_end) ? r : hs, c1w, s1w);
                solve_modes(M, G);
                s->solves++;
                finish(M, s, G, M->Vt, M->Ft);
            }
            s->t = tb;
            size_t nsw = 0;
            for (size_t k = 0; k < M->ncand; k++)
                if (M->S[M->cand[k]] == tb) M->cand[nsw++] = M->cand[k];
            M->ncand = nsw;
            set_ghosts(M, s, G);
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
        if (hs >= r) phase_of(M, s, t_end, &c1w, &s1w);
        else { c1w = dfo_cos(M->omega * t1 + M->phi0); s1w = dfo_sin(M->omega * t1 + M->phi0); }
        trial(M, s, G, hs, c1w, s1w);
        solve_modes(M, G);
        s->solves++;
        for (size_t k = 0; k < M->ncand; k++) {  /* a stopping block ends the sub-step at rest */
            const size_t i = M->cand[k];
            if (M->st[i] != 0 && switch_margin(M, s, i) <= 0.0) M->Vt[i] = 0.0;
        }
        finish(M, s, G, M->Vt, M->Ft);
        s->t = (hs >= r) ? t_end : fmax(t1, nextafter(ta, INFINITY));
        set_ghosts(M, s, G);
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

static void step_lcp(chain_model *M, chain_state *s, double t_end, double hh, chain_switch_fn fn, void *ctx,
                     int consistent);

/* What a grid step of the fast path reads, constant over one chain_advance call: taken out of the
 * model once per call, so that the stepping loop keeps it in registers or on its own stack. */
typedef struct {
    size_t n;
    double h, alpha, rate_max, c1, pV, pA, cV, g1;
    fast_row *rows;
    double *xp, *ph, *dp, *Vt, *Ft, *l;
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
    F->xp = M->xp; F->ph = M->ph; F->dp = M->dp; F->Vt = M->Vt; F->Ft = M->Ft;
    F->l = M->l; F->st = M->st;
}

/* The located step of a whole grid step in the current modes, in fused sweeps: the same arithmetic,
 * in the same order, as trial + solve_modes + finish (so the same bits), without their separate
 * passes, and with the factorisation of M_hat for the step's held rows kept from the last step
 * (rows: a row is refactored, by solve_rows' operations, when its own hold changed or
 * when it is free and the row above was refactored; a held row starts the elimination afresh).
 * Returns 1 when the warm basis solves the LCP: the step is taken (not the time). Returns 0, with
 * nothing done, when A must be re-based (then rebase_whole makes A0 and step_fast goes on with
 * rebased set: trial's A0p). Returns -1 when a block must switch: the state is
 * untouched and the model holds the trial and its solve in the current modes as trial +
 * solve_modes leave them (xp, ph, st, l, Vt, Ft, kin, cd, ce, A0p, cw1, sw1), for step_located to
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
    double *restrict xp = C->xp, *restrict ph = C->ph, *restrict dp = C->dp, *restrict Vt = C->Vt;
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
        ph[i] = p;
        xl = xc;
        xc = xr;
        const int hold = (mode[i] == 0 && R[i].Fb > 0.0);
        refac = refactor_row(R, i, hold, cprev, refac);
        /* solve_rows' (rhs - lo_e dprev) / den, rhs = p + the sliding force; on the first row
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
                double f = -ph[i] + R[i - 1].e * vn;
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
        double f = -ph[0];
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
        if (!(R[i].Fb > 0.0)) mode[i] = sgn(V1);
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
            /* the excitation's rate at s->t, and its phase as physical_accel reads it */
            cw = dfo_cos(M->omega * s->t + M->phi0);
            sw = dfo_sin(M->omega * s->t + M->phi0);
            phase_of(M, s, s->t, &pcw, &psw);
            have = 1;
        }
        double j = 0.0;
        if (!held(M, s, i)) {
            const double Pd = -M->Pc[i] * M->omega * sw + -M->Ps[i] * M->omega * cw;
            double cv = 0.0;
            if (M->damped) {
                /* (C a)_i with the physical accelerations of i and its neighbours (accelerations) */
                double acc[3];
                for (int k = 0; k < 3; k++) {
                    acc[k] = 0.0;
                    if ((k == 0 && i == 0) || (k == 2 && i + 1 >= n)) continue;
                    const size_t b = i + (size_t)k - 1;
                    if (held(M, s, b)) continue;
                    const double F = has_friction(M, b) ? -s->mode[b] * M->mukN[b] : 0.0;
                    acc[k] = (P_at(M, b, pcw, psw) + M->u[b] - Kx(M, s->X, b) + F - Cv(M, s->V, b)) / M->m[b];
                }
                cv = M->Cd[i] * acc[1];
                if (i > 0) cv += M->Co[i - 1] * acc[0];
                if (i + 1 < n) cv += M->Co[i] * acc[2];
            }
            j = (Pd - Kx(M, s->V, i) - cv) / M->m[i];
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
 * step_fast's result (0, -1) for step_located. No calls: the loop keeps its data in registers. */
static HOT_INLINE int fast_run(chain_model *M, const fast_ctx *C, chain_state *s, double t_target, double *g_prev,
                               double *t_end, double *cw1, double *sw1)
{
    const double h = C->h, t0 = s->t0, rc = M->rot_c, rs = M->rot_s;
    const int stuck_ok = M->stuck_ok;
    if (M->any_frozen) return 1;
    for (;;) {
        const long long g = s->n_grid + 1;
        if ((stuck_ok && s->mode[0] == 0) || g % EXC_ANCHOR == 0 || s->exc_n != g - 1) return 1;
        const double grid = t0 + (double)g * h;
        if (!(grid <= t_target) || !(grid > s->t)) return 1;
        /* chain_advance's step: grid_phase with its cache at g - 1 (one rotation) */
        s->n_grid = g;
        *g_prev = grid;
        const double c = s->exc_c, sn = s->exc_s;
        const double cn = c * rc - sn * rs, sw = sn * rc + c * rs;
        s->exc_n = g;
        s->exc_c = cn;
        s->exc_s = sw;
        const double cw = clamp1(cn), swc = clamp1(sw);
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

/* One located step. The whole chain is solved in the current modes; when blocks must switch, a long
 * chain (more than 2 w + 3 blocks, w the span beyond which a block's influence inside one step is
 * below rounding: M_hat's inverse decays like rho^distance) takes the step in those modes outside
 * clusters of w blocks either side of the switching ones, and each cluster takes it again on its
 * own, switches placed inside, with its outside neighbours as interpolated ghosts. A short chain,
 * stop_at_switch and the energy accounts take the located step on the whole chain. fast: step_fast's
 * result for this step (-1: it has solved the step in the current modes), or 0. */
static COLD_CALL void step_located(chain_model *M, chain_state *s, double t_end, double hh, double cw1, double sw1,
                                   int fast, chain_switch_fn fn, void *ctx, int stop_at_switch)
{
    const size_t n = M->n;
    /* a stiff step (several periods of the fastest mode) cannot place a switch: restarts with the
     * physical acceleration would feed the unresolved mode; the consistent test, which is stable,
     * takes it (as in the oscillator) */
    if (M->rate_max * hh > STIFF_STEP) {
        step_lcp(M, s, t_end, hh, fn, ctx, 1);
        return;
    }
    span G0 = whole(M, s);
    if (fast == 0) {  /* else step_fast has solved the trial in the current modes */
        if (M->any_frozen) {
            for (size_t i = 0; i < n; i++) M->frozen[i] = 0;
            M->any_frozen = 0;
        }
        for (size_t i = 0; i < n; i++) {
            M->st[i] = held(M, s, i) ? 0 : s->mode[i];
            M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mukN[i];
        }
        trial(M, s, &G0, hh, cw1, sw1);
        solve_modes(M, &G0);
        s->solves++;
    }
    M->ncand = 0;
    for (size_t i = 0; i < n; i++)
        if (has_friction(M, i) && switch_margin(M, s, i) <= 0.0) M->cand[M->ncand++] = i;
    if (M->ncand == 0) {  /* the warm basis solves the LCP: O(n), no pivot */
        finish(M, s, &G0, M->Vt, M->Ft);
        for (size_t i = 0; i < n; i++)
            if (!has_friction(M, i)) s->mode[i] = sgn(s->V[i]);
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
    finish(M, s, &G0, M->Vt, M->Ft);
    for (size_t i = 0; i < n; i++)
        if (!has_friction(M, i)) s->mode[i] = sgn(s->V[i]);
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

/* ---- the paper and consistent schemes -------------------------------------------------------- */

static COLD_CALL void step_lcp(chain_model *M, chain_state *s, double t_end, double hh, chain_switch_fn fn, void *ctx,
                               int consistent)
{
    const size_t n = M->n;
    double cw1, sw1;
    phase_of(M, s, t_end, &cw1, &sw1);
    span G0 = whole(M, s);
    trial(M, s, &G0, hh, cw1, sw1);
    /* the LCP with the coefficient of each block's mode before the step, from that basis */
    for (size_t i = 0; i < n; i++) {
        M->st[i] = s->mode[i];
        M->l[i] = !has_friction(M, i) ? 0.0 : (s->mode[i] == 0) ? M->Fb[i] : M->mukN[i];
    }
    int piv = chain_box_lcp(n, M->cd, M->ce, M->ph, M->l, M->st, M->Vt, M->Ft, M->box);
    s->solves++;
    if (piv < 0) { M->err = CHAIN_ERR_LCP; return; }
    int total = piv, update = 0;
    if (!consistent) {
        /* paper: one update of the coefficients from the result, and a second solve */
        for (size_t i = 0; i < n; i++) {
            if (!has_friction(M, i)) continue;
            const double l1 = (M->st[i] == 0) ? M->Fb[i] : M->mukN[i];
            if (l1 != M->l[i]) { M->l[i] = l1; update = 1; }
        }
        if (update) {
            piv = chain_box_lcp(n, M->cd, M->ce, M->ph, M->l, M->st, M->Vt, M->Ft, M->box);
            s->solves++;
            if (piv < 0) { M->err = CHAIN_ERR_LCP; return; }
            total += piv;
        }
    } else {
        /* consistent (method.md section 4): a stuck block that breaks loose slides with mu_k; a
         * sliding block that fails to keep sliding sticks if the static force at its predicted
         * rest position is within the breakaway limit, else slides the way of that force with mu_k
         * (and sticks if its velocity then comes out the wrong way) */
        for (size_t i = 0; i < n; i++) {
            if (!has_friction(M, i)) continue;
            const int from = s->mode[i];
            if (from == 0 && M->st[i] != 0) { M->l[i] = M->mukN[i]; update = 1; }
            if (from != 0 && M->st[i] != from) {
                const double S = P_at(M, i, cw1, sw1) + M->u[i] - Kx(M, M->xp, i);
                M->st[i] = (fabs(S) <= M->Fb[i]) ? 0 : sgn(S);
                M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mukN[i];
                M->frozen[i] = M->any_frozen = 1; /* judged: no more pivots on it */
                update = 1;
            } else {
                M->frozen[i] = 0;
            }
        }
        for (int pass = 0; update && pass <= (int)n; pass++) {
            solve_held(n, M->cd, M->ce, M->ph, M->l, M->st, M->Vt, M->Ft, M->cp, M->dp);
            s->solves++;
            update = 0;
            for (size_t i = 0; i < n; i++) {
                if (!has_friction(M, i) || M->st[i] == 0 || M->st[i] * M->Vt[i] > 0.0) continue;
                if (s->mode[i] == 0 && !M->frozen[i]) continue;
                M->st[i] = 0;
                M->l[i] = M->Fb[i];
                update = 1;
            }
        }
        for (size_t i = 0; i < n; i++) {
            /* a stuck block's held force is the static force, clamped to the limit */
            if (has_friction(M, i) && M->st[i] == 0) M->Ft[i] = fmax(-M->Fb[i], fmin(M->Fb[i], M->Ft[i]));
            if (!has_friction(M, i)) M->st[i] = sgn(M->Vt[i]);
        }
        total += update;
    }
    if (total > 0) s->pivot_steps++;
    finish(M, s, &G0, M->Vt, M->Ft);
    s->t = t_end;
    for (size_t i = 0; i < n; i++) {
        const int from = s->mode[i];
        s->mode[i] = M->st[i];
        if (s->mode[i] == 0 && from != 0) s->t_stick[i] = s->t;
        if (consistent && s->mode[i] == 0 && has_friction(M, i)) s->A[i] = 0.0;
        if (has_friction(M, i) && s->mode[i] != from) report(M, s, i, from, fn, ctx);
    }
}

/* ---- public stepping ------------------------------------------------------------------------- */

void chain_start(chain_model *M, const chain_inputs *in, double t0, chain_state *s)
{
    const size_t n = M->n;
    loads_init(M, in);
    s->t0 = s->t = t0;
    s->n_grid = 0;
    s->exc_n = -1;
    s->exc_c = s->exc_s = 0.0;
    s->W_applied = s->W_friction = s->D_damping = 0.0;
    s->steps = s->pivot_steps = s->switches = s->solves = 0;
    for (size_t i = 0; i < n; i++) {
        s->X[i] = M->x0[i];
        s->V[i] = M->v0[i];
        s->hA[i] = 0.0;
        s->t_stick[i] = t0;
    }
    const span G = whole(M, s);
    net_forces(M, s, &G, M->S);
    for (size_t i = 0; i < n; i++) {
        if (has_friction(M, i) && s->V[i] == 0.0) s->mode[i] = (fabs(M->S[i]) <= M->Fb[i]) ? 0 : sgn(M->S[i]);
        else s->mode[i] = sgn(s->V[i]);
    }
    restart(M, s, &G);
    for (size_t i = 0; i < n; i++) {
        const int dir = s->mode[i];
        if (!has_friction(M, i)) s->F[i] = 0.0;
        else if (dir != 0 && s->V[i] == 0.0)
            s->A[i] = dir * fmax(fmax(dir * M->S[i], M->Fb[i]) - M->mukN[i], 0.0) / M->m[i];
    }
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
        tb = fmin(tb, block_breakaway(M, s, i, &dir) - 1e-6 * h);
    }
    if (!(tb > s->t)) return s->n_grid;
    long long m = (long long)floor((tb - s->t0) / h);
    while (m > s->n_grid && !(s->t0 + (double)m * h < tb)) m--;
    while (s->t0 + (double)(m + 1) * h < tb) m++;
    return (m > s->n_grid) ? m : s->n_grid;
}

/* Block i's external force and kinetic friction magnitude under the inputs in. */
static void block_loads(const chain_model *M, const chain_inputs *in, size_t i, double *u, double *mukN)
{
    const double N = (in && in->N_ext) ? fmax(M->N[i] + in->N_ext[i], 0.0) : M->N[i];
    *u = (in && in->F_ext) ? in->F_ext[i] : 0.0;
    *mukN = M->mu_k[i] * N;
}

void chain_new_inputs(const chain_model *M, const chain_inputs *old_in, const chain_inputs *new_in, chain_state *s)
{
    for (size_t i = 0; i < M->n; i++) {
        if (s->mode[i] == 0) continue;
        double u0, f0, u1, f1;
        block_loads(M, old_in, i, &u0, &f0);
        block_loads(M, new_in, i, &u1, &f1);
        const double dF = (u1 - u0) - s->mode[i] * (f1 - f0);
        if (dF == 0.0) continue;
        s->A[i] += dF / M->m[i];
        s->F[i] = -s->mode[i] * f1;
    }
}

/* The consistent scheme: a stuck block at rest holds its static force, clamped to the limit,
 * evaluated where a call ends (as the oscillator's dfo_advance); the LCP's force of the step in
 * which it stopped would still carry the deceleration. */
static void rest_forces(chain_model *M, chain_state *s)
{
    if (M->scheme != DFO_SCHEME_CONSISTENT) return;
    double cw, sw;
    phase_of(M, s, s->t, &cw, &sw);
    for (size_t i = 0; i < M->n; i++) {
        if (!held(M, s, i)) continue;
        const double S = P_at(M, i, cw, sw) + M->u[i] - Kx(M, s->X, i) - Cv(M, s->V, i);
        s->F[i] = -fmax(-M->Fb[i], fmin(M->Fb[i], S));
    }
}

chain_status chain_advance(chain_model *M, const chain_inputs *in, chain_state *s, double t_target,
                           int stop_at_switch, chain_switch_fn on_switch, void *ctx)
{
    const double h = M->h;
    loads_init(M, in);
    M->err = CHAIN_OK;
    M->switched = 0;
    M->jerk_valid = 0;
    /* a requested time within SNAP_REL_H h of a grid point is that grid point */
    const double r = (t_target - s->t0) / h;
    if (r > -0.5 && r < 0x1p52) {
        const long long g = (long long)floor(r + 0.5);
        const double tg = s->t0 + (double)g * h;
        if (g >= s->n_grid && tg >= s->t && fabs(t_target - tg) <= SNAP_REL_H * h) t_target = tg;
    }
    /* whole grid steps of the located scheme try the fast path first (step_fast) */
    const int fast_grid = M->scheme == DFO_SCHEME_LOCATED && !(M->rate_max * h > STIFF_STEP) && !M->energy;
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
            phase_of(M, s, t_end, &cw1, &sw1);
        }
        if (!(t_end > s->t)) return CHAIN_ERR_RESOLUTION;
        double hh = h;
        if (!(from_grid && t_end == grid)) hh = t_end - s->t;
        s->steps++;
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
            step_located(M, s, t_end, hh, cw1, sw1, fast, on_switch, ctx, stop_at_switch);
        } else {
            step_lcp(M, s, t_end, hh, on_switch, ctx, M->scheme == DFO_SCHEME_CONSISTENT);
        }
        if (M->err != CHAIN_OK) return M->err;
        if (stop_at_switch && M->switched) {
            /* the grid index stays that of the last grid point at or before the time reached */
            if (s->t < t_end && t_end == grid) s->n_grid--;
            rest_forces(M, s);
            return CHAIN_SWITCHED;  /* (g_prev is not used again) */
        }
    }
    rest_forces(M, s);
    for (size_t i = 0; i < M->n; i++)
        if (!(fabs(s->X[i]) <= DBL_MAX && fabs(s->V[i]) <= DBL_MAX && fabs(s->A[i]) <= DBL_MAX))
            return CHAIN_ERR_NONFINITE;
    return CHAIN_OK;
}

void chain_step_problem(chain_model *M, const chain_inputs *in, const chain_state *s, double h,
                        double *d, double *e, double *p, double *l)
{
    loads_init(M, in);
    M->jerk_valid = 0;
    span G = whole(M, s);
    trial(M, s, &G, h, dfo_cos(M->omega * (s->t + h) + M->phi0), dfo_sin(M->omega * (s->t + h) + M->phi0));
    for (size_t i = 0; i < M->n; i++) {
        d[i] = M->cd[i];
        if (i + 1 < M->n) e[i] = M->ce[i];
        p[i] = M->ph[i];
        l[i] = (s->mode[i] == 0) ? M->Fb[i] : M->mukN[i];
    }
}

const char *chain_status_text(chain_status st)
{
    switch (st) {
    case CHAIN_OK: return "ok";
    case CHAIN_ERR_LCP: return "the chain's friction LCP could not be solved (pivot budget)";
    case CHAIN_ERR_NO_PROGRESS: return "too many stick/slip switches inside one internal step";
    case CHAIN_ERR_NONFINITE: return "the state became non-finite (overflow)";
    case CHAIN_ERR_RESOLUTION: return "the internal step h is below the time resolution at this time";
    case CHAIN_SWITCHED: return "stopped at a switch";
    }
    return "unknown status";
}

/* ---- state storage without a model (FMU states of the chain FMU) ---------------------------- */

int chain_state_alloc(const chain_alloc *al, size_t n, chain_state *s)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    double *b = dalloc(al, 6 * n);
    int *mode = (int *)al->allocate(al->env, n, sizeof(int));
    if (!b || !mode) {
        if (b) al->release(al->env, b);
        if (mode) al->release(al->env, mode);
        return 0;
    }
    s->X = b;
    s->V = b + n;
    s->A = b + 2 * n;
    s->F = b + 3 * n;
    s->hA = b + 4 * n;
    s->t_stick = b + 5 * n;
    s->mode = mode;
    s->exc_n = -1;
    return 1;
}

void chain_state_release(const chain_alloc *al, chain_state *s)
{
    if (s->X) al->release(al->env, s->X);
    if (s->mode) al->release(al->env, s->mode);
    s->X = s->V = s->A = s->F = s->hA = s->t_stick = NULL;
    s->mode = NULL;
}
