/* The engine's schemes specialised at compile time (fmu_src/engine/engine_step.h included with a
 * model's inline operators: models/oscillator/osc_engine.c, models/chain/chain_engine.c) against the
 * same schemes through engine.c with the same operators behind eng_ops's function pointers: the
 * same bits (positions, velocities, Bossak variables, forces, modes, counters, every switch's
 * time), one block in the three Bossak schemes with a belt, input ramps and input and belt changes,
 * a chain of 8 blocks (the chain's own model, chain_create's engine setup) in the three schemes with
 * a change of the external forces, undamped and damped, and with a belt and its change; the runs
 * switch many times. A chain's block held on its belt moves at the belt's speed. The chain's
 * sparse-structure operators (eng_sparse) level by level: held solves, the fused step, closed-form
 * breakaways, spans, their ranges checked. The
 * oscillator's stepper (scheme.h's dfo_advance: its engine model made per call, the state mapped
 * through dfo_state) against its engine model kept across the calls: the same bits; the located
 * scheme's stuck fast path on against off; the fused loop of held-input grid steps against the
 * general path, the three schemes, observed; the oscillator's observables over a fused run against
 * the general path's. */
#include "check.h"
#include "chain_internal.h" /* the chain's engine (chain_model.E), operators and specialised schemes */
#include "osc_engine.h"     /* the block's operators and its specialised schemes */
#include "osc_params.h"

#include "newmark.h"

#include "scheme.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <stddef.h>
#include <string.h>

#define NCHAIN 8

static void *t_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void t_free(void *env, void *p) { (void)env; free(p); }
static const eng_alloc ALLOC = {t_alloc, t_free, NULL};

/* The switches of a run: how many, and the sum of their times and contacts (a fingerprint). */
typedef struct {
    long count;
    double t_sum;
    size_t j_sum;
} switch_log;

static void on_switch(void *ctx, double t, size_t contact, const eng_state *s, int from, int to)
{
    switch_log *L = ctx;
    (void)s; (void)from; (void)to;
    L->count++;
    L->t_sum += t;
    L->j_sum += contact;
}

/* The entry points of one build of the schemes. */
typedef struct {
    void (*start)(eng *, const eng_inputs *, double, const double *, const double *, eng_state *);
    eng_status (*advance)(eng *, const eng_inputs *, eng_state *, double, const eng_hooks *);
    void (*new_inputs)(eng *, const eng_inputs *, const eng_inputs *, eng_state *, const eng_hooks *);
} entry;

static const entry GENERIC = {eng_start, eng_advance, eng_new_inputs};
static const entry BLOCK = {osc_eng_start, osc_eng_advance, osc_eng_new_inputs};
static const entry CHAIN = {chain_eng_start, chain_eng_advance, chain_eng_new_inputs};

/* Run S with the entry points of X from rest: communication points every dt (off the grid) to
 * t_end, the inputs in1 before t_change and in2 from there (eng_new_inputs at the change). The
 * final state into s (initialised here; the caller frees it with E), the switches into L. */
static eng *run(const eng_setup *S, const entry *X, const eng_inputs *in1, const eng_inputs *in2, double t_change,
                double dt, double t_end, eng_state *s, switch_log *L, eng_status *status)
{
    static const double zeros[NCHAIN] = {0.0};
    eng *E = eng_create(S, &ALLOC, NULL);
    if (!E || !eng_state_init(E, s, 0)) { fprintf(stderr, "test_engine_step: out of memory\n"); exit(1); }
    memset(L, 0, sizeof *L);
    const eng_hooks hk = {on_switch, L, NULL, 0, 0, 1};
    X->start(E, in1, 0.0, zeros, zeros, s);
    const eng_inputs *in = in1;
    *status = ENG_OK;
    for (int k = 1; (double)k * dt <= t_end && *status == ENG_OK; k++) {
        const double t = (double)k * dt;
        if (in == in1 && t > t_change) {
            *status = X->advance(E, in, s, t_change, &hk);
            if (*status != ENG_OK) break;
            X->new_inputs(E, in1, in2, s, &hk);
            in = in2;
        }
        *status = X->advance(E, in, s, t, &hk);
    }
    return E;
}

/* The two runs' states and switches bit for bit. */
static int same_bits(const eng_state *a, const eng_state *b, const switch_log *La, const switch_log *Lb)
{
    const size_t n = a->n, nc = a->nc;
    int same = a->t == b->t && a->n_grid == b->n_grid && a->steps == b->steps && a->solves == b->solves &&
               a->pivot_steps == b->pivot_steps && a->switches == b->switches && La->count == Lb->count &&
               La->j_sum == Lb->j_sum && !memcmp(&La->t_sum, &Lb->t_sum, sizeof(double)) &&
               !memcmp(&a->t_switch, &b->t_switch, sizeof(double));
    same &= !memcmp(a->X, b->X, n * sizeof(double)) && !memcmp(a->V, b->V, n * sizeof(double));
    same &= !memcmp(a->A, b->A, n * sizeof(double)) && !memcmp(a->hA, b->hA, n * sizeof(double));
    same &= !memcmp(a->F, b->F, nc * sizeof(double)) && !memcmp(a->mode, b->mode, nc * sizeof(int));
    same &= !memcmp(a->t_stick, b->t_stick, nc * sizeof(double));
    return same;
}

static eng_setup setup_common(size_t n, const eng_row *rows, const double *N, const double *ms, const double *mk,
                              const double *Pc, const double *Ps, int scheme, double rate)
{
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = n;
    S.nc = n;
    S.rows = rows;
    S.exc.omega = 0.5;
    S.exc.Pc = Pc;
    S.exc.Ps = Ps;
    S.N = N;
    S.mu_s = ms;
    S.mu_k = mk;
    S.h = 4.0 * DFO_PI / 800.0;
    S.alpha = -0.1;
    S.scheme = scheme;
    S.friction_updates = 1;
    S.fast_paths = 1;
    S.rate_max = rate + 0.5;
    S.snap_max_rel_h = S.snap_min_rel_h = 1e-7;
    return S;
}

