/* A chain of n blocks with dry friction (method.md section 9), integrated by the Bossak-Newmark
 * scheme of the oscillator with the friction posed as the 2n LCP of the chain.
 *
 *     wall -k[0],c[0]- m[0] -k[1],c[1]- m[1] - ... - m[n-1] -k_end,c_end- wall
 *     (and each block i tied to the ground by k_site[i], c_site[i], 0 unless set)
 *     M x'' + C x' + K x = P(t) + F_ext + F,     P_i = P0_i cos(omega t + phi_i),
 *     F_i Coulomb on block i: |F_i| <= max(mu_s_i, mu_k_i) N_i stuck, -/+ mu_k_i N_i sliding,
 *     mu_k_i = chi_i mu_s_i, N_i = max(N_i + N_ext_i, 0); or (friction_law = stribeck) sliding
 *     -/+ N_i mu_i(|v_i - vb_i|), mu_i(u) = mu_k_i + (mu_s_i - mu_k_i) exp(-(u / v_s_i)^delta_i).
 *
 * k[i], c[i] is the spring and damper on the left of block i (k[0], c[0] tie block 0 to the left
 * wall); k_end = c_end = 0 is a free right end. Springs are relaxed at x = 0.
 *
 * The chain is a model of the friction engine (fmu_src/engine): contact i on block i (w_i = e_i),
 * the engine's Bossak schemes (located, the default; paper; consistent) over the chain's operators
 * (chain_engine_ops.h). One step: M_hat V1 = p_hat + F1 with M_hat = (1 - a) M / (g h) + C +
 * (b h / g) K (tridiagonal, symmetric positive definite); the friction is the box form of the 2n
 * LCP, solved from the basis named by the blocks' modes (stuck blocks held, sliding ones with their
 * kinetic force): one tridiagonal solve, O(n), with the factorisation kept for the held pattern;
 * where that basis is infeasible the located scheme places each switch inside its step in a span
 * of nearby blocks (the engine's spans: O(span) per switch), the paper and consistent schemes pivot
 * (lcp_box). engine.h says what each scheme does.
 *
 * Memory: O(n), every array through the caller's allocate/free callbacks (the engine's too). The
 * state is the engine's (chain_state_copy). Plain C, no FMI types. */
#ifndef DFO_CHAIN_H
#define DFO_CHAIN_H

#include "engine.h"

#include <stddef.h>

/* Allocation callbacks (zero-filled memory, as FMI's calloc); env is passed through. */
typedef struct {
    void *(*allocate)(void *env, size_t nobj, size_t size);
    void (*release)(void *env, void *obj);
    void *env;
} chain_alloc;

/* Everything set before a run. Arrays of length n (owned by the caller; chain_create copies them). */
typedef struct {
    size_t n;
    const double *m, *k, *c, *P0, *phi, *N, *mu_s, *chi, *x0, *v0;
    double k_end, c_end, omega, h, alpha;
    int scheme;  /* dfo_scheme: 1 paper, 2 consistent, 3 located */
    int account_energy;  /* keep the energy accounts of chain_state (costs O(n) per step) */
    /* springs and dampers from each block to the ground frame (NULL: none; the Burridge-Knopoff
     * model's site springs), added to K's and C's diagonals */
    const double *k_site, *c_site;
    /* the sliding friction law (friction.h): 0 or DFO_LAW_COULOMB (1) mu_k; DFO_LAW_STRIBECK (2)
     * mu(u) = mu_k + (mu_s - mu_k) exp(-(u / v_s)^delta) at the speed u relative to the belt, with
     * v_s[i] > 0 and delta[i] >= 1 per block (arrays of n; NULL: 0.01 and 1); located scheme only */
    int friction_law;
    const double *v_s, *delta;
} chain_params;

/* Inputs held over a communication step: arrays of length n, or NULL when never set. */
typedef struct {
    const double *F_ext, *N_ext;
} chain_inputs;

/* Input derivatives over one chain_advance_ramped call: input u of block i then varies as
 * u(t) = u + u1 (t - t_ref) + u2 (t - t_ref)^2 / 2, u1 = dF_ext[0][i] (dN_ext[0] for N_ext),
 * u2 = dF_ext[1][i]; a NULL array is 0. */
