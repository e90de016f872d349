/* The exact scheme on a moving belt: a call's start after the belt changed, and the call's phases
 * (with a spring: the spring phase's loop in the belt's terms; without one: the free mass in the
 * belt's frame). See exact_belt.h and docs/belt.md. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "exact_belt.h"
#include "exact_free.h"
#include "exact_poly.h"
#include "exact_spring.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

/* A call's start after a change of the belt at this communication point (the block keeps its velocity):
 * a stuck block whose velocity is not the belt's slides in the direction of v - vb, and a sliding one
 * whose v - vb now points against its mode (beyond the rounding of the last call's end, at which a
 * slide may end a few ulps past its stop) slides the other way: a switch. */
void dfo_exact_belt_start(const dfo_model *M, const dfo_inputs *u, double vb, dfo_state *s, dfo_switch_fn on_switch,
                          void *switch_ctx)
{
    int to = s->mode;
    if (s->mode == 0) {
        if (s->V != vb) to = dfo_sign(s->V - vb);
    } else {
        dfo_loads L;
        dfo_loads_init(&L, M, u);
        const double k = M->p.k, w0 = sqrt(k / M->p.m);
        const double len = (k > 0.0) ? fabs(s->X) + (M->P_amp + fabs(L.F_ext) + L.Fb) / k : 0.0;
        const double harm = (k == 0.0 && M->p.omega > 0.0) ? M->P_amp / (M->p.m * M->p.omega) : 0.0;
        const double thr = 4.0 * DFO_EXACT_ROUND * (fabs(s->V) + fabs(vb) + w0 * len + harm);
        if (s->mode * (s->V - vb) < -thr) to = -s->mode;
    }
    if (to == s->mode) return;
    if (on_switch) on_switch(switch_ctx, s->t, s->X, s->mode, to);
    s->mode = to;
    if (M->p.observe && s->t > M->p.t_obs_start && s->t <= M->p.t_obs_stop) s->transitions++;
}

/* A call without a spring on a belt (free_belt): the switch reports with x from the belt's frame, and
 * (observe) the extremes of x, phase by phase, from the switches: a stuck block rides on the belt (x
 * linear), a slide may turn inside (dfo_exact_free_slide_extremes). */
typedef struct {
    dfo_switch_fn fn;
    void *ctx;
    double vb, t0;
    const dfo_model *M;
    const dfo_inputs *u;      /* the inputs (physical frame) */
    const dfo_input_poly *q;  /* their polynomials (NULL: held) */
    int observe, have;
    double ta, xa, va;   /* the current phase's start (physical frame) */
    int mode;
    double lo, hi;       /* the extremes of x in the window so far (have) */
} belt_free;

static void belt_free_sample(belt_free *b, double x)
{
    if (!b->have) b->lo = b->hi = x;
    b->have = 1;
    b->lo = fmin(b->lo, x);
    b->hi = fmax(b->hi, x);
}

/* The phase from b's start to tb (physical x there: xb) in b->mode, into the extremes. */
static void belt_free_phase(belt_free *b, double tb, double xb)
{
    const dfo_params *p = &b->M->p;
    const double w0 = p->t_obs_start, w1 = p->t_obs_stop, ta = b->ta;
    if (!b->observe || tb < w0 || ta > w1) return;
    const double t0 = fmax(ta, w0), t1 = fmin(tb, w1);
    if (b->mode == 0) {
        belt_free_sample(b, (t0 == ta) ? b->xa : b->xa + b->vb * (t0 - ta));
        belt_free_sample(b, (t1 == tb) ? xb : b->xa + b->vb * (t1 - ta));
        return;
    }
    if (t0 == ta) belt_free_sample(b, b->xa);
    if (t1 == tb) belt_free_sample(b, xb);
    double lo, hi, Xe, Ve;
    if (b->q == NULL) {
        dfo_exact_free_slide_extremes(b->M, b->u, NULL, ta, b->xa, b->va, b->mode, t0, t1, t1, &lo, &hi, &Xe, &Ve);
        belt_free_sample(b, lo);
        belt_free_sample(b, hi);
        return;
    }
    /* polynomial inputs: the pieces between the zeros of N + N_ext(t), the motion carried over each */
    const dfo_input_poly *q = b->q;
    double n[3], z[2], poly[7] = {q->t0, dfo_external_force(b->M, b->u), q->F[0], q->F[1], 0.0, 0.0, 0.0};
    const int nz = dfo_exact_normal_zeros(b->M, b->u, q, ta, tb, n, z);
    double X = b->xa, V = b->va;
    for (int i = 0; i <= nz; i++) {
        const double a = (i == 0) ? ta : q->t0 + z[i - 1], e = (i == nz) ? tb : q->t0 + z[i];
        dfo_exact_piece_normal(n, 0.5 * (a + e) - q->t0, poly + 4);
        dfo_exact_free_slide_extremes(b->M, b->u, poly, a, X, V, b->mode, fmax(a, t0), fmin(e, t1), e, &lo, &hi, &X,
                                      &V);
        if (fmin(e, t1) >= fmax(a, t0)) {
            belt_free_sample(b, lo);
            belt_free_sample(b, hi);
        }
    }
}

