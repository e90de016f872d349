/* The exact scheme's observables and switch reports: the bookkeeping after each phase. See
 * exact_observe.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "exact_observe.h"

#include <math.h>

void dfo_exact_sample(dfo_state *s, double x)
{
    if (!s->observed) {
        s->x_max = s->x_min = x;
        s->observed = 1;
    }
    if (x > s->x_max) s->x_max = x;
    if (x < s->x_min) s->x_min = x;
}

void dfo_exact_after_phase(const dfo_model *M, double muk_N, dfo_switch_fn on_switch, void *switch_ctx,
                           dfo_state *s, dfo_phase_x_fn x_at, const void *ctx, const void *phase, double ta,
                           double tb, double xa, double xb, int mode_during, int mode_after, int event)
{
    if (event && mode_after != mode_during) {
        if (on_switch) on_switch(switch_ctx, tb, xb, mode_during, mode_after);
    }
    if (!M->p.observe) return;
    const double w0 = M->p.t_obs_start, w1 = M->p.t_obs_stop;
    if (tb < w0 || ta > w1) return;
    if (mode_during == 0 || phase == NULL) {
        s->t_stuck += (mode_during == 0) ? fmax(fmin(tb, w1) - fmax(ta, w0), 0.0) : 0.0;
        dfo_exact_sample(s, xb);
    } else {
        const double x0 = (ta < w0) ? x_at(ctx, phase, w0 - ta) : xa;
        const double x1 = (tb > w1) ? x_at(ctx, phase, w1 - ta) : xb;
        dfo_exact_sample(s, x0);
        dfo_exact_sample(s, x1);
        s->E_friction += muk_N * fabs(x1 - x0);
    }
    if (event && mode_after != mode_during && tb > w0 && tb <= w1) s->transitions++;
}

void dfo_exact_after_phase_poly(const dfo_model *M, dfo_switch_fn on_switch, void *switch_ctx, dfo_state *s,
                                dfo_phase_x_fn x_at, dfo_phase_work_fn work, const void *ctx, const void *phase,
                                const double *n, double ta, double tb, double xa, double xb, int mode_during,
                                int mode_after, int event)
{
    const int varying = n != NULL && (n[1] != 0.0 || n[2] != 0.0);
    const double muk_N = (n != NULL) ? M->mu_k * fmax(n[0], 0.0) : 0.0;
    dfo_exact_after_phase(M, varying ? 0.0 : muk_N, on_switch, switch_ctx, s, x_at, ctx, phase, ta, tb, xa, xb,
                          mode_during, mode_after, event);
    if (varying && M->p.observe && mode_during != 0) {
        const double w0 = M->p.t_obs_start, w1 = M->p.t_obs_stop;
        const double a = fmax(ta, w0), b = fmin(tb, w1);
        if (b > a) s->E_friction += work(ctx, phase, a - ta, b - ta);
    }
}

long long dfo_exact_grid_index(const dfo_model *M, const dfo_state *s)
{
    const double h = M->p.h, q = floor((s->t - s->t0) / h);
    if (!(q >= 0.0)) return 0;
    if (q > 9e18) return s->n;
    long long n = (long long)q;
    while (n > 0 && s->t0 + (double)n * h > s->t) n--;
    while (s->t0 + (double)(n + 1) * h <= s->t) n++;
    return n;
}