typedef struct {
    const double *dF_ext[2], *dN_ext[2];
    double t_ref;
} chain_ramp;

typedef enum {
    CHAIN_OK = 0,
    CHAIN_ERR_LCP = 1,          /* the 2n LCP could not be solved */
    CHAIN_ERR_NO_PROGRESS = 2,  /* too many switches inside one internal step */
    CHAIN_ERR_NONFINITE = 3,    /* the state overflowed */
    CHAIN_ERR_RESOLUTION = 4,   /* a step would not advance time */
    CHAIN_SWITCHED = 5,         /* stopped at the first switch (stop_at_switch): s->t is its time */
    CHAIN_ERR_FRICTION = 6      /* the speed-dependent (Stribeck) friction's implicit solve did not converge */
} chain_status;

typedef struct chain_model chain_model;

/* The state: the friction engine's (engine.h's eng_state, contact i on block i: nc = n): time, grid
 * point, X, V, A, hA, F, mode, t_stick per block, the energy accounts since the start (kept with
 * chain_params.account_energy: the work of the applied forces and of friction, the dissipation in
 * the dampers), the counters (internal steps, steps whose warm basis was infeasible, switches,
 * solves) and the excitation's grid cache. Copy with chain_state_copy. */
typedef eng_state chain_state;

/* Check the parameters; NULL when valid, else a sentence naming the element, e.g.
 * "invalid value -1 for m[3] (valid: > 0)" (1-based indices, as the FMU's names), written to buf. */
const char *chain_check_params(const chain_params *p, char *buf, size_t len);

/* Create the model (copies the parameters, allocates the O(n) workspace); NULL on a failed
 * allocation or invalid parameters (then *err, if not NULL, points to the reason). */
chain_model *chain_create(const chain_params *p, const chain_alloc *al, const char **err);
void chain_destroy(chain_model *M);
/* The shortest period (s) of the dynamics, as the oscillator's dfo_shortest_period: the shortest
 * of 2 pi / sqrt(max eig M^-1 K), 2 pi / |omega| and 2 pi / max eig M^-1 C, the eigenvalues bounded
 * by Gershgorin (so it errs short); +inf when there is none. */
double chain_shortest_period(const chain_model *M);
/* The same from the parameters (before a model exists). */
double chain_shortest_period_of(const chain_params *p);
/* The internal step a run uses: p->h when > 0, else derived from the dynamics as the oscillator's
 * (1/DFO_STEPS_PER_PERIOD of the shortest period; DFO_STEP_FALLBACK without one). */
double chain_step_size(const chain_params *p);
/* The model's internal step. */
double chain_step(const chain_model *M);
size_t chain_size(const chain_model *M);

/* State arrays through the model's callbacks; 0 on failure. */
int chain_state_init(const chain_model *M, chain_state *s);
void chain_state_free(const chain_model *M, chain_state *s);
/* dst (initialised for the same n) := src, arrays included. */
void chain_state_copy(chain_state *dst, const chain_state *src);

/* Consistent start-up at t0 from x0, v0: a block at rest with its net force inside its breakaway
 * limit starts stuck. */
void chain_start(chain_model *M, const chain_inputs *in, double t0, chain_state *s);

/* Called at every change of a block's mode, with its time, index and position. */
typedef void (*chain_switch_fn)(void *ctx, double t, size_t block, double x, int from_mode, int to_mode);

/* Advance to t_target with the inputs held. With stop_at_switch, return CHAIN_SWITCHED at the first
 * switch (located scheme: at its time; other schemes: at the end of the internal step holding it),
 * the state complete there; the next call goes on from there. */
chain_status chain_advance(chain_model *M, const chain_inputs *in, chain_state *s, double t_target,
                           int stop_at_switch, chain_switch_fn on_switch, void *ctx);
/* The same with the inputs varying as the polynomials of ramp (NULL, or every array NULL: held, the
 * bits of chain_advance). Each internal step (and, in the located scheme, each trial of a switch's
 * location) takes the inputs at its end; the fast paths do not apply. */
