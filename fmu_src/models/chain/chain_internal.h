/* The chain's private header: the model struct, the span a step is taken on, and the small
 * functions every part of the chain reads (inline: the stepping loops keep them in registers).
 * chain.h is the public API; the implementation is split by concern:
 *
 *   chain_setup.c    parameters, chain_create (the derived constants, the O(n) workspace),
 *                    shortest period, state storage, energy, status texts
 *   chain_forces.c   the loads of the inputs, the forces and accelerations of a state, one trial
 *                    step (trial: M_hat, the re-based A0, p_hat) and its acceptance (finish), the
 *                    consistent restart after a switch, input changes, the closed-form breakaway
 *   chain_located.c  the located scheme: the basis solve (kept factorisation or lcp_box_basis), the
 *                    switch margins, root finding, switches, spans and clusters (chain_step_located)
 *   chain_paper.c    the paper and consistent schemes: the box LCP (numerics/lcp.h) and the
 *                    coefficient update (chain_step_lcp)
 *   chain_advance.c  chain_start and chain_advance: the grid, the fast path of whole grid steps
 *                    (step_fast, fast_run: inlined into the loop), the stuck fast path
 *
 * Every array is through the caller's allocation callbacks; no global state. Plain C, no FMI types. */
#ifndef DFO_CHAIN_INTERNAL_H
#define DFO_CHAIN_INTERNAL_H

#include "chain.h"

#include "bossak.h"
#include "dmath.h"
#include "excitation.h"
#include "friction.h"
#include "lcp.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define SNAP_REL_H 1e-7         /* a requested time this close (in h) to a grid point is that point */
#define HALVINGS 60             /* search for a sub-step before the first switch */
#define STIFF_STEP 10.0         /* rate_max h above which a step does not resolve the motion */

/* The fast path of a grid step is inlined into the stepping loop (as the oscillator's step); the
 * rare paths stay out of it. */
#if defined(__GNUC__)
#define HOT_INLINE inline __attribute__((always_inline))
#define COLD_CALL __attribute__((noinline))
#else
#define HOT_INLINE inline
#define COLD_CALL
#endif

/* A block's data for the fused grid step (step_fast, solve_kept), together in memory. */
typedef struct {
    double Pc, Ps;   /* copies of chain_model's Pc[i], Ps[i] (excitation) */
    double u;        /* copy of u[i]: the external force (chain_loads_init) */
    double am, am1;  /* copies of am[i], am1[i] */
    double Kd, Ko;   /* copies of Kd[i], Ko[i] (stiffness) */
    double d, e;     /* copies of dF[i], eF[i]: M_hat of a whole grid step */
    double Fb, mukN; /* copies of Fb[i], mukN[i] (chain_loads_init) */
    /* the factorisation of that M_hat with the held rows replaced by V_i = 0 (Thomas: cp = e / den
     * and inv = 1 / den), kept for the held pattern fh */
    double cp, inv;
    int fh;          /* the row's factor is for: 0 nothing yet, 1 a free row, 2 a held row */
    int pad;         /* (unused: the struct's size a multiple of 8) */
} fast_row;

