/* The engine's private header: its constants and the engine object (setup, factor-slot caches and
 * workspace), shared by engine.c (set-up, memory, the state's storage) and engine_step.h (the
 * schemes, a template over the model's operators; engine_generic.c's instance of it). Not for models: they use engine.h, or include
 * engine_step.h to specialise the schemes by their own inline operators. */
#ifndef DFO_ENGINE_PRIVATE_H
#define DFO_ENGINE_PRIVATE_H

#include "engine.h"

#include "dmath.h"
#include "excitation.h"
#include "lcp.h"
#include "roots.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <stdlib.h>

#define MAX_PHASES_BASE 64       /* switches one internal step may hold: 64 + 4 nc */
#define START_REST_EPS 64.0     /* a start's slip within this many ulps of its terms: at rest */
#define STIFF_STEP 10.0          /* rate_max h above which a step does not resolve the motion */
#define PLACE_NUDGES 12          /* a placed breakaway: ulps (doubling) to a holding force at its limit */
#define HALVINGS 60              /* search for a resolvable sub-step before the first switch */
#define LEMKE_PIVOTS_PER_N 8     /* Lemke's pivot budget: 8 (2 nc) + 16 */
#define ACTIVE_SET_ROUNDS 4      /* the active-set fallback: rounds per contact */
#define NEWTON_ITERS 60          /* Stribeck's Newton iteration */
#define DEPENDENT_REL 1e-13      /* a Cholesky pivot below this share of its diagonal: a dependent row */

/* A release of the rest rule's round: the contact and its excess over its limit */
typedef struct {
    double excess;
    size_t j;
} eng_release;

/* A held set of the tangent's constrained solves (engine_tangent.h's tan_prep) */
typedef struct {
    int slot;
    size_t m;
    int *sel, *dep;         /* nc */
    double *D, *L;          /* nc x nc */
    const double **col;     /* nc */
} tan_set;