chain_status chain_advance_ramped(chain_model *M, const chain_inputs *in, const chain_ramp *ramp, chain_state *s,
                                  double t_target, int stop_at_switch, chain_switch_fn on_switch, void *ctx);
/* Belts: block i's friction acts on v_i - vb[i] (vb: n speeds held from ramp->t_ref, or s->t without a
 * ramp; NULL: chain_advance_ramped itself). Stuck means v_i = vb[i]: the block rides its belt while
 * the force that holds it is within its limit. Stepped in the frame y = x - vb (t - t_ref) (the
 * ramp machinery: no fast paths), x and v given back. The energy accounts are the moving frame's. */
chain_status chain_advance_belt(chain_model *M, const chain_inputs *in, const chain_ramp *ramp, const double *vb,
                                chain_state *s, double t_target, int stop_at_switch, chain_switch_fn on_switch,
                                void *ctx);
/* chain_start with belts vb (NULL: chain_start): a block with friction and v0 = vb starts stuck while
 * its net force is within its limit. */
void chain_start_belt(chain_model *M, const chain_inputs *in, const double *vb, double t0, chain_state *s);
/* Belt speeds changed at s->t (NULL: 0): a stuck block keeps its velocity and slides the way
 * v - vb_new points; a sliding block whose v - vb_new changed sign slides that way, one that the new
 * belt meets (v = vb_new) takes the rest rule; the new mode set restarts consistently. Switches are
 * reported through on_switch. Inputs in: the current ones. */
void chain_new_belt(chain_model *M, const chain_inputs *in, const double *vb_old, const double *vb_new, chain_state *s,
                    chain_switch_fn on_switch, void *ctx);
/* Input k (0 F_ext, 1 N_ext) of block i at time t under the ramp (NULL: held), and its rate. */
void chain_ramp_value(const chain_inputs *in, const chain_ramp *ramp, int k, size_t i, double t, double *value,
                      double *rate);

/* Inputs changed at the communication point s->t (from old_in to new_in, held over the next call):
 * each sliding block's A takes the jump of its physical acceleration, (dF_ext_i - mode_i
 * d(mu_k N)_i) / m_i, and its F the new kinetic force, so that the step from s starts on the right
 * limit (else every input change costs a first-order error); stuck blocks are decided by the next
 * step. As the oscillator's dfo_new_inputs. */
void chain_new_inputs(const chain_model *M, const chain_inputs *old_in, const chain_inputs *new_in, chain_state *s);
/* The same with the new inputs varying as ramp's polynomials (taken at s->t; NULL: held), the state
 * on the belts vb (n speeds, NULL: none; the Stribeck law's relative speed). */
void chain_new_inputs_ramped(const chain_model *M, const chain_inputs *old_in, const chain_inputs *new_in,
                             const chain_ramp *ramp, const double *vb, chain_state *s);

/* Physical accelerations (0 for stuck blocks) into a (n values), the state on the belts vb (n speeds,
 * NULL: none; the Stribeck law's relative speed). */
void chain_accelerations(chain_model *M, const chain_inputs *in, const double *vb, const chain_state *s, double *a);

/* Mechanical energy: kinetic + springs (J). */
double chain_energy(const chain_model *M, const chain_state *s);

/* The box form of the chain's 2n LCP for a step of length h from state s (stuck blocks' limit
 * mu_b N, sliding ones' mu_k N), for tests: fills the tridiagonal M_hat (diag d[n], off-diagonal
 * e[n-1]), q[n] = -p_hat and the limits l[n], the problem lcp_box (numerics/lcp.h) solves:
 * F = M_hat V + q, V_i > 0 => F_i = -l_i, V_i < 0 => F_i = l_i, |F_i| <= l_i. */
void chain_step_problem(chain_model *M, const chain_inputs *in, const chain_state *s, double h,
                        double *d, double *e, double *q, double *l);

const char *chain_status_text(chain_status st);

/* State arrays for n blocks through al without a model (the same layout as chain_state_init; an FMU
 * state of the chain FMU); 0 on failure. Release with chain_state_release and the same al. */
int chain_state_alloc(const chain_alloc *al, size_t n, chain_state *s);
void chain_state_release(const chain_alloc *al, chain_state *s);

#endif