struct chain_model {
    chain_alloc al;             /* the caller's allocation callbacks (every array below) */
    size_t n;                   /* number of blocks */
    double k_end, c_end;        /* spring and damper from the last block to the right wall */
    double omega, h, alpha;     /* excitation frequency, internal step, Bossak parameter */
    double gamma, beta;         /* Newmark's coefficients of alpha (bossak.h) */
    double g1;                  /* (1 - gamma) / gamma */
    double rate_max;            /* sqrt(Gershgorin bound of M^-1 K) + that of M^-1 C + |omega| (1/s) */
    double T_min;               /* the shortest period of the dynamics (chain_shortest_period) */
    double rot_c, rot_s;        /* cos and sin of omega h: the excitation phase's advance per step */
    double phi0;                /* the phase every block shares (then Pc = P0, Ps = 0: each block's excitation
                                 * is P0 cos(omega t + phi0), evaluated as the oscillator's), else 0 */
    int scheme;                 /* dfo_scheme: DFO_SCHEME_PAPER, _CONSISTENT or _LOCATED */
    int energy;                 /* keep the energy accounts (chain_params.account_energy) */
    int damped;                 /* some damper is not 0 (else Cv is not evaluated) */
    int stuck_ok;               /* the stuck fast path may apply (stuck_until): located, no energy
                                 * accounts, a grid step resolving the motion, friction on every block */
    /* per block (length n): parameters and constants */
    double *m;                  /* masses */
    double *am, *am1;           /* alpha m, (1 - alpha) m */
    double *Pc, *Ps;            /* excitation P_i = Pc cos(omega t + phi0) - Ps sin(omega t + phi0) */
    double *P0, *phi;           /* the excitation's amplitude and phase as set */
    double *N;                  /* normal forces (without N_ext) */
    double *mu_k, *mu_b;        /* kinetic coefficient chi mu_s, breakaway coefficient max(mu_s, mu_k) */
    double *x0, *v0;            /* initial state */
    double *Kd, *Ko, *Cd, *Co;  /* K and C: diagonal, and Ko[i], Co[i] coupling i and i + 1 (0 on the last) */
    double *ks, *cs;            /* k_site, c_site: the parts of Kd[i], Cd[i] tying block i to the ground */
    double *fw;                 /* 2n: scratch of chain_advance_belt, the moving frame's F_ext and its rate,
                                 * handed on as the inputs of that call (no other function reads it) */
    int stribeck;               /* friction_law = stribeck: sliding friction N mu(|v_rel|) (law) */
    dfo_friction_law *law;      /* per block (stribeck only, else NULL) */
    double *dF, *eF;            /* M_hat of a whole grid step: diagonal, off-diagonal */
    fast_row *rows;             /* per block, for the fused grid step */
    /* per block: the loads of the current inputs (chain_loads_init) */
    double *u;                  /* external force F_ext (0 when never set) */
    double *mukN, *Fb;          /* kinetic friction mu_k N and breakaway limit mu_b N, N = max(N + N_ext, 0) */
    double *Nn;                 /* that normal force N */
    double *mlN;                /* the located LCP's sliding limit: mu_k N, or (stribeck) min(mu_s, mu_k) N,
                                 * where the LCP stops a block every speed stops it */
    /* workspace, per block */
    double *d, *e;              /* M_hat of the current trial step (when it is not a grid step) */
    double *A0;                 /* the trial's re-based A0 (when any block is re-based) */
    double *xp;                 /* the trial's predicted positions (X1 = xp + corr_V V1) */
    double *q;                  /* the trial's LCP vector q = -p_hat (lcp.h: w = M_hat V + q = F) */
    double *Vt, *Ft;            /* the trial's solution: end velocities, friction forces */
    double *cp, *dp;            /* Thomas workspace of the basis solves */
    double *S;                  /* net applied forces (chain_net_forces), or a candidate's breakaway time */
    double *l;                  /* the trial's friction limits: Fb held, mukN sliding (set with st) */
    double *sX, *sV, *sA, *sF, *shA;  /* blocks' states saved around a cluster (chain_step_located) */
    double *J;                  /* jerks at the current state (trial's re-basing), when jerk_valid */
    int jerk_valid;             /* J holds the jerks of the current state */
    int sparse_rebase;          /* chain_trial re-bases only the blocks that need it, their jerks not
                                 * kept (the one trial of a long chain's step before its clusters) */
    double *box;                /* 2n: lcp_box's work */
    int *frozen;                /* per block: held at rest to the step's end (a slide that cannot move,
                                 * or judged by the consistent scheme) */
    int *st;                    /* per block: the trial's modes (0 held, +-1 sliding) */
    int *smode;                 /* per block: modes saved with sX... */
    size_t *cand;               /* candidates: blocks whose switch margin is <= 0 (ncand of them) */
    size_t *clu;                /* 2n: clusters [clu[2j], clu[2j + 1]) around the candidates */
    size_t w;                   /* a cluster's half-width: beyond w blocks a block's influence inside
                                 * one step is below 2^-56 (chain_create) */
    /* the current trial */
    const double *cd, *ce;      /* its M_hat: dF, eF for a grid step, else d, e */
    const double *A0p;          /* its re-based A0: A0, or the state's A when nothing is re-based */
    int any_frozen;             /* frozen may hold a 1 */
    dfo_bossak_kin kin, kinF;   /* the trial's kinematics; a grid step's */
    double cw1, sw1;            /* cos, sin of omega t + phi0 at its end */
    size_t ncand;               /* number of candidates in cand */
    /* inputs with derivatives (chain_inputs): ramped says the loads follow the time (chain_loads_at),
     * rin is a copy of the inputs (their arrays the caller's, read during chain_advance only) */
    int ramped;
    chain_inputs rin;
    chain_ramp ramp;
    double t_trial;             /* the current trial's end (ramped inputs: the switch margins' time) */
    double t_step;              /* ramped inputs: the current internal step's end (its loads') */
    double t_load;              /* ramped inputs: the time of the next trial's loads (t_step, or a
                                 * switch search's sub-step end) */
    chain_status err;           /* first error of the current chain_advance */
    int switched;               /* a block switched in the current chain_advance */
};

