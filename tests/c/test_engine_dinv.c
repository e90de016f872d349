/* The default friction solver's cache of the grid slot's D^-1 (eng_dense_friction, engine_step.h:
 * gDinv and its key gd_sel, gd_m, gd_comp, gd_cv, gd_ok). Checked by looking inside the engine: after
 * every LCP solve on the grid slot the cache holds the inverse of the Delassus matrix of exactly the
 * contacts with friction in that problem (plus its compliances), computed here from the columns
 * A^-1 w_j independently of the engine; a problem of another set (a normal load to 0), other
 * compliances or none, and the set back again, each recompute it; a refactor of the grid slot (other
 * coefficients) clears it; every solve equals the same solve by a fresh engine (no cache), bit for
 * bit. (Through the LCP alone a stale D^-1 need not show: the solver's last basis solve recomputes the
 * velocities and forces from the modes Lemke found.) */
#include "check.h"
#include "dfo_fp.h"
#include "engine_private.h"
#include "dense_model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *t_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void t_free(void *env, void *p) { (void)env; free(p); }
static const eng_alloc ALLOC = {t_alloc, t_free, NULL};

#define NDOF 3
#define NC 3

/* three DOFs, contacts on DOF 0, on DOF 1, between DOFs 0 and 2 */
static dense MODEL = {NDOF,
                      {2.0, 0.3, 0.0, 0.3, 1.0, 0.1, 0.0, 0.1, 1.5},
                      {0.2, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.3},
                      {4.0, -1.0, 0.0, -1.0, 3.0, -1.0, 0.0, -1.0, 2.0},
                      {{0.0}},
                      0};
static size_t IDX[NC][2] = {{0, 0}, {1, 1}, {0, 2}};
static double W[NC][2] = {{1.0, 0.0}, {1.0, 0.0}, {1.0, -1.0}};
static size_t NNZ[NC] = {1, 1, 2};

static eng *engine(eng_row *rows, double *Nn, double *mu)
{
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = NDOF;
    S.nc = NC;
    dense_ops(&MODEL, &S);
    for (size_t j = 0; j < NC; j++) {
        rows[j].nnz = NNZ[j];
        rows[j].idx = IDX[j];
        rows[j].w = W[j];
    }
    S.rows = rows;
    S.N = Nn;
    S.mu_s = S.mu_k = mu;
    S.h = 0.01;
    S.alpha = -0.1;
    S.scheme = DFO_SCHEME_CONSISTENT;
    S.friction_updates = 1;
    S.rate_max = 4.0;
    S.snap_max_rel_h = S.snap_min_rel_h = 1e-7;
    eng *E = eng_create(&S, &ALLOC, NULL);
    if (!E) { fprintf(stderr, "test_engine_dinv: no engine\n"); exit(1); }
    return E;
}

/* D of the contacts with limit > 0 (+ comp), from the columns A_grid^-1 w_j solved here; into D (m x m),
 * their indices into sel; returns m */
static size_t delassus(const double *limit, const double *comp, int *sel, double *D)
{
    double col[NC][NDOF];
    size_t m = 0;
    for (size_t j = 0; j < NC; j++) {
        if (!(limit[j] > 0.0)) continue;
        double w[NDOF] = {0.0, 0.0, 0.0};
        for (size_t k = 0; k < NNZ[j]; k++) w[IDX[j][k]] += W[j][k];
        op_solve(&MODEL, ENG_SLOT_GRID, w, col[m]);
        sel[m++] = (int)j;
    }
    for (size_t a = 0; a < m; a++)
        for (size_t b = 0; b < m; b++) {
            const size_t j = (size_t)sel[a];
            double s = 0.0;
            for (size_t k = 0; k < NNZ[j]; k++) s += W[j][k] * col[b][IDX[j][k]];
            D[a * m + b] = s + ((a == b && comp) ? comp[j] : 0.0);
        }
    return m;
}

/* the largest |gDinv D - I| of the cache against the problem's own D */
static double inverse_error(const eng *E, size_t m, const double *D)
{
    double worst = 0.0;
    for (size_t a = 0; a < m; a++)
        for (size_t b = 0; b < m; b++) {
            double s = 0.0;
            for (size_t k = 0; k < m; k++) s += E->gDinv[a * m + k] * D[k * m + b];
            worst = fmax(worst, fabs(s - (a == b ? 1.0 : 0.0)));
        }
    return worst;
}

