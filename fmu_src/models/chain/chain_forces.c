/* The chain's loads and inputs: the ramps of the inputs, the loads of held inputs (the outputs'
 * derivatives read them), the engine's inputs of the chain's, the box LCP of a step for tests. See
 * chain_internal.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_internal.h"

#include <string.h>

void chain_ramp_value(const chain_inputs *in, const chain_ramp *ramp, int k, size_t i, double t, double *value,
                      double *rate)
{
    const double *u = in ? (k ? in->N_ext : in->F_ext) : NULL;
    const double *const *d = ramp ? (k ? ramp->dN_ext : ramp->dF_ext) : NULL;
    const double u1 = (d && d[0]) ? d[0][i] : 0.0, u2 = (d && d[1]) ? d[1][i] : 0.0;
    const double tau = ramp ? t - ramp->t_ref : 0.0;
    *value = (u ? u[i] : 0.0) + tau * (u1 + 0.5 * tau * u2);
    *rate = u1 + tau * u2;
}

void chain_loads_init(chain_model *M, const chain_inputs *in)
{
    for (size_t i = 0; i < M->n; i++) {
        const double N = (in && in->N_ext) ? fmax(M->N[i] + in->N_ext[i], 0.0) : M->N[i];
        M->u[i] = (in && in->F_ext) ? in->F_ext[i] : 0.0;
        M->mukN[i] = M->mu_k[i] * N;
        M->Fb[i] = M->mu_b[i] * N;
        M->Nn[i] = N;
    }
}

void chain_eng_inputs(const chain_inputs *in, const chain_ramp *ramp, const double *vb, eng_inputs *ei)
{
    memset(ei, 0, sizeof *ei);
    if (in) {
        ei->F_ext = in->F_ext;
        ei->N_ext = in->N_ext;
    }
    ei->v_belt = vb;
    if (ramp) {
        for (int d = 0; d < 2; d++) {
            ei->dF_ext[d] = ramp->dF_ext[d];
            ei->dN_ext[d] = ramp->dN_ext[d];
        }
        ei->t_ref = ramp->t_ref;
    }
}

void chain_step_problem(chain_model *M, const chain_inputs *in, const chain_state *s, double h,
                        double *d, double *e, double *q, double *l)
{
    chain_loads_init(M, in);
    const size_t n = M->n;
    const double a = M->alpha, g = dfo_bossak_gamma(a), b = dfo_bossak_beta(a);
    dfo_bossak_kin kin;
    dfo_bossak_kin_for(h, g, b, &kin);
    const double g1 = (1.0 - g) / g, cw = dfo_cos(M->omega * (s->t + h) + M->phi0),
                 sw = dfo_sin(M->omega * (s->t + h) + M->phi0);
    for (size_t i = 0; i < n; i++) {
        d[i] = (1.0 - a) * kin.c1 * M->m[i] + (b * h / g) * M->Kd[i] + M->Cd[i];
        if (i + 1 < n) e[i] = (b * h / g) * M->Ko[i] + M->Co[i];
    }
    for (size_t i = 0; i < n; i++) {
        double kxp = 0.0;
        for (size_t j = (i > 0 ? i - 1 : 0); j <= i + 1 && j < n; j++) {
            const double xp = s->X[j] + kin.pred_V * s->V[j] + kin.pred_A * s->A[j];
            kxp += ((j == i) ? M->Kd[i] : M->Ko[j < i ? j : i]) * xp;
        }
        const double ph = chain_P_at(M, i, cw, sw) + M->u[i] - kxp +
                          M->m[i] * (-a * s->A[i] + (1.0 - a) * (s->V[i] * kin.c1 + g1 * s->A[i]));
        q[i] = -ph;
        l[i] = (s->mode[i] == 0) ? M->Fb[i] : M->mukN[i];
    }
}