/* A span of blocks [a, b) stepped on its own: the whole chain, or a cluster around switching
 * blocks (see chain_step_located). A cluster's outside neighbours a - 1 and b are ghosts: their motion
 * over the step, interpolated (cubic Hermite) between their states at its start and end, is
 * written into the state arrays at the current time. The belts of the call travel with it (never
 * in the model): vb, the located scheme's fixed-frame stepping on belts (the LCP on the velocity
 * relative to the belts, p_hat shifted by M_hat vb and solved for W = V - vb, a stuck block riding
 * on its belt, as the oscillator's located step), NULL without belts or in the belts' moving
 * frame; vrel, what to subtract from s->V for the speed relative to the belt (the Stribeck law):
 * vb while stepping, the state's belts outside the steps (chain_accelerations, input changes). */
typedef struct {
    size_t a, b;      /* the span's blocks */
    const double *vb, *vrel;  /* the call's belts (n each, or NULL), as above */
    int has[2];       /* ghost a - 1 (0), ghost b (1) present */
    size_t idx[2];    /* the ghosts' block indices */
    double t_start, H;  /* the step the ghosts' interpolation covers: start, length */
    double X0[2], V0[2], X1[2], V1[2];  /* the ghosts' states at its start and end */
    double gV[2];     /* the ghosts' velocities at the end of the current trial (Dirichlet rows) */
} span;

static inline int chain_sgn(double x) { return (x > 0.0) - (x < 0.0); }

/* cos and sin of omega t + phi0: from the state's grid cache when t is its grid point, else
 * evaluated */
static inline void chain_phase_of(const chain_model *M, const chain_state *s, double t, double *cw, double *sw)
{
    if (s->exc_n >= 0 && t == s->t0 + (double)s->exc_n * M->h) {
        *cw = dfo_clamp1(s->exc_c);
        *sw = dfo_clamp1(s->exc_s);
        return;
    }
    *cw = dfo_cos(M->omega * t + M->phi0);
    *sw = dfo_sin(M->omega * t + M->phi0);
}

/* block i's excitation at the phase (cw, sw) */
static inline double chain_P_at(const chain_model *M, size_t i, double cw, double sw)
{
    return M->Pc[i] * cw - M->Ps[i] * sw;
}

/* (K x)_i and (C v)_i */
static inline double chain_Kx(const chain_model *M, const double *x, size_t i)
{
    double f = M->Kd[i] * x[i];
    if (i > 0) f += M->Ko[i - 1] * x[i - 1];
    if (i + 1 < M->n) f += M->Ko[i] * x[i + 1];
    return f;
}
static inline double chain_Cv(const chain_model *M, const double *v, size_t i)
{
    if (!M->damped) return 0.0;
    double f = M->Cd[i] * v[i];
    if (i > 0) f += M->Co[i - 1] * v[i - 1];
    if (i + 1 < M->n) f += M->Co[i] * v[i + 1];
    return f;
}

static inline int chain_has_friction(const chain_model *M, size_t i) { return M->Fb[i] > 0.0; }

/* block i's belt speed in the fixed-frame stepping of span G (0 without belts) */
static inline double chain_vb(const span *G, size_t i) { return G->vb ? G->vb[i] : 0.0; }

/* Block i's speed relative to its belt vrel (NULL: the state's velocity, as while stepping in the
 * belt's frame) */
static inline double chain_rel_speed(const double *vrel, const chain_state *s, size_t i)
{
    return fabs(vrel ? s->V[i] - vrel[i] : s->V[i]);
}

/* The kinetic friction magnitude of sliding block i at the state: mu_k N, or N mu(|v_rel|) */
static inline double chain_slide_mag(const chain_model *M, const double *vrel, const chain_state *s, size_t i)
{
    if (!M->stribeck) return M->mukN[i];
    return M->Nn[i] * dfo_friction_mu(&M->law[i], chain_rel_speed(vrel, s, i));
}

/* The kinetic magnitude a slide starts with from rest (the rest rule's and breakaway's): mu_k N, or
 * N mu(0) (as the oscillator's start_loads) */
static inline double chain_start_mag(const chain_model *M, size_t i)
{
    if (!M->stribeck) return M->mukN[i];
    return M->Nn[i] * dfo_friction_mu(&M->law[i], 0.0);
}

/* held at rest in the current step: stuck (schemes whose stuck blocks rest) */
static inline int chain_held(const chain_model *M, const chain_state *s, size_t i)
{
    return s->mode[i] == 0 && chain_has_friction(M, i);
}

/* the whole chain as a span, from the state's time, with the call's belts vb and vrel (span) */
static inline span chain_whole(const chain_model *M, const chain_state *s, const double *vb, const double *vrel)
{
    span G;
    G.a = 0;
    G.b = M->n;
    G.vb = vb;
    G.vrel = vrel;
    G.has[0] = G.has[1] = 0;
    G.idx[0] = G.idx[1] = 0;
    G.t_start = s->t;
    G.H = 0.0;
    for (int k = 0; k < 2; k++) G.X0[k] = G.V0[k] = G.X1[k] = G.V1[k] = G.gV[k] = 0.0;
    return G;
}