static void belt_free_switch(void *ctx, double t, double x, int from_mode, int to_mode)
{
    belt_free *b = (belt_free *)ctx;
    const double xp = x + b->vb * (t - b->t0);
    if (b->fn) b->fn(b->ctx, t, xp, from_mode, to_mode);
    belt_free_phase(b, t, xp);
    b->ta = t;
    b->xa = xp;
    b->va = b->vb; /* every event is at v = vb */
    b->mode = to_mode;
}

/* No spring on a belt: in the belt's frame (x - vb (t - t0), v - vb) the motion is the one on a support
 * at rest with the constant force -c vb added (the damper's pull; k = 0: no drift), exactly. Its
 * observables but x's extremes are those of the belt's frame (the stick time, the friction's work on the
 * relative motion, the transitions); the extremes are of x itself. */
static dfo_status free_belt(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                            double t_target, dfo_switch_fn on_switch, void *switch_ctx, double vb)
{
    dfo_inputs ub = *u;
    ub.F_ext = dfo_external_force(M, u) - M->p.c * vb;
    ub.F_ext_set = 1;
    ub.v_belt = 0.0;
    ub.v_belt_set = 0;
    const int poly = q != NULL && dfo_input_poly_active(q);
    belt_free b = {on_switch, switch_ctx, vb, s->t, M, u, poly ? q : NULL, M->p.observe, 0, s->t, s->X, s->V, s->mode,
                   0.0, 0.0};
    const int had = s->observed;
    const double x_max = s->x_max, x_min = s->x_min;
    const int report = on_switch != NULL || M->p.observe;
    s->V -= vb;
    dfo_status st;
    /* (ub: no belt, k = 0: the free mass's own calls; q, when active, was checked finite by the caller) */
    if (poly)
        st = dfo_exact_free_advance_pieces(M, &ub, q, s, t_target, report ? belt_free_switch : NULL, &b);
    else
        st = dfo_exact_free_advance(M, &ub, s, t_target, report ? belt_free_switch : NULL, &b);
    s->V += vb;
    s->X += vb * (s->t - b.t0);
    if (M->p.observe) {
        belt_free_phase(&b, s->t, s->X); /* the last phase, to the call's end */
        s->observed = had || s->observed;
        if (s->observed) {
            s->x_max = had ? x_max : -INFINITY;
            s->x_min = had ? x_min : INFINITY;
            if (b.have) {
                s->x_max = fmax(s->x_max, b.hi);
                s->x_min = fmin(s->x_min, b.lo);
            }
        }
    }
    return st;
}

dfo_status dfo_exact_belt_advance(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                                  double t_target, dfo_switch_fn on_switch, void *switch_ctx, double vb)
{
    if (M->p.k == 0.0) return free_belt(M, u, q, s, t_target, on_switch, switch_ctx, vb);
    const dfo_input_poly held = {s->t, {0.0, 0.0}, {0.0, 0.0}};
    return dfo_exact_spring_advance_poly(M, u, (q != NULL && dfo_input_poly_active(q)) ? q : &held, s, t_target, on_switch,
                                         switch_ctx, vb);
}