static void test_block(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    static const size_t idx[1] = {0};
    static const double w1[1] = {1.0};
    const eng_row row = {1, idx, w1};
    const double N[1] = {0.6}, ms[1] = {0.5}, mk[1] = {0.35}, Pc[1] = {1.0};
    /* a belt at 0.2, a ramp of the normal force, then the belt at -0.1 and a held external force */
    const double vb1[1] = {0.2}, vb2[1] = {-0.1}, F2[1] = {0.15}, dN[1] = {0.004};
    const eng_inputs in1 = {NULL, NULL, vb1, {NULL, NULL}, {dN, NULL}, 0.0};
    const eng_inputs in2 = {F2, NULL, vb2, {NULL, NULL}, {NULL, NULL}, 0.0};
    for (int scheme = DFO_SCHEME_PAPER; scheme <= DFO_SCHEME_LOCATED; scheme++) {
        check_context(T, "one block, %s: the inline build against engine.c", names[scheme]);
        osc_eng_model Bg, Bi;
        memset(&Bg, 0, sizeof Bg);
        Bg.m = 1.0;
        Bg.c = 0.05;
        Bg.k = 1.0;
        Bi = Bg;
        eng_setup S = setup_common(1, &row, N, ms, mk, Pc, NULL, scheme, 1.0);
        const eng_ops og = {&Bg, eng1_K, eng1_C, eng1_M, eng1_factor, eng1_solve, eng1_friction, eng1_breakaway, 1};
        S.ops = og;
        eng_state sg, si;
        switch_log Lg, Li;
        eng_status stg, sti;
        eng *Eg = run(&S, &GENERIC, &in1, &in2, 20.0, 0.37, 40.0, &sg, &Lg, &stg);
        S.ops.ctx = &Bi;
        eng *Ei = run(&S, &BLOCK, &in1, &in2, 20.0, 0.37, 40.0, &si, &Li, &sti);
        printf("  block %-10s 40 s: %ld switches, x %.17g / %.17g\n", names[scheme], Lg.count, sg.X[0], si.X[0]);
        CHECK(stg == ENG_OK);
        CHECK(sti == ENG_OK);
        CHECK(Lg.count >= 10);
        CHECK(same_bits(&sg, &si, &Lg, &Li));
        eng_state_free(Eg, &sg);
        eng_state_free(Ei, &si);
        eng_destroy(Eg);
        eng_destroy(Ei);
    }
}

/* The stuck fast path (eng_ops.breakaway with fast_paths): the block's friction solves and
 * breakaway questions counted behind the hooks, and an observer's phases summed. */
typedef struct {
    long solves, asks;
    long phases, velocities; /* (the phases with velocities: none where not asked for) */
    double t_sum, x_max;
} hook_count;

static hook_count *counted; /* the run's counters (set by test_stuck_fast_path before each run) */

static eng_status count_friction(void *ctx, const eng_problem *P, int what, int *mode, double *V1, double *f,
                                 int *pivots)
{
    counted->solves++;
    return eng1_friction(ctx, P, what, mode, V1, f, pivots);
}

static double count_breakaway(void *ctx, const eng_harmonic *exc, const eng_state *s, const eng_inputs *in,
                              const double *Fb)
{
    counted->asks++;
    return eng1_breakaway(ctx, exc, s, in, Fb);
}

static void count_phase(void *ctx, const eng_phase *ph, const eng_state *s)
{
    hook_count *H = ctx;
    H->phases++;
    H->t_sum += ph->tb - ph->ta;
    (void)s;
    H->x_max = fmax(H->x_max, ph->X1[0]);
    H->velocities += ph->V0 != NULL || ph->V1 != NULL; /* (not asked for: none) */
}

/* Four runs of one block compared: their final states, engines, switches and observed phases. */
typedef struct {
    eng_state s[4];
    eng *E[4];
    switch_log L[4];
    hook_count H[4];
} four_runs;

/* Held inputs: none, and an external force of 0.15 (the runs' change at 20 s). */
static const double F_JUMP[1] = {0.15};
static const eng_inputs HELD_NONE = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
static const eng_inputs HELD_F = {F_JUMP, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};

/* The unit block of the runs below: m = k = 1, c = 0.05. */
static void unit_block(osc_eng_model *B)
{
    memset(B, 0, sizeof *B);
    B->m = 1.0;
    B->c = 0.05;
    B->k = 1.0;
}

/* One block of S from rest through the entry points of X, observed by obs: the inputs in1 to 20 s,
 * then in2 (eng_new_inputs) and communication points every 1.37 s, k_max of them. The final state
 * into s (initialised here), the switches into L. */
static eng *run_with(checks *T, const eng_setup *S, const entry *X, const eng_inputs *in1, const eng_inputs *in2,
                     const eng_observer *obs, int k_max, switch_log *L, eng_state *s)
{
    eng *E = eng_create(S, &ALLOC, NULL);
    if (!E || !eng_state_init(E, s, 0)) { fprintf(stderr, "test_engine_step: out of memory\n"); exit(1); }
    memset(L, 0, sizeof *L);
    const eng_hooks hk = {on_switch, L, obs, 0, 0, 1};
    const double zero[1] = {0.0};
    X->start(E, in1, 0.0, zero, zero, s);
    eng_status st = X->advance(E, in1, s, 20.0, &hk);
    CHECK(st == ENG_OK);
    X->new_inputs(E, in1, in2, s, &hk);
    for (int k = 1; k <= k_max && st == ENG_OK; k++) st = X->advance(E, in2, s, 20.0 + 1.37 * k, &hk);
    CHECK(st == ENG_OK);
    return E;
}

/* run_with observed over [12, w1], its phases counted into H */
static eng *run_observed(checks *T, const eng_setup *S, const entry *X, const eng_inputs *in1, const eng_inputs *in2,
                         double w1, int k_max, hook_count *H, switch_log *L, eng_state *s)
{
    memset(H, 0, sizeof *H);
    H->x_max = -INFINITY;
    const eng_observer obs = {12.0, w1, count_phase, H, 0};
    return run_with(T, S, X, in1, in2, &obs, k_max, L, s);
}

/* One block in the located scheme, stick-dominated (N mu_s = 0.8 against a unit excitation with a
 * sine part), held inputs with a change of the external force at 20 s and an observer's window
 * [12, 18]: the stuck fast path on and off, through engine.c and inlined, end on the same bits and
 * observe the same motion (on, a stuck stretch taken at once is one phase); on, it asks the model's breakaway and takes a quarter fewer friction solves
 * (the stick phases outside the window: about half the time; a sliding step takes several). */