/* A switch of block i from mode `from` (its new mode in s->mode): counted and reported. */
static inline void chain_report(chain_model *M, chain_state *s, size_t i, int from, chain_switch_fn fn, void *ctx)
{
    s->switches++;
    M->switched = 1;
    if (fn) fn(ctx, s->t, i, s->X[i], from, s->mode[i]);
}

/* Row i of the kept factorisation (fast_row), refreshed when its held state differs from the one
 * it was made for (fh) or a free row follows a refreshed one (refac); cprev: row i - 1's cp. A held
 * row has cp = 0; a free one inv = 1 / den, cp = e inv (+0 on the last row, e[n - 1] = +0, as
 * lcp_box_basis' 0.0). Returns whether the row was refreshed (the next row's refac). */
static HOT_INLINE int chain_refactor_row(fast_row *R, size_t i, int hold, double cprev, int refac)
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

/* ---- chain_forces.c ---- */
/* The loads of the inputs into u, mukN, Fb (and the rows' copies); stuck_ok; ramped off. */
void chain_loads_init(chain_model *M, const chain_inputs *in);
/* Ramped inputs (chain_advance_ramped): ramped on when ramp has a derivative, the loads at
 * ramp->t_ref, stuck_ok off. */
void chain_loads_ramped(chain_model *M, const chain_inputs *in, const chain_ramp *ramp);
/* Ramped inputs: the loads at time t (u(t), mu_k N(t), mu_b N(t)). */
COLD_CALL void chain_loads_ramp(chain_model *M, double t);
/* The loads at time t: a no-op unless the inputs are ramped. */
static inline void chain_loads_at(chain_model *M, double t)
{
    if (M->ramped) chain_loads_ramp(M, t);
}

/* Write the ghosts' state at the current time into the state arrays. */
void chain_set_ghosts(chain_model *M, chain_state *s, const span *G);
/* Net applied force on the span's blocks at the state (excitation, inputs, springs, dampers). */
void chain_net_forces(chain_model *M, const chain_state *s, const span *G, double *S);
/* Physical accelerations at the state in its modes: stuck blocks 0, the others from the equation
 * of motion. */
void chain_mode_accels(chain_model *M, const chain_state *s, const span *G, double *a);
/* The same, and the net applied forces into M->S. */
void chain_physical_accel(chain_model *M, const chain_state *s, const span *G, double *a);
/* The trial step of length hh of the span from the state (cw1, sw1: the phase at its end): M_hat
 * (cd, ce), the re-based A0 (A0p), xp and q; a ghost's xp and velocity at the end. */
void chain_trial(chain_model *M, const chain_state *s, span *G, double hh, double cw1, double sw1);
/* Accept the trial for the span's blocks with end velocities V1 and friction forces F1: X, V, A,
 * F, hA and the energy accounts (whole chain only); not the time. With belts (G->vb) V1 is the velocity
 * relative to the belts (W) and a held block rides on its belt to t1, the trial's end. */
void chain_finish(chain_model *M, chain_state *s, const span *G, const double *V1, const double *F1, double t1);
/* After a switch: the consistent restart of the span's new mode set (physical accelerations,
 * hA = 0) and the friction forces of its stuck blocks. */
void chain_restart(chain_model *M, chain_state *s, const span *G);
/* The next breakaway of block i, stuck at X with its neighbours where they are (friction.h's
 * closed form; its excitation as a single block's, its static offset u - (K x)_i). */
double chain_block_breakaway(const chain_model *M, const chain_state *s, size_t i, int *dir);

/* Ramped inputs: the rate of block i's applied force from its inputs at the state's time (vrel: the
 * belts of its relative speed, span). */
double chain_ramp_rate(const chain_model *M, const double *vrel, const chain_state *s, size_t i);

/* ---- chain_located.c ---- */
/* One located step from s->t to t_end (length hh, phase cw1, sw1 at its end); fast: step_fast's
 * result for it (-1: the trial in the current modes is solved already), or 0. */
/* vb: the fixed-frame stepping's belts (span; NULL: none). */
COLD_CALL void chain_step_located(chain_model *M, chain_state *s, const double *vb, double t_end, double hh, double cw1,
                                  double sw1, int fast, chain_switch_fn fn, void *ctx, int stop_at_switch);

/* ---- chain_paper.c ---- */
/* One step of the paper scheme (consistent = 0) or of the consistent scheme (1) to t_end. */
COLD_CALL void chain_step_lcp(chain_model *M, chain_state *s, const double *vb, double t_end, double hh,
                              chain_switch_fn fn, void *ctx, int consistent);

#endif