int main(void)
{
    checks TT = {0, 0, NULL, {0}};
    checks *T = &TT;
    eng_row rows[NC], rows_f[NC];
    double Nn[NC] = {1.0, 1.0, 1.0}, mu[NC] = {0.3, 0.3, 0.3};
    eng *E = engine(rows, Nn, mu);
    const double cM = 2.0, cC = 0.05, cK = 1e-4;
    if (!op_factor(&MODEL, ENG_SLOT_GRID, cM, cC, cK)) return 1;
    E->slot_ok[ENG_SLOT_GRID] = 1; /* (the engine's record of that factorisation: its factor_slot's) */
    E->slot_c[ENG_SLOT_GRID][0] = cM;
    E->slot_c[ENG_SLOT_GRID][1] = cC;
    E->slot_c[ENG_SLOT_GRID][2] = cK;
    /* a load that breaks every contact loose from the warm all-stuck basis: Lemke on D^-1 */
    double p_hat[NDOF] = {4.0, -3.0, 2.5};
    const double comp_a[NC] = {0.5, 0.0, 0.1};
    struct { double limit[NC]; const double *comp; const char *what; } seq[] = {
        {{0.3, 0.3, 0.3}, NULL, "all three"},
        {{0.3, 0.3, 0.3}, NULL, "all three again (a hit)"},
        {{0.3, 0.0, 0.3}, NULL, "contact 2 without load"},
        {{0.3, 0.3, 0.3}, comp_a, "all three, compliances"},
        {{0.3, 0.3, 0.3}, NULL, "all three, none"},
        {{0.0, 0.3, 0.3}, comp_a, "contact 1 without load, compliances"},
    };
    for (size_t q = 0; q < sizeof seq / sizeof seq[0]; q++) {
        eng_problem P;
        memset(&P, 0, sizeof P);
        P.slot = ENG_SLOT_GRID;
        P.cM = cM;
        P.cC = cC;
        P.cK = cK;
        P.p_hat = p_hat;
        P.limit = seq[q].limit;
        P.N = Nn;
        P.comp = seq[q].comp;
        int mode[NC] = {0, 0, 0}, piv = 0;
        double V1[NDOF], f[NC];
        check_context(T, "%s", seq[q].what);
        CHECK(eng_dense_friction(E, &P, ENG_SOLVE_LCP, mode, V1, f, &piv) == ENG_OK);
        CHECK(q == 1 || piv > 0); /* (Lemke ran on D^-1; the hit's warm basis holds) */
        int sel[NC];
        double D[NC * NC];
        const size_t m = delassus(seq[q].limit, seq[q].comp, sel, D);
        CHECK(E->gd_ok && E->gd_m == m && E->gd_comp == (seq[q].comp != NULL)); /* the cache's key */
        for (size_t a = 0; a < m; a++) {
            CHECK(E->gd_sel[a] == sel[a]);
            if (seq[q].comp) CHECK(E->gd_cv[a] == seq[q].comp[sel[a]]);
        }
        CHECK(inverse_error(E, m, D) < 1e-12); /* D^-1 of the problem's own set */
        /* the same solve by a fresh engine, bit for bit */
        eng *F = engine(rows_f, Nn, mu);
        memcpy(F->slot_c[ENG_SLOT_GRID], E->slot_c[ENG_SLOT_GRID], sizeof E->slot_c[ENG_SLOT_GRID]);
        F->slot_ok[ENG_SLOT_GRID] = 1;
        int mode_f[NC] = {0, 0, 0};
        double V1f[NDOF], ff[NC];
        CHECK(eng_dense_friction(F, &P, ENG_SOLVE_LCP, mode_f, V1f, ff, NULL) == ENG_OK);
        CHECK(memcmp(mode, mode_f, sizeof mode) == 0 && memcmp(V1, V1f, sizeof V1) == 0 &&
              memcmp(f, ff, sizeof f) == 0); /* the fresh engine's solve, bit for bit */
        eng_destroy(F);
    }
    /* the scheme refactors the grid slot with its own coefficients: the cache is cleared then, so
     * whatever it holds after some steps is D^-1 of the new matrix */
    check_context(T, "after steps of the consistent scheme");
    eng_state s;
    CHECK(eng_state_init(E, &s, 0));
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    const double x0[NDOF] = {0.3, 0.0, -0.3}, v0[NDOF] = {0.0, 0.5, 0.0};
    eng_start(E, &in, 0.0, x0, v0, &s);
    CHECK(eng_advance(E, &in, &s, 0.5, NULL) == ENG_OK);
    CHECK(E->slot_c[ENG_SLOT_GRID][0] != cM); /* (refactored: MODEL.L holds the new factor) */
    if (E->gd_ok) {
        double limit[NC], D[NC * NC];
        int sel[NC];
        for (size_t j = 0; j < NC; j++) limit[j] = 0.0;
        for (size_t a = 0; a < E->gd_m; a++) limit[E->gd_sel[a]] = 1.0;
        CHECK(delassus(limit, NULL, sel, D) == E->gd_m);
        CHECK(inverse_error(E, E->gd_m, D) < 1e-12);
    }
    printf("test_engine_dinv: after the steps the cache is %s\n", E->gd_ok ? "the new matrix's" : "empty");
    eng_state_free(E, &s);
    eng_destroy(E);
    return checks_done(T, "test_engine_dinv");
}
