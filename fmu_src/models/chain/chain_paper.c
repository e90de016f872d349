/* The chain's paper and consistent schemes (method.md sections 4 and 9): the box LCP of the step
 * (numerics/lcp.h) from the modes before it, then the paper's coefficient update and second solve,
 * or the consistent scheme's rest rule. See chain_internal.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_internal.h"

COLD_CALL void chain_step_lcp(chain_model *M, chain_state *s, const double *vb, double t_end, double hh,
                               chain_switch_fn fn, void *ctx, int consistent)
{
    const size_t n = M->n;
    double cw1, sw1;
    chain_phase_of(M, s, t_end, &cw1, &sw1);
    span G0 = chain_whole(M, s, vb, vb);
    chain_trial(M, s, &G0, hh, cw1, sw1);
    /* the LCP with the coefficient of each block's mode before the step, from that basis */
    for (size_t i = 0; i < n; i++) {
        M->st[i] = s->mode[i];
        M->l[i] = !chain_has_friction(M, i) ? 0.0 : (s->mode[i] == 0) ? M->Fb[i] : M->mukN[i];
    }
    int piv = 0;
    lcp_status st = lcp_box(n, M->cd, M->ce, M->q, M->l, M->st, M->Vt, M->Ft, M->box, &piv);
    s->solves++;
    if (st != LCP_OK) { M->err = CHAIN_ERR_LCP; return; }
    int total = piv, update = 0;
    if (!consistent) {
        /* paper: one update of the coefficients from the result, and a second solve */
        for (size_t i = 0; i < n; i++) {
            if (!chain_has_friction(M, i)) continue;
            const double l1 = (M->st[i] == 0) ? M->Fb[i] : M->mukN[i];
            if (l1 != M->l[i]) { M->l[i] = l1; update = 1; }
        }
        if (update) {
            st = lcp_box(n, M->cd, M->ce, M->q, M->l, M->st, M->Vt, M->Ft, M->box, &piv);
            s->solves++;
            if (st != LCP_OK) { M->err = CHAIN_ERR_LCP; return; }
            total += piv;
        }
    } else {
        /* consistent (method.md section 4): a stuck block that breaks loose slides with mu_k; a
         * sliding block that fails to keep sliding sticks if the static force at its predicted
         * rest position is within the breakaway limit, else slides the way of that force with mu_k
         * (and sticks if its velocity then comes out the wrong way) */
        for (size_t i = 0; i < n; i++) {
            if (!chain_has_friction(M, i)) continue;
            const int from = s->mode[i];
            if (from == 0 && M->st[i] != 0) { M->l[i] = M->mukN[i]; update = 1; }
            if (from != 0 && M->st[i] != from) {
                const double S = chain_P_at(M, i, cw1, sw1) + M->u[i] - chain_Kx(M, M->xp, i);
                M->st[i] = (fabs(S) <= M->Fb[i]) ? 0 : chain_sgn(S);
                M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mukN[i];
                M->frozen[i] = M->any_frozen = 1; /* judged: no more pivots on it */
                update = 1;
            } else {
                M->frozen[i] = 0;
            }
        }
        for (int pass = 0; update && pass <= (int)n; pass++) {
            lcp_box_basis(0, n, 0, 0.0, 0, 0.0, M->cd, M->ce, M->q, M->l, M->st, M->Vt, M->Ft, M->cp, M->dp);
            s->solves++;
            update = 0;
            for (size_t i = 0; i < n; i++) {
                if (!chain_has_friction(M, i) || M->st[i] == 0 || M->st[i] * M->Vt[i] > 0.0) continue;
                if (s->mode[i] == 0 && !M->frozen[i]) continue;
                M->st[i] = 0;
                M->l[i] = M->Fb[i];
                update = 1;
            }
        }
        for (size_t i = 0; i < n; i++) {
            /* a stuck block's held force is the static force, clamped to the limit */
            if (chain_has_friction(M, i) && M->st[i] == 0) M->Ft[i] = fmax(-M->Fb[i], fmin(M->Fb[i], M->Ft[i]));
            if (!chain_has_friction(M, i)) M->st[i] = chain_sgn(M->Vt[i]);
        }
        total += update;
    }
    if (total > 0) s->pivot_steps++;
    chain_finish(M, s, &G0, M->Vt, M->Ft, t_end);
    s->t = t_end;
    for (size_t i = 0; i < n; i++) {
        const int from = s->mode[i];
        s->mode[i] = M->st[i];
        if (s->mode[i] == 0 && from != 0) s->t_stick[i] = s->t;
        if (consistent && s->mode[i] == 0 && chain_has_friction(M, i)) s->A[i] = 0.0;
        if (chain_has_friction(M, i) && s->mode[i] != from) chain_report(M, s, i, from, fn, ctx);
    }
}