static void test_stuck_fast_path(checks *T)
{
    static const size_t idx[1] = {0};
    static const double w1[1] = {1.0};
    const eng_row row = {1, idx, w1};
    const double N[1] = {1.8}, ms[1] = {0.5}, mk[1] = {0.35}, Pc[1] = {cos(0.3)}, Ps[1] = {sin(0.3)};
    const eng_inputs *in1 = &HELD_NONE, *in2 = &HELD_F;
    four_runs R;
    for (int r = 0; r < 4; r++) { /* r: 0 generic off, 1 generic on, 2 inline off, 3 inline on */
        osc_eng_model B;
        unit_block(&B);
        eng_setup S = setup_common(1, &row, N, ms, mk, Pc, Ps, DFO_SCHEME_LOCATED, 1.0);
        const eng_ops ops = {&B, eng1_K, eng1_C, eng1_M, eng1_factor, eng1_solve, count_friction, count_breakaway, 1};
        S.ops = ops;
        S.fast_paths = r & 1;
        counted = &R.H[r];
        R.E[r] = run_observed(T, &S, (r < 2) ? &GENERIC : &BLOCK, in1, in2, 18.0, 40, &R.H[r], &R.L[r], &R.s[r]);
    }
    printf("  stuck fast path: %ld switches, solves off %ld / on %ld, breakaways asked %ld, x %.17g\n", R.L[0].count,
           R.H[0].solves, R.H[1].solves, R.H[1].asks, R.s[0].X[0]);
    check_context(T, "one block, located, the stuck fast path against the steps one by one");
    CHECK(R.L[0].count >= 10);
    /* the stick ended at the model's closed form with the fast path off too (the same numbers: the stick's
     * breakaway kept, a stuck step taken without a trial where it lies beyond the step, asked again
     * from the step that holds it); on, no more than off (the inline runs call the block's hooks
     * directly) */
    CHECK(R.H[0].asks > 0 && R.H[1].asks >= R.H[0].asks);
    CHECK(4 * R.H[1].solves < 3 * R.H[0].solves); /* (the stick phases outside the window skipped) */
    for (int r = 1; r < 4; r++) {
        CHECK(same_bits(&R.s[0], &R.s[r], &R.L[0], &R.L[r]));
        /* the same phases off (r = 2) and on (r = 3) through either build; on, a stuck stretch taken at
         * once is one phase (fewer phases, the same time observed to rounding, the same positions) */
        const int ref = r & 1;
        CHECK(R.H[r].phases == R.H[ref].phases && R.H[r].t_sum == R.H[ref].t_sum && R.H[r].x_max == R.H[ref].x_max);
        CHECK(R.H[r].phases <= R.H[0].phases && fabs(R.H[r].t_sum - R.H[0].t_sum) <= 1e-12 * R.H[0].t_sum &&
              R.H[r].x_max == R.H[0].x_max);
    }
    CHECK(R.H[1].phases < R.H[0].phases);
    CHECK(R.H[0].phases > 100);
    for (int r = 0; r < 4; r++) CHECK(R.H[r].velocities == 0);
    for (int r = 0; r < 4; r++) {
        eng_state_free(R.E[r], &R.s[r]);
        eng_destroy(R.E[r]);
    }
}

/* The stick-dominated block of the runs below (N mu_s = 0.35 against a unit excitation with a sine
 * part) in scheme with the step h, its arrays in D; B its operators' model. */
typedef struct {
    size_t idx[1];
    double w[1], N[1], ms[1], mk[1], Pc[1], Ps[1];
    eng_row row;
} stick_data;

static eng_setup stick_block(stick_data *D, osc_eng_model *B, int scheme, double h)
{
    D->idx[0] = 0;
    D->w[0] = 1.0;
    D->N[0] = 0.7;
    D->ms[0] = 0.5;
    D->mk[0] = 0.35;
    D->Pc[0] = cos(0.3);
    D->Ps[0] = sin(0.3);
    D->row.nnz = 1;
    D->row.idx = D->idx;
    D->row.w = D->w;
    unit_block(B);
    eng_setup S = setup_common(1, &D->row, D->N, D->ms, D->mk, D->Pc, D->Ps, scheme, 1.0);
    S.h = h;
    const eng_ops ops = {B, eng1_K, eng1_C, eng1_M, eng1_factor, eng1_solve, eng1_friction, eng1_breakaway, 1};
    S.ops = ops;
    return S;
}

/* The fused loop (engine_step.h's fused_steps: held inputs, no energy accounts) against the general
 * path (the same run with the energy accounts, which take every step through step_located and
 * step_lcp): one block, stick-dominated, on a coarse grid (50 steps per period: switches inside most
 * of the steps that hold one), the three schemes through engine.c and inlined, an observer's window
 * [12, 30] inside the run: the same bits, counters and switches, and the same observed phases (the
 * fused loop's declined step handing its trial to the general path, the stuck step the stuck fast
 * path declines taken in the loop, the window's test once per run). */
static void test_fused_vs_general(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    const eng_inputs *in1 = &HELD_NONE, *in2 = &HELD_F;
    for (int scheme = DFO_SCHEME_PAPER; scheme <= DFO_SCHEME_LOCATED; scheme++) {
        four_runs R;
        for (int r = 0; r < 4; r++) { /* r: 0 generic general, 1 generic fused, 2 inline general, 3 inline fused */
            osc_eng_model B;
            stick_data D;
            eng_setup S = stick_block(&D, &B, scheme, 4.0 * DFO_PI / 50.0);
            S.account_energy = !(r & 1);
            R.E[r] = run_observed(T, &S, (r < 2) ? &GENERIC : &BLOCK, in1, in2, 30.0, 30, &R.H[r], &R.L[r], &R.s[r]);
        }
        printf("  fused loop, %-10s: %ld switches, %lld steps, %ld phases observed, x %.17g\n", names[scheme],
               R.L[0].count, R.s[0].steps, R.H[0].phases, R.s[0].X[0]);
        check_context(T, "one block, %s: the fused loop against the general path", names[scheme]);
        CHECK(R.L[0].count >= 10);
        CHECK(R.H[0].phases > 50);
        for (int r = 1; r < 4; r++) {
            CHECK(same_bits(&R.s[0], &R.s[r], &R.L[0], &R.L[r]));
            CHECK(R.H[r].phases == R.H[0].phases && !memcmp(&R.H[r].t_sum, &R.H[0].t_sum, sizeof(double)) &&
                  R.H[r].x_max == R.H[0].x_max);
        }
        for (int r = 0; r < 4; r++) {
            eng_state_free(R.E[r], &R.s[r]);
            eng_destroy(R.E[r]);
        }
    }
}

/* The oscillator's observer (osc_eng_observe: osc_observables on a dfo_state) called through
 * another function pointer: the specialised fused loop calls it out of line from the phase's values */
static void other_observe(void *ctx, const eng_phase *ph, const eng_state *s) { osc_observe_phase(ctx, ph, s); }

/* The oscillator's observables over a fused run (its values in registers, ENG_OBS_RUN) against the
 * general path's (the energy accounts on: every phase observed by its own call) and against the
 * fused run with the observer called out of line (another function pointer): one block,
 * stick-dominated, about 50 steps per period, the three schemes, inlined, the window [12, 30] opened in
 * the middle of a call and closed in another (runs that start inside it, sampled, and runs that
 * start before it), and [20, 30] opened where a call starts on a grid point (a run inside it, nothing
 * sampled yet): x_max, x_min, the stuck time, the friction's work and the open stick stretch
 * the same bits; the motion observed is stick-slip (a stuck time, a dissipated energy, a range). */