struct eng {
    eng_setup S;
    eng_alloc al;
    double g, b, g1;             /* Newmark's gamma, beta, (1 - gamma) / gamma */
    double slot_c[ENG_NSLOTS][3];
    int slot_ok[ENG_NSLOTS];
    int any_law;                 /* some contact has the Stribeck law */
    double *mu_b;                /* nc: breakaway coefficients max(mu_s, mu_k) */
    /* loads of the current inputs at the current time (loads_at) */
    double *u;                   /* n: external force */
    double *Nn, *mukN, *Fb, *mlN;/* nc: normal force, kinetic magnitude, breakaway limit, the located
                                  * LCP's sliding limit (Stribeck: min(mu_s, mu_k) N) */
    const double *vb;            /* nc: belts of the current call (the inputs' or zeros) */
    const eng_inputs *loads_for; /* the held inputs the loads above are of (NULL: none; loads_at) */
    int all_friction;            /* every contact has friction under these loads (Fb > 0: no mode follows a slip) */
    dfo_bossak_kin kin_grid;     /* the kinematics of a grid step h */
    double *zero_nc;
    /* per-DOF workspace */
    double *A0, *xp, *ph, *V1, *r, *y, *y2, *X0, *V0, *acc, *jk; /* (X0, V0: an observed phase's start) */
    double *ew;                  /* 3 n: the energy accounts' work (account; NULL without them) */
    int jk_ok;                   /* jk holds the jerks of the current phase's start (begin_phase clears it) */
    int *rpin;                   /* n: the pins (needs_rebase's) of the current phase's start, where rpin_ok */
    int rpin_ok;                 /* (rebase sets it, with held inputs; cleared with jk_ok) */
    int held_ready;              /* xp, ph, V1, f hold the model's declined fused step from the state as it is
                                  * (held_steps, for held_step's next call; eng_advance clears it) */
    int fused_ready;             /* xp, ph, V1, f, A0, lim hold fused_steps' declined located grid step from the
                                  * state as it is (a contact switches in it: step_located's phase 0 takes it
                                  * as its trial; eng_advance clears it) */
    double *rb;                  /* n: the right-hand side of a basis solve (p_hat + the sliding forces) */
    /* per-contact workspace */
    double *lim, *f, *f2;
    int *st, *cand, *held, *st2, *mode0, *frozen, *tmode;
    double *hlim, *hf;           /* nc: held_solve's limits and forces */
    int any_jenk;                /* some contact is a Jenkins element (S.k_t) */
    double *vbj, *comp;          /* nc: a Jenkins trial's shifted targets and compliances (solve_trial) */
    int *jstop;                  /* nc: a sliding slider that stops at the located sub-step's end */
    double *jf0;                 /* nc: a stuck slider's force at the located phase's start, clamped to
                                  * its limit (jenk_phase_forces) */
    double *tbk;                 /* nc: the candidates' closed-form breakaways (eng_sparse.contact_breakaway) */
    int *hmode;                  /* nc: held_solve's modes */
    int *pin;                    /* n: the DOFs a held contact pins alone (trial_step) */
    int pin_all;                 /* every DOF is some contact's only one (w_j = e_i): held, they pin the
                                  * whole structure (eng_pin_all) */
    int rest_apart;              /* the contacts' holding forces independent of one another's modes
                                  * (eng_setup.mass_diagonal, rows on distinct DOFs: eng_rest_apart) */
    eng_release *rel;            /* nc: the rest rule's releases of one round, in its order */
    /* the located map's tangent (eng_setup.tangent; engine_tangent.h), NULL without: the next state's
     * columns (tg2, nz x L), the derivative in hh (th, L), the columns' d hs (tdh, nz), forces' (tdf,
     * nc), the phase start's jerks' (tjk, nz x n; tjk_ok), n-vectors (tw1 .. tw5, tMV, tKV, trate,
     * trate2), the held sets (tset: 0 the trial's, 1 the mass slot's), their solves' (trhs, tsol, tfh,
     * ttgt, tcomp: nc; theld: nc), the re-based DOFs (trb, n; tany_rb) */
    double *tg2, *th, *tdh, *tdf, *tjk, *tw1, *tw2, *tw3, *tw4, *tw5, *tMV, *tKV, *trate, *trate2;
    double *trhs, *tsol, *tfh, *ttgt, *tcomp;
    int *theld, *trb;
    int tjk_ok, tany_rb;
    tan_set tset[2];
    double rot_c, rot_s;         /* cos, sin of omega h: the excitation phase's advance per grid step */
    double trig_tc, trig_c, trig_ts, trig_s; /* cos and sin of omega t + phi0 at the last t each was evaluated
                                  * for (trig_at; NaN: none) */
    /* dense: the columns A_slot^-1 w_j of each slot (ENG_NSLOTS x nc x n), solved on first use after
     * the slot's factorisation (cok: solved), the selected ones' pointers (colp), D (nc x nc),
     * Cholesky, Lemke's 2 nc problem */
    double *ccol;
    int *cok;
    const double **colp;
    double *D, *Lc, *rhs, *sol, *Dinv, *lM, *lq, *lz, *lw;
    int *zb, *guess, *sel;
    /* the grid slot's D^-1 (nc x nc; the Lemke path's, a slot factored once a run) and its key: the
     * set (gd_sel, gd_m), the compliances (gd_cv, gd_comp: some), D singular (gd_sing); valid while
     * gd_ok (cleared where the slot is refactored) */
    double *gDinv, *gd_cv;
    int *gd_sel;
    size_t gd_m;
    int gd_comp, gd_sing, gd_ok;
    lcp_workspace *ws;           /* Lemke's, for 2 nc unknowns (NULL without contacts) */
    /* Stribeck's Newton */
    double *Jn, *res;
    /* the located trials' store (trial_margin, trial_again): a trial's xp, V1, A0, ph (n) and f (nc),
     * exchanged with those above */
    double *sX, *sV, *sA, *shA, *sF;
    int *smode;
    /* spans (eng_sparse.span; the located scheme's local switch placement): the sub-engine that steps
     * one span at a time (its S.n, S.nc and arrays set per span), its state, the labels, the local
     * numbering (ldof, lgh: DOFs and ghost flags; lct: contacts; gmap: global DOF -> local), the
     * span's gathered data and inputs, and the whole step's start state (ps) */
    struct eng *sub;
    eng_sparse sub_sparse;       /* the sub-engine's sparse operators: held_basis, no spans */
    eng_state ss;
    int *dlab, *clab, *lgh;
    size_t *ldof, *lct, *lidx;
    size_t lnnz;                 /* the longest contact row: lidx, lw hold lnnz entries per contact */
    long *gmap;
    size_t *drng, *crng;         /* per span k: [drng[2k], drng[2k + 1]) the DOF indices holding its labels,
                                  * crng likewise the contacts' (eng_sparse.span's) */
    eng_row *lrows;
    double *lrw, *lN, *lmus, *lmuk, *lPc, *lPs, *lF, *lNe, *lvb;
    dfo_friction_law *llaw;
    eng_state ps;                /* the whole step's start (its arrays only) */
    /* a sub-engine's ghosts (ghost: n flags, NULL in the whole structure's engine; gidx: the ngh
     * ghosts' indices, gve: their velocities at a trial's end): their states at the step's start (gt0)
     * and end (length gH), interpolated */
    int *ghost;
    size_t *gidx, ngh;
    double *gve;
    double gt0, gH;
    double *gX0, *gV0, *gX1, *gV1;
};

/* Whether every DOF of E's structure is some contact's only DOF (w_j = e_i), E->pin as scratch. */
static inline int eng_pin_all(eng *E)
{
    const size_t n = E->S.n;
    for (size_t i = 0; i < n; i++) E->pin[i] = 0;
    for (size_t j = 0; j < E->S.nc; j++)
        if (E->S.rows[j].nnz == 1 && !(E->S.k_t && E->S.k_t[j] > 0.0)) E->pin[E->S.rows[j].idx[0]] = 1;
    int all = 1;
    for (size_t i = 0; i < n; i++) all &= E->pin[i];
    return all;
}

/* Whether E's contacts hold apart (eng_rest_apart's rule): M diagonal to the bit and no two contact
 * rows on one DOF, E->pin as scratch. */
static inline int eng_rest_apart(eng *E)
{
    if (!E->S.mass_diagonal) return 0;
    const size_t n = E->S.n;
    for (size_t i = 0; i < n; i++) E->pin[i] = 0;
    for (size_t j = 0; j < E->S.nc; j++) {
        const eng_row *w = &E->S.rows[j];
        for (size_t k = 0; k < w->nnz; k++) {
            if (E->pin[w->idx[k]]) return 0;
            E->pin[w->idx[k]] = 1;
        }
    }
    return 1;
}

#endif