static void test_observables_in_run(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    for (int k = 0; k < 6; k++) {
        const int scheme = DFO_SCHEME_PAPER + k / 2;
        const double w0 = (k % 2) ? 20.0 : 12.0; /* the window opened inside a call, or where one starts */
        dfo_state d[3];
        eng_state s[3];
        eng *E[3];
        switch_log L[3];
        for (int r = 0; r < 3; r++) { /* r: 0 general, 1 fused, 2 fused with another observer's function */
            osc_eng_model B;
            stick_data D;
            eng_setup S = stick_block(&D, &B, scheme, 0.125); /* (20 s a grid point) */
            S.account_energy = r == 0;
            memset(&d[r], 0, sizeof d[r]);
            d[r].stuck_from = NAN;
            d[r].x_max = 1e300; /* (not a sample: the first one replaces them) */
            d[r].x_min = -1e300;
            osc_observables O = {w0, 30.0, &d[r]};
            const eng_observer obs = {w0, 30.0, (r == 2) ? other_observe : osc_eng_observe, &O, 0};
            E[r] = run_with(T, &S, &BLOCK, &HELD_NONE, &HELD_F, &obs, 30, &L[r], &s[r]);
        }
        printf("  observables in a fused run, %-10s, [%g, 30]: x in [%.6g, %.6g], stuck %.6g s, E_friction %.6g\n",
               names[scheme], w0, d[0].x_min, d[0].x_max, d[0].t_stuck, d[0].E_friction);
        check_context(T, "one block, %s, window from %g: the oscillator's observables in a fused run", names[scheme], w0);
        CHECK(d[0].observed && d[0].x_max > d[0].x_min && d[0].t_stuck > 0.1 && d[0].t_stuck < 30.0 - w0 &&
              d[0].E_friction > 0.0);
        for (int r = 1; r < 3; r++) {
            CHECK(same_bits(&s[0], &s[r], &L[0], &L[r]));
            CHECK(d[r].observed == d[0].observed && !memcmp(&d[r].x_max, &d[0].x_max, sizeof(double)) &&
                  !memcmp(&d[r].x_min, &d[0].x_min, sizeof(double)) &&
                  !memcmp(&d[r].t_stuck, &d[0].t_stuck, sizeof(double)) &&
                  !memcmp(&d[r].E_friction, &d[0].E_friction, sizeof(double)) &&
                  isnan(d[r].stuck_from) == isnan(d[0].stuck_from) &&
                  (isnan(d[0].stuck_from) || d[r].stuck_from == d[0].stuck_from));
        }
        for (int r = 0; r < 3; r++) {
            eng_state_free(E[r], &s[r]);
            eng_destroy(E[r]);
        }
    }
}

/* ---- the oscillator's stepper against its engine model kept across calls -------------------- */

/* What a comparison of the oscillator's stepper with its engine model varies. */
typedef struct {
    int scheme;
    double chi, c, Nn;
    double v_belt;   /* NaN: no belt */
    int stribeck;
    double F_ramp;   /* dF_ext/dt over the run (0: held) */
    double F_jump;   /* F_ext set to this at t = 10 (0: none) */
    double belt_to;  /* the belt's speed set to this at t = 10 (NaN: held) */
} osc_case;

static void count_switch(void *ctx, double t, double x, int from, int to)
{
    (void)t; (void)x; (void)from; (void)to;
    ++*(long long *)ctx;
}

/* Run case K: the oscillator's stepper (dfo_advance), and the engine through both entries, communication
 * steps of 0.1 s over 30 s at h = 1e-3; max |x_engine - x_stepper| / max |x| into *d, the switches into
 * sw[0..2]. */
static int run_case(checks *T, const osc_case *K, double *d, long long sw[3])
{
    const double h = 1e-3;
    dfo_params p = osc_test_params(K->scheme, 1.0, 1.0, K->c, 0.6, 0.9, K->Nn, 0.8, K->chi);
    p.h = h;
    if (K->stribeck) osc_test_stribeck(&p, 0.05, 1.0);
    dfo_model M;
    dfo_model_init(&M, &p);
    dfo_inputs u;
    memset(&u, 0, sizeof u);
    if (!isnan(K->v_belt)) { u.v_belt = K->v_belt; u.v_belt_set = 1; }
    if (K->F_ramp != 0.0) { u.F_ext_set = 1; u.F_ext_d[0] = K->F_ramp; u.ramp = 1; u.t_d = 0.0; }
    dfo_state so;
    dfo_start(&M, &u, 0.0, &so);
    osc_eng_model O[2];
    eng *E[2];
    eng_state s[2];
    osc_eng_inbuf b[2][2]; /* per run: the current inputs and the former ones */
    eng_inputs in[2], old[2];
    const entry *X[2] = {&GENERIC, &BLOCK};
    /* (one run: the state's stick breakaway is of its inputs between the calls, as the stepper keeps it) */
    const eng_hooks keep = {NULL, NULL, NULL, 0, 0, 1};
    for (int r = 0; r < 2; r++) {
        E[r] = osc_eng_create(&M, &O[r], &ALLOC, NULL);
        if (!E[r] || !eng_state_init(E[r], &s[r], 0)) { fprintf(stderr, "test_engine_step: no engine\n"); exit(1); }
        osc_eng_inputs(&u, &b[r][0], &in[r]);
        X[r]->start(E[r], &in[r], 0.0, &p.x0, &p.v0, &s[r]);
    }
    double dmax = 0.0, xm = 0.0;
    long long sw_o = 0;
    int ok = 1;
    for (int k = 1; k <= 300 && ok; k++) {
        const double t = (double)(k * 100) * h;
        if (k == 101 && (K->F_jump != 0.0 || !isnan(K->belt_to))) { /* the inputs change at t = 10 s */
            const dfo_inputs uold = u;
            if (K->F_jump != 0.0) { u.F_ext = K->F_jump; u.F_ext_set = 1; }
            if (!isnan(K->belt_to)) { u.v_belt = K->belt_to; u.v_belt_set = 1; }
            dfo_new_inputs(&M, &uold, &u, &so);
            for (int r = 0; r < 2; r++) {
                osc_eng_inputs(&uold, &b[r][1], &old[r]);
                osc_eng_inputs(&u, &b[r][0], &in[r]);
                X[r]->new_inputs(E[r], &old[r], &in[r], &s[r], NULL);
            }
        }
        for (int r = 0; r < 2; r++) ok &= X[r]->advance(E[r], &in[r], &s[r], t, &keep) == ENG_OK;
        ok &= dfo_advance(&M, &u, &so, t, count_switch, &sw_o) == DFO_OK;
        dmax = fmax(dmax, fabs(s[0].X[0] - so.X));
        xm = fmax(xm, fabs(so.X));
    }
    CHECK(ok);
    const switch_log none = {0, 0.0, 0}; /* (no switch hook in these runs) */
    CHECK(same_bits(&s[0], &s[1], &none, &none));
    *d = dmax / xm;
    sw[0] = sw_o;
    sw[1] = s[0].switches;
    sw[2] = s[1].switches;
    for (int r = 0; r < 2; r++) {
        eng_state_free(E[r], &s[r]);
        eng_destroy(E[r]);
    }
    return ok;
}

/* The oscillator's engine model (osc_engine.c), inline and through engine.c, against the oscillator's
 * stepper (dfo_advance and dfo_new_inputs: a fresh engine per call, the state and the inputs mapped):
 * the same bits between the two builds, the same positions and switches as the stepper (the three
 * schemes, damping, a stick-dominated case, belts and a belt change, Stribeck, a ramp of F_ext, a
 * jump of F_ext): nothing is lost between the calls. */
static void test_vs_stepper(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    const double nan = NAN;
    const osc_case cases[] = {
        {DFO_SCHEME_PAPER, 0.7, 0.0, 0.5, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_CONSISTENT, 0.3, 0.0, 0.5, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.3, 0.0, 0.5, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.05, 0.5, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.0, 0.7, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.6, 0.0, 0.5, 0.3, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.6, 0.0, 0.5, 0.3, 1, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.0, 0.5, nan, 0, 0.02, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.0, 0.5, nan, 0, 0.0, 0.25, nan},
        {DFO_SCHEME_CONSISTENT, 0.6, 0.0, 0.5, 0.3, 0, 0.0, 0.0, -0.2},
        {DFO_SCHEME_LOCATED, 0.6, 0.05, 0.5, 0.3, 1, 0.0, 0.0, 0.1},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const osc_case *K = &cases[k];
        check_context(T, "%s chi %.1f c %.2f N %.1f belt %g (to %g) stribeck %d ramp %g jump %g", names[K->scheme],
                      K->chi, K->c, K->Nn, K->v_belt, K->belt_to, K->stribeck, K->F_ramp, K->F_jump);
        double d = INFINITY;
        long long sw[3] = {0, 0, 0};
        run_case(T, K, &d, sw);
        printf("  %-10s chi %.1f c %.2f N %.1f belt %-4g to %-4g stribeck %d ramp %-4g jump %-4g: max |dx| / max |x| "
               "%.2e, switches %lld / %lld\n",
               names[K->scheme], K->chi, K->c, K->Nn, K->v_belt, K->belt_to, K->stribeck, K->F_ramp, K->F_jump, d,
               sw[0], sw[1]);
        CHECK(d == 0.0);
        CHECK(sw[1] >= 4);
        CHECK(sw[1] == sw[0] && sw[2] == sw[1]);
    }
}

/* ---- the chain: its own operators (chain_engine_ops.h), inline (chain_engine.c) and generic ----- */

/* A chain of n blocks between two walls, the chain's own model (chain.h): masses 1 + dm (i mod 3),
 * unit springs (k_end = 1) and dampers c (c_end = c), normal forces 1.2 + dN (i mod 3), mu_s 0.5,
 * mu_k 0.35, the excitation cos(0.5 t + 0.1 i), at rest; the setups of its engines copied from the
 * one chain_create makes (chain_setup.c's, through eng_setup_of), the models kept until
 * test_chain_free (up to TC_MODELS). */
enum { TC_MODELS = 8 };
typedef struct {
    size_t n;
    double *m, *k, *c, *P0, *phi, *N, *ms, *chi, *zero;
    double c_end;
    chain_model *M[TC_MODELS];
    int nm;
    eng_sparse sp; /* the sparse-structure operators of the latest test_chain_setup */
} test_chain_model;

static double *dvec(size_t n)
{
    double *p = calloc(n, sizeof(double));
    if (!p) { fprintf(stderr, "test_engine_step: out of memory\n"); exit(1); }
    return p;
}

static void test_chain_make(test_chain_model *B, size_t n, double dm, double dN, double c)
{
    memset(B, 0, sizeof *B);
    B->n = n;
    B->m = dvec(n); B->k = dvec(n); B->c = dvec(n); B->P0 = dvec(n); B->phi = dvec(n); B->N = dvec(n);
    B->ms = dvec(n); B->chi = dvec(n); B->zero = dvec(n);
    B->c_end = c;
    for (size_t i = 0; i < n; i++) {
        B->m[i] = 1.0 + dm * (double)(i % 3);
        B->k[i] = 1.0;
        B->c[i] = c;
        B->P0[i] = 1.0;
        B->phi[i] = 0.1 * (double)i;
        B->N[i] = 1.2 + dN * (double)(i % 3);
        B->ms[i] = 0.5;
        B->chi[i] = 0.7; /* (0.7 * 0.5: the double nearest 0.35) */
    }
}

/* A chain_create of B in scheme with the step h: the engine setup it makes. */
static eng_setup test_chain_setup(checks *T, test_chain_model *B, int scheme, double h)
{
    const chain_params p = {B->n, B->m, B->k, B->c, B->P0, B->phi, B->N, B->ms, B->chi, B->zero, B->zero,
                            1.0, B->c_end, 0.5, h, -0.1, scheme, 0, NULL, NULL, 0, NULL, NULL};
    const chain_alloc al = {t_alloc, t_free, NULL};
    const char *err = NULL;
    chain_model *M = (B->nm < TC_MODELS) ? chain_create(&p, &al, &err) : NULL;
    if (!M) { fprintf(stderr, "test_engine_step: no chain: %s\n", err ? err : "too many models"); exit(1); }
    B->M[B->nm++] = M;
    const eng_setup S = *eng_setup_of(M->E);
    CHECK(S.n == B->n && S.nc == B->n && S.scheme == scheme && S.h == h && S.fast_paths == 1);
    return S;
}

/* A run's state and engine freed. */
static void run_free(eng *E, eng_state *s)
{
    eng_state_free(E, s);
    eng_destroy(E);
}

/* The models made since the last release (their engines destroyed first). */
static void test_chain_release(test_chain_model *B)
{
    for (int j = 0; j < B->nm; j++) chain_destroy(B->M[j]);
    B->nm = 0;
}

static void test_chain_free(test_chain_model *B)
{
    test_chain_release(B);
    free(B->m); free(B->k); free(B->c); free(B->P0); free(B->phi); free(B->N); free(B->ms); free(B->chi);
    free(B->zero);
}

/* The first comparison (the chain's inline build against engine.c), undamped and damped, and a belt:
 * the chain's box LCP on the velocities relative to the belts, in both builds; a held block rides
 * its belt. */
static void test_chain(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    const double h = 4.0 * DFO_PI / 800.0;
    double F2[NCHAIN];
    for (size_t i = 0; i < NCHAIN; i++) F2[i] = (i == 0) ? 0.3 : (i == NCHAIN - 1) ? -0.2 : 0.0;
    const eng_inputs in1 = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    const eng_inputs in2 = {F2, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    for (int damped = 0; damped < 2; damped++) {
        test_chain_model B;
        test_chain_make(&B, NCHAIN, 0.1, 0.0, damped ? 0.05 : 0.0);
        for (int scheme = DFO_SCHEME_PAPER; scheme <= DFO_SCHEME_LOCATED; scheme++) {
            check_context(T, "chain of %d blocks%s, %s: the inline build against engine.c", NCHAIN,
                          damped ? " with dampers" : "", names[scheme]);
            const eng_setup Sg = test_chain_setup(T, &B, scheme, h), Si = test_chain_setup(T, &B, scheme, h);
            CHECK((Sg.ops.apply_C != NULL) == damped);
            eng_state sg, si;
            switch_log Lg, Li;
            eng_status stg, sti;
            eng *Eg = run(&Sg, &GENERIC, &in1, &in2, 20.0, 0.37, 40.0, &sg, &Lg, &stg);
            eng *Ei = run(&Si, &CHAIN, &in1, &in2, 20.0, 0.37, 40.0, &si, &Li, &sti);
            printf("  chain n = %d%s %-10s 40 s: %ld switches, x_1 %.17g / %.17g\n", NCHAIN, damped ? " damped" : "",
                   names[scheme], Lg.count, sg.X[0], si.X[0]);
            CHECK(stg == ENG_OK);
            CHECK(sti == ENG_OK);
            CHECK(Lg.count >= 5 * NCHAIN);
            CHECK(same_bits(&sg, &si, &Lg, &Li));
            run_free(Eg, &sg);
            run_free(Ei, &si);
            test_chain_release(&B);
        }
        test_chain_free(&B);
    }
    /* a belt under block 3, its speed changed at 20 s: the same bits in both builds, and block 3 held
     * moves with its belt (its velocity the belt's to the bit) */
    check_context(T, "chain of %d blocks with a belt: the inline build against engine.c, the block held on it",
                  NCHAIN);
    test_chain_model B;
    test_chain_make(&B, NCHAIN, 0.1, 0.0, 0.0);
    B.N[3] = 3.0; /* (block 3 held on its belt for stretches) */
    double vb1[NCHAIN] = {0.0}, vb2[NCHAIN] = {0.0};
    vb1[3] = 0.1;
    vb2[3] = -0.05;
    const eng_inputs inb1 = {NULL, NULL, vb1, {NULL, NULL}, {NULL, NULL}, 0.0};
    const eng_inputs inb2 = {NULL, NULL, vb2, {NULL, NULL}, {NULL, NULL}, 0.0};
    const eng_setup Sg = test_chain_setup(T, &B, DFO_SCHEME_LOCATED, h);
    const eng_setup Si = test_chain_setup(T, &B, DFO_SCHEME_LOCATED, h);
    eng_state sg, si, s0;
    switch_log Lg, Li, L0;
    eng_status stg, sti, st0;
    eng *Eg = run(&Sg, &GENERIC, &inb1, &inb2, 20.0, 0.37, 40.0, &sg, &Lg, &stg);
    eng *Ei = run(&Si, &CHAIN, &inb1, &inb2, 20.0, 0.37, 40.0, &si, &Li, &sti);
    eng *E0 = run(&Si, &CHAIN, &in1, &in1, 100.0, 0.37, 40.0, &s0, &L0, &st0); /* no belt */
    printf("  chain n = %d with a belt: %ld switches (without: %ld), x_4 %.17g (without: %.17g)\n", NCHAIN, Lg.count,
           L0.count, sg.X[3], s0.X[3]);
    CHECK(stg == ENG_OK && sti == ENG_OK && st0 == ENG_OK);
    CHECK(Lg.count >= 5 * NCHAIN);
    CHECK(same_bits(&sg, &si, &Lg, &Li));
    CHECK(fabs(sg.X[3] - s0.X[3]) > 1e-3); /* the belt is not ignored */
    run_free(Eg, &sg);
    run_free(Ei, &si);
    run_free(E0, &s0);
    /* block 3 held on its belt at 0.1: from rest it slides against its belt, sticks to it, is pulled
     * back by its springs, and again */
    eng *E = eng_create(&Sg, &ALLOC, NULL);
    eng_state s;
    if (!E || !eng_state_init(E, &s, 0)) { fprintf(stderr, "test_engine_step: out of memory\n"); exit(1); }
    chain_eng_start(E, &inb1, 0.0, B.zero, B.zero, &s);
    int held = 0, riding = 0;
    eng_status st = ENG_OK;
    for (int k = 1; k <= 100 && st == ENG_OK; k++) {
        st = chain_eng_advance(E, &inb1, &s, 0.37 * k, NULL);
        if (s.mode[3] == 0) {
            held++;
            riding += s.V[3] == 0.1;
        }
    }
    printf("  chain n = %d, block 4 on a belt at 0.1: held at %d of 100 points, at the belt's speed at %d\n", NCHAIN,
           held, riding);
    CHECK(st == ENG_OK);
    CHECK(held >= 10);
    CHECK(riding == held);
    run_free(E, &s);
    test_chain_free(&B);
}

/* ---- the chain's sparse-structure operators (eng_sparse): held solves, the fused step, spans ---- */

static long held_steps;   /* calls of the fused step (counting_step_held) */
static long spans_given;  /* span calls that gave spans (counting_span) */

static int counting_step_held(void *ctx, const eng_held_step *F, eng_state *s)
{
    held_steps++;
    return chain_op_step_held(ctx, F, s);
}

static size_t counting_span(void *ctx, const int *cand, int *dof_lab, int *ct_lab, size_t *dof_rng, size_t *ct_rng)
{
    const size_t ns = chain_op_span(ctx, cand, dof_lab, ct_lab, dof_rng, ct_rng);
    if (ns > 0) spans_given++;
    return ns;
}

/* The chain's spans with every contact range emptied: no candidate lies in a span (the engine then steps
 * the whole structure) */
static size_t spans_off_range(void *ctx, const int *cand, int *dof_lab, int *ct_lab, size_t *dof_rng, size_t *ct_rng)
{
    const size_t ns = chain_op_span(ctx, cand, dof_lab, ct_lab, dof_rng, ct_rng);
    for (size_t k = 0; k < ns; k++) ct_rng[2 * k + 1] = ct_rng[2 * k];
    return ns;
}

/* The chain's spans, the first one's DOF range past the structure's end (a model's error) */
static size_t spans_bad_range(void *ctx, const int *cand, int *dof_lab, int *ct_lab, size_t *dof_rng, size_t *ct_rng)
{
    const size_t ns = chain_op_span(ctx, cand, dof_lab, ct_lab, dof_rng, ct_rng);
    if (ns > 0) dof_rng[1] = ((const chain_eng_ops *)ctx)->n + 1;
    return ns;
}

/* The engine on a chain of B in scheme with the chain's sparse operators up to a level: 0 none, 1
 * held_basis only, 2 and the fused step, 3 and the closed-form breakaways (the chain's whole one,
 * ops.breakaway, and its contacts'), 4 and spans (counted by counting_span); h = T / steps. */
static eng_setup big_setup(checks *T, test_chain_model *B, int scheme, int sparse, double steps)
{
    eng_setup S = test_chain_setup(T, B, scheme, 4.0 * DFO_PI / steps);
    CHECK(S.sparse && S.sparse->held_basis && S.sparse->step_held && S.sparse->contact_breakaway && S.sparse->span);
    B->sp = *S.sparse;
    if (sparse < 2) B->sp.step_held = NULL;
    if (sparse < 3) {
        B->sp.contact_breakaway = NULL;
        S.ops.breakaway = NULL;
    }
    if (sparse < 4) {
        B->sp.span_max = 0;
        B->sp.span = NULL;
        B->sp.span_bind = NULL;
    } else {
        B->sp.span = counting_span;
    }
    S.sparse = sparse ? &B->sp : NULL;
    return S;
}

/* The reach of the spans of the latest big_setup's chain. */
static size_t big_reach(const test_chain_model *B) { return B->M[B->nm - 1]->ops.w; }

/* From rest to t_end in communication steps dt, without hooks (spans need none). */
static eng *run_plain(const eng_setup *S, const entry *X, const double *zero, double dt, double t_end, eng_state *s,
                      eng_status *status)
{
    eng *E = eng_create(S, &ALLOC, NULL);
    if (!E || !eng_state_init(E, s, 0)) { fprintf(stderr, "test_engine_step: out of memory\n"); exit(1); }
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    X->start(E, &in, 0.0, zero, zero, s);
    *status = ENG_OK;
    for (int k = 1; (double)k * dt <= t_end && *status == ENG_OK; k++) *status = X->advance(E, &in, s, (double)k * dt, NULL);
    return E;
}

static double max_rel_diff(const double *a, const double *b, size_t n)
{
    double d = 0.0, m = 0.0;
    for (size_t i = 0; i < n; i++) { d = fmax(d, fabs(a[i] - b[i])); m = fmax(m, fabs(b[i])); }
    return d / m;
}

static void test_chain_sparse(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    test_chain_model B;
    test_chain_make(&B, NCHAIN, 0.0, 0.4, 0.0); /* bench_engine's chain, its normal forces varied along it */
    for (int scheme = DFO_SCHEME_PAPER; scheme <= DFO_SCHEME_LOCATED; scheme++) {
        check_context(T, "chain of %d blocks, %s: the held solves through the box LCP, the fused step", NCHAIN,
                      names[scheme]);
        eng_state s[5];
        eng_status st[5];
        eng *E[5];
        for (int v = 0; v < 4; v++) {
            const eng_setup S = big_setup(T, &B, scheme, v, 800.0);
            E[v] = run_plain(&S, &GENERIC, B.zero, 0.37, 40.0, &s[v], &st[v]);
        }
        const eng_setup S = big_setup(T, &B, scheme, 3, 800.0);
        E[4] = run_plain(&S, &CHAIN, B.zero, 0.37, 40.0, &s[4], &st[4]);
        const double d = max_rel_diff(s[1].X, s[0].X, NCHAIN), db = max_rel_diff(s[3].X, s[2].X, NCHAIN);
        printf("  chain n = %d %-10s held solves by the box LCP against the dense: %.2e, %lld / %lld switches; "
               "closed-form breakaways against root finding: %.2e, %lld switches\n",
               NCHAIN, names[scheme], d, s[1].switches, s[0].switches, db, s[3].switches);
        for (int v = 0; v < 5; v++) CHECK(st[v] == ENG_OK);
        CHECK(s[0].switches >= 5 * NCHAIN);
        CHECK(s[1].switches == s[0].switches);
        CHECK(d < 1e-11);
        const switch_log none = {0, 0.0, 0};
        CHECK(same_bits(&s[2], &s[1], &none, &none)); /* the fused step: the general path's bits */
        CHECK(s[3].switches == s[2].switches);
        CHECK(db < 1e-11);
        if (scheme != DFO_SCHEME_LOCATED) CHECK(same_bits(&s[3], &s[2], &none, &none)); /* (located only) */
        CHECK(same_bits(&s[4], &s[3], &none, &none)); /* inline: engine.c's bits */
        for (int v = 0; v < 5; v++) {
            eng_state_free(E[v], &s[v]);
            eng_destroy(E[v]);
        }
        test_chain_release(&B);
    }
    test_chain_free(&B);
    /* spans: a chain longer than two reaches, located; against the whole structure's steps at h and h / 2 */
    const size_t n = 24;
    test_chain_make(&B, n, 0.0, 0.4, 0.0);
    double dh[2] = {0.0, 0.0};
    for (int r = 0; r < 2; r++) {
        const double steps = 800.0 * (double)(1 << r);
        check_context(T, "chain of %zu blocks, located, h = T / %.0f: spans against the whole structure", n, steps);
        eng_state s[3];
        eng_status st[3];
        eng *E[3];
        eng_setup S = big_setup(T, &B, DFO_SCHEME_LOCATED, 3, steps);
        E[0] = run_plain(&S, &GENERIC, B.zero, 0.37, 40.0, &s[0], &st[0]);
        spans_given = 0;
        S = big_setup(T, &B, DFO_SCHEME_LOCATED, 4, steps);
        E[1] = run_plain(&S, &GENERIC, B.zero, 0.37, 40.0, &s[1], &st[1]);
        const long spans = spans_given;
        const size_t reach = big_reach(&B);
        E[2] = run_plain(&S, &CHAIN, B.zero, 0.37, 40.0, &s[2], &st[2]);
        dh[r] = max_rel_diff(s[1].X, s[0].X, n);
        printf("  chain n = %zu located T/%.0f: reach %zu, %ld steps by spans, %lld / %lld switches, spans against "
               "whole %.2e\n", n, steps, reach, spans, s[1].switches, s[0].switches, dh[r]);
        for (int v = 0; v < 3; v++) CHECK(st[v] == ENG_OK);
        CHECK(2 * reach + 3 < n);
        CHECK(spans > 50);
        CHECK(labs((long)(s[1].switches - s[0].switches)) <= s[0].switches / 50);
        CHECK(dh[r] < 1e-5);
        const switch_log none = {0, 0.0, 0};
        CHECK(same_bits(&s[2], &s[1], &none, &none));
        for (int v = 0; v < 3; v++) {
            eng_state_free(E[v], &s[v]);
            eng_destroy(E[v]);
        }
        test_chain_release(&B);
    }
    check_context(T, "chain of %zu blocks, located: spans against the whole structure, second order", n);
    printf("  spans against whole: %.2e, %.2e (ratio %.2f)\n", dh[0], dh[1], dh[0] / dh[1]);
    CHECK(dh[0] / dh[1] > 3.0);
    /* the spans' ranges: a candidate outside them, the whole structure stepped (the bits of no spans);
     * a range past the structure, an error */
    check_context(T, "chain of %zu blocks, located: spans whose ranges miss the candidates, or overrun", n);
    {
        eng_state s3[3];
        eng_status st3[3];
        eng *E3[3];
        eng_setup S = big_setup(T, &B, DFO_SCHEME_LOCATED, 3, 800.0);
        E3[0] = run_plain(&S, &GENERIC, B.zero, 0.37, 40.0, &s3[0], &st3[0]);
        S = big_setup(T, &B, DFO_SCHEME_LOCATED, 4, 800.0);
        B.sp.span = spans_off_range;
        E3[1] = run_plain(&S, &GENERIC, B.zero, 0.37, 40.0, &s3[1], &st3[1]);
        B.sp.span = spans_bad_range;
        E3[2] = run_plain(&S, &GENERIC, B.zero, 0.37, 40.0, &s3[2], &st3[2]);
        printf("  spans off their candidates: %lld / %lld switches; overrun: status %d at t = %g\n", s3[1].switches,
               s3[0].switches, (int)st3[2], s3[2].t);
        const switch_log none = {0, 0.0, 0};
        CHECK(st3[0] == ENG_OK && st3[1] == ENG_OK);
        CHECK(s3[0].switches > 50);
        CHECK(same_bits(&s3[1], &s3[0], &none, &none));
        CHECK(st3[2] == ENG_ERR_BAD_INPUT);
        CHECK(s3[2].t < 40.0);
        for (int v = 0; v < 3; v++) {
            eng_state_free(E3[v], &s3[v]);
            eng_destroy(E3[v]);
        }
        test_chain_release(&B);
    }
    test_chain_free(&B);
    /* the stuck fast path from the contacts' closed-form breakaways: a chain that sticks whole for
     * stretches (one block slips near its excitation's peaks, the others hold), on against off */
    check_context(T, "chain of %d blocks stuck for stretches: the stuck fast path from the contacts' breakaways",
                  NCHAIN);
    test_chain_make(&B, NCHAIN, 0.0, 0.4, 0.0);
    for (size_t i = 0; i < NCHAIN; i++) B.N[i] = (i == 0) ? 1.99 : 2.1; /* block 0 slips near its peaks */
    eng_state s2[2];
    eng_status st2[2];
    eng *E2[2];
    long calls[2];
    for (int v = 0; v < 2; v++) {
        eng_setup S = big_setup(T, &B, DFO_SCHEME_LOCATED, 3, 800.0);
        B.sp.step_held = counting_step_held;
        S.fast_paths = v;
        held_steps = 0;
        E2[v] = run_plain(&S, &GENERIC, B.zero, 0.37, 40.0, &s2[v], &st2[v]);
        calls[v] = held_steps;
    }
    printf("  stuck fast path: %ld / %ld fused steps taken, %lld switches\n", calls[1], calls[0], s2[0].switches);
    const switch_log none = {0, 0.0, 0};
    CHECK(st2[0] == ENG_OK && st2[1] == ENG_OK);
    CHECK(s2[0].switches >= 2 * NCHAIN);
    CHECK(calls[1] < calls[0] - calls[0] / 10); /* stuck stretches skipped */
    CHECK(same_bits(&s2[1], &s2[0], &none, &none));
    for (int v = 0; v < 2; v++) {
        eng_state_free(E2[v], &s2[v]);
        eng_destroy(E2[v]);
    }
    test_chain_free(&B);
}

/* ---- the rest rule's one-round releases (eng_setup.mass_diagonal) -------------------------------- */

/* The rest rule's reports of a run: how many of each stage, and a fingerprint of the releases'
 * order, contacts, modes and excesses. */
typedef struct {
    long open, release, settled;
    unsigned long long order;
    double excess_sum;
} rest_log;

static void log_rest(void *ctx, double t, int stage, size_t contact, int mode, double excess, const int *rest,
                     const int *modes)
{
    rest_log *L = ctx;
    (void)t; (void)rest; (void)modes;
    if (stage == ENG_REST_OPEN) L->open++;
    if (stage == ENG_REST_SETTLED) L->settled++;
    if (stage != ENG_REST_RELEASE) return;
    L->release++;
    L->order = L->order * 1000003ull + (unsigned long long)(contact * 4 + (size_t)(mode + 1));
    L->excess_sum += excess * (double)L->release;
}

/* A chain of n blocks started at rest from x0 (springs stretched, so that many blocks start beyond
 * their limits, with ties among them), run to 30 s in scheme: its final state, switches and the
 * rest rule's reports, with the model's mass_diagonal as given. */
static eng *run_rest(const eng_setup *S0, int mass_diagonal, const double *x0, const double *v0, eng_state *s,
                     switch_log *L, rest_log *R, eng_status *st)
{
    eng_setup S = *S0;
    S.mass_diagonal = mass_diagonal;
    S.on_rest = log_rest;
    S.rest_ctx = R;
    memset(R, 0, sizeof *R);
    memset(L, 0, sizeof *L);
    eng *E = eng_create(&S, &ALLOC, NULL);
    if (!E || !eng_state_init(E, s, 0)) { fprintf(stderr, "test_engine_step: out of memory\n"); exit(1); }
    const eng_hooks hk = {on_switch, L, NULL, 0, 0, 1};
    static const eng_inputs none = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    chain_eng_start(E, &none, 0.0, x0, v0, s);
    *st = ENG_OK;
    for (int k = 1; k <= 80 && *st == ENG_OK; k++) *st = chain_eng_advance(E, &none, s, 0.37 * k, &hk);
    return E;
}

/* The rest rule on contacts that hold apart (the chain: M diagonal, contact i on block i) releases
 * all the contacts beyond their limits in one round: the same modes, states and reports, bit for
 * bit, as one release a round (mass_diagonal 0), in the three schemes; the start decides many
 * contacts at once (the case that made the rounds O(n^2): 4096 blocks took 0.22 s to initialise). */
static void test_rest_apart(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    const size_t n = 96;
    const double h = 4.0 * DFO_PI / 800.0;
    test_chain_model B;
    test_chain_make(&B, n, 0.0, 0.0, 0.02);
    double *x0 = dvec(n), *v0 = dvec(n);
    for (size_t i = 0; i < n; i++) { /* a pattern of period 5 in blocks alike: many ties in excess */
        x0[i] = 0.9 * (double)((i * 7) % 5) - 1.7;
        B.phi[i] = 0.0;
    }
    for (int scheme = DFO_SCHEME_PAPER; scheme <= DFO_SCHEME_LOCATED; scheme++) {
        check_context(T, "chain of %zu blocks from stretched springs, %s: the rest rule's one round against one "
                         "release a round", n, names[scheme]);
        const eng_setup S = test_chain_setup(T, &B, scheme, h);
        CHECK(S.mass_diagonal == 1);
        eng_state sa, sb;
        switch_log La, Lb;
        rest_log Ra, Rb;
        eng_status sta, stb;
        eng *Ea = run_rest(&S, 1, x0, v0, &sa, &La, &Ra, &sta);
        eng *Eb = run_rest(&S, 0, x0, v0, &sb, &Lb, &Rb, &stb);
        printf("  chain n = %zu %-10s from stretched springs: %ld rest decisions, %ld releases, %ld switches\n", n,
               names[scheme], Ra.open, Ra.release, La.count);
        CHECK(sta == ENG_OK && stb == ENG_OK);
        CHECK(Ra.open >= 1 && Ra.release >= 20); /* (many released together at the start) */
        CHECK(Ra.open == Rb.open && Ra.release == Rb.release && Ra.settled == Rb.settled);
        CHECK(Ra.order == Rb.order);
        CHECK(!memcmp(&Ra.excess_sum, &Rb.excess_sum, sizeof(double)));
        CHECK(same_bits(&sa, &sb, &La, &Lb));
        run_free(Ea, &sa);
        run_free(Eb, &sb);
        test_chain_release(&B);
    }
    free(x0);
    free(v0);
    test_chain_free(&B);
}

int main(void)
{
    checks C = {0, 0, NULL, {0}};
    checks *T = &C;
    test_block(T);
    test_stuck_fast_path(T);
    test_fused_vs_general(T);
    test_observables_in_run(T);
    test_vs_stepper(T);
    test_chain(T);
    test_chain_sparse(T);
    test_rest_apart(T);
    return checks_done(T, "test_engine_step");
}
