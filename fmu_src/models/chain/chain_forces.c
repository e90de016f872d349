/* The chain's forces and one trial step: the loads of the inputs, net forces and accelerations of
 * a state, the trial step (M_hat, the re-based A0, q = -p_hat; method.md sections 2, 8 and 9) and
 * its acceptance, the consistent restart after a switch, input changes, the closed-form breakaway
 * of a stuck block. See chain_internal.h. */
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

void chain_loads_ramp(chain_model *M, double t)
{
    for (size_t i = 0; i < M->n; i++) {
        double u, Ne, r;
        chain_ramp_value(&M->rin, &M->ramp, 0, i, t, &u, &r);
        chain_ramp_value(&M->rin, &M->ramp, 1, i, t, &Ne, &r);
        const double N = fmax(M->N[i] + Ne, 0.0);
        M->u[i] = u;
        M->mukN[i] = M->mu_k[i] * N;
        M->Fb[i] = M->mu_b[i] * N;
        M->Nn[i] = N;
        M->mlN[i] = M->stribeck ? fmin(M->law[i].mu_s, M->law[i].mu_k) * N : M->mukN[i];
        M->rows[i].u = M->u[i];
        M->rows[i].mukN = M->mukN[i];
        M->rows[i].Fb = M->Fb[i];
    }
}

void chain_loads_ramped(chain_model *M, const chain_inputs *in, const chain_ramp *ramp)
{
    chain_loads_init(M, in);
    if (!ramp || !(ramp->dF_ext[0] || ramp->dF_ext[1] || ramp->dN_ext[0] || ramp->dN_ext[1])) return;
    const chain_inputs none = {NULL, NULL};
    M->ramped = 1;
    M->rin = in ? *in : none;
    M->ramp = *ramp;
    M->stuck_ok = 0;
    M->t_step = M->t_load = ramp->t_ref;
    chain_loads_ramp(M, ramp->t_ref);
}

void chain_loads_init(chain_model *M, const chain_inputs *in)
{
    M->ramped = 0;
    int all_friction = 1;
    for (size_t i = 0; i < M->n; i++) {
        const double N = (in && in->N_ext) ? fmax(M->N[i] + in->N_ext[i], 0.0) : M->N[i];
        M->u[i] = (in && in->F_ext) ? in->F_ext[i] : 0.0;
        M->mukN[i] = M->mu_k[i] * N;
        M->Fb[i] = M->mu_b[i] * N;
        M->Nn[i] = N;
        M->mlN[i] = M->stribeck ? fmin(M->law[i].mu_s, M->law[i].mu_k) * N : M->mukN[i];
        M->rows[i].u = M->u[i];
        M->rows[i].mukN = M->mukN[i];
        M->rows[i].Fb = M->Fb[i];
        all_friction &= (M->Fb[i] > 0.0);
    }
    M->stuck_ok = M->scheme == DFO_SCHEME_LOCATED && !M->energy && M->rate_max * M->h <= 1.0 && all_friction;
}

static void ghost_at(const span *G, int k, double tau, double *x, double *v, double *acc)
{
    const double H = G->H, r = tau / H, dx = G->X1[k] - G->X0[k], v0 = G->V0[k], v1 = G->V1[k];
    *x = G->X0[k] + v0 * H * (r * r * r - 2.0 * r * r + r) + dx * (3.0 * r * r - 2.0 * r * r * r) +
         v1 * H * (r * r * r - r * r);
    *v = v0 * (3.0 * r * r - 4.0 * r + 1.0) + dx / H * (6.0 * r - 6.0 * r * r) + v1 * (3.0 * r * r - 2.0 * r);
    *acc = (v0 * (6.0 * r - 4.0) + dx / H * (6.0 - 12.0 * r) + v1 * (6.0 * r - 2.0)) / H;
}

/* Write the ghosts' state at the current time into the state arrays. */
void chain_set_ghosts(chain_model *M, chain_state *s, const span *G)
{
    M->jerk_valid = 0;
    for (int k = 0; k < 2; k++)
        if (G->has[k]) ghost_at(G, k, s->t - G->t_start, &s->X[G->idx[k]], &s->V[G->idx[k]], &s->A[G->idx[k]]);
}

/* Net applied force on the span's blocks at the state (excitation, inputs, springs, dampers). */
void chain_net_forces(chain_model *M, const chain_state *s, const span *G, double *S)
{
    double cw, sw;
    chain_phase_of(M, s, s->t, &cw, &sw);
    for (size_t i = G->a; i < G->b; i++) S[i] = chain_P_at(M, i, cw, sw) + M->u[i] - chain_Kx(M, s->X, i) - chain_Cv(M, s->V, i);
}

/* Physical accelerations at the state: stuck blocks 0, the others from the equation of motion. */
void chain_mode_accels(chain_model *M, const chain_state *s, const span *G, double *a)
{
    double cw, sw;
    chain_phase_of(M, s, s->t, &cw, &sw);
    for (size_t i = G->a; i < G->b; i++) {
        if (chain_held(M, s, i)) { a[i] = 0.0; continue; }
        const double F = chain_has_friction(M, i) ? -s->mode[i] * chain_slide_mag(M, G->vrel, s, i) : 0.0;
        /* summed as the oscillator's accel_of */
        a[i] = (chain_P_at(M, i, cw, sw) + M->u[i] - chain_Kx(M, s->X, i) + F - chain_Cv(M, s->V, i)) / M->m[i];
    }
}

/* The same, and the net applied forces into M->S. */
void chain_physical_accel(chain_model *M, const chain_state *s, const span *G, double *a)
{
    chain_net_forces(M, s, G, M->S);
    chain_mode_accels(M, s, G, a);
}

void chain_accelerations(chain_model *M, const chain_inputs *in, const double *vb, const chain_state *s0, double *a)
{
    chain_loads_init(M, in);
    /* the excitation in closed form at s->t, as the oscillator's output a (dfo_acceleration): the
     * state's grid cache would round otherwise where omega t + phi does (a large phi) */
    chain_state copy = *s0;
    copy.exc_n = -1;
    const chain_state *s = &copy;
    const span G = chain_whole(M, s, NULL, vb);
    chain_physical_accel(M, s, &G, a);
    if (M->stribeck) {
        /* a slide's force is the state's (its step's end solve), as the oscillator's output a: N mu(u)
         * at the solved relative speed u, not at its rounding |V - vb| */
        double cw, sw;
        chain_phase_of(M, s, s->t, &cw, &sw);
        for (size_t i = 0; i < M->n; i++)
            if (s->mode[i] != 0 && chain_has_friction(M, i))
                a[i] = (chain_P_at(M, i, cw, sw) + M->u[i] - chain_Kx(M, s->X, i) + s->F[i] - chain_Cv(M, s->V, i)) /
                       M->m[i];
    }
    if (M->scheme != DFO_SCHEME_PAPER) return;
    /* the paper's stuck block is not at rest: it creeps with the force of its LCP (Bossak's A
     * throughout), as the oscillator reports it */
    double cw, sw;
    chain_phase_of(M, s, s->t, &cw, &sw);
    for (size_t i = 0; i < M->n; i++)
        if (chain_held(M, s, i))
            a[i] = (chain_P_at(M, i, cw, sw) + M->u[i] - chain_Kx(M, s->X, i) + s->F[i] - chain_Cv(M, s->V, i)) / M->m[i];
}

/* v^T C v */
static double damping_power(const chain_model *M, const double *v)
{
    double D = 0.0;
    for (size_t i = 0; i < M->n; i++) {
        const double dv = v[i] - (i > 0 ? v[i - 1] : 0.0);
        const double cl = (M->Cd[i] - M->cs[i]) + ((i + 1 < M->n) ? M->Co[i] : -M->c_end);
        D += cl * dv * dv;
        if (M->cs[i] != 0.0) D += M->cs[i] * v[i] * v[i];
    }
    return D + M->c_end * v[M->n - 1] * v[M->n - 1];
}

/* Block b's physical acceleration at the state in its mode (chain_mode_accels' value; a ghost's its
 * interpolated one), the phase (cw, sw) at s->t */
static double block_accel(const chain_model *M, const chain_state *s, const span *G, size_t b, double cw, double sw)
{
    for (int k = 0; k < 2; k++)
        if (G->has[k] && b == G->idx[k]) return s->A[b];
    if (chain_held(M, s, b)) return 0.0;
    const double F = chain_has_friction(M, b) ? -s->mode[b] * chain_slide_mag(M, G->vrel, s, b) : 0.0;
    return (chain_P_at(M, b, cw, sw) + M->u[b] - chain_Kx(M, s->X, b) + F - chain_Cv(M, s->V, b)) / M->m[b];
}

/* chain_trial's re-basing of A on hh for the span's blocks that need it, into A0 (method.md section 8) */
static void rebase_sparse(chain_model *M, const chain_state *s, const span *G, double hh)
{
    const size_t n = M->n;
    const double a = M->alpha, tol = 1e-12 * hh + 4.0 * DBL_EPSILON * fabs(s->t);
    const double cw = dfo_cos(M->omega * s->t + M->phi0), sw = dfo_sin(M->omega * s->t + M->phi0);
    double pcw, psw;
    chain_phase_of(M, s, s->t, &pcw, &psw);
    for (size_t i = G->a; i < G->b; i++) {
        const double hA = s->hA[i];
        const int ri = hh != hA && fabs(hh - hA) > tol && M->rate_max * fmax(hh, hA) <= 1.0;
        if (!ri) {
            M->A0[i] = s->A[i];
            continue;
        }
        double j = 0.0;
        if (!chain_held(M, s, i)) {
            const double ai = block_accel(M, s, G, i, pcw, psw);
            double cv = 0.0; /* chain_Cv of the physical accelerations */
            if (M->damped) {
                cv = M->Cd[i] * ai;
                if (i > 0) cv += M->Co[i - 1] * block_accel(M, s, G, i - 1, pcw, psw);
                if (i + 1 < n) cv += M->Co[i] * block_accel(M, s, G, i + 1, pcw, psw);
            }
            const double Pd = -M->Pc[i] * M->omega * sw + -M->Ps[i] * M->omega * cw;
            double f;
            if (M->ramped) f = Pd - chain_Kx(M, s->V, i) - cv + chain_ramp_rate(M, G->vrel, s, i);
            else f = Pd - chain_Kx(M, s->V, i) - cv;
            if (M->stribeck && chain_has_friction(M, i))
                f -= M->Nn[i] * dfo_friction_dmu(&M->law[i], chain_rel_speed(G->vrel, s, i)) * ai;
            j = f / M->m[i];
        }
        M->A0[i] = s->A[i] + a * (hh - hA) * j;
    }
}

/* The step of length hh of the span's blocks from the state to t1 (cw1, sw1: the excitation phase
 * at t1): M_hat, the re-based A0, the predicted position xp and p_hat (method.md sections 2, 8
 * and 9); a ghost's xp and velocity at t1 from its interpolation. */
void chain_trial(chain_model *M, const chain_state *s, span *G, double hh, double cw1, double sw1)
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
    M->t_trial = s->t + hh;
    if (M->ramped) {
        /* ramped inputs: the loads at t_load (the internal step's end, or a sub-step's of a switch
         * search), the limits of the trial's modes with them, and the jerk from them (as the
         * oscillator's trial sub-steps) */
        chain_loads_ramp(M, M->t_load);
        for (size_t i = a0; i < b0; i++) M->l[i] = (M->st[i] == 0) ? M->Fb[i] : M->mlN[i];
        M->jerk_valid = 0;
    }
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
    const int sparse = rebase && !M->jerk_valid && M->sparse_rebase;
    if (sparse) {
        /* the first trial of a long chain's step (chain_step_located; after a switch in a cluster):
         * only the re-based blocks' jerks, each from the physical accelerations of it and its
         * neighbours (the same values as below, not kept: O(re-based blocks), not O(n), per step) */
        rebase_sparse(M, s, G, hh);
    } else if (rebase && !M->jerk_valid) {
        /* jerk_i = (P'_i - (K V)_i - (C a)_i) / m_i for the moving blocks, 0 for the held ones; a
         * function of the state only, kept for the further trials from it (root finding) */
        /* the excitation's rate -P0 omega sin(omega t + phi), as the oscillator's */
        const double cw = dfo_cos(M->omega * s->t + M->phi0), sw = dfo_sin(M->omega * s->t + M->phi0);
        chain_mode_accels(M, s, G, M->A0);  /* physical accelerations, in A0 for now */
        for (int k = 0; k < 2; k++)
            if (G->has[k]) M->A0[G->idx[k]] = s->A[G->idx[k]];
        for (size_t i = a0; i < b0; i++) {
            double j = 0.0;
            if (!chain_held(M, s, i)) {
                const double Pd = -M->Pc[i] * M->omega * sw + -M->Ps[i] * M->omega * cw;
                /* ramped inputs: with the rates of the inputs at the state's time (the loads are the
                 * internal step's, as the oscillator's jerk) */
                double f;
                if (M->ramped)
                    f = Pd - chain_Kx(M, s->V, i) - chain_Cv(M, M->A0, i) + chain_ramp_rate(M, G->vrel, s, i);
                else f = Pd - chain_Kx(M, s->V, i) - chain_Cv(M, M->A0, i);
                /* Stribeck: d F / dt = -N mu'(u) a, u the relative speed (as the oscillator's jerk) */
                if (M->stribeck && chain_has_friction(M, i))
                    f -= M->Nn[i] * dfo_friction_dmu(&M->law[i], chain_rel_speed(G->vrel, s, i)) * M->A0[i];
                j = f / M->m[i];
            }
            M->J[i] = j;
        }
        M->jerk_valid = 1;
    }
    if (sparse) {
        M->A0p = M->A0;
    } else if (rebase) {
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
    double *xp = M->xp, *q = M->q;
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
        /* q = -p_hat (the negation is exact: the solves read p_hat's bits back) */
        q[i] = -(M->Pc[i] * cw1 - M->Ps[i] * sw1 + M->u[i] - M->am[i] * A0[i] +
                 M->am1[i] * (V[i] * c1 + g1 * A0[i]) - kx);
    }
    if (G->vb) {
        /* belts: the LCP on W = V - vb, M_hat W = p_hat - M_hat vb + F (the oscillator's shifted LCP:
         * q = -(p_hat - (M_hat vb)_i), p_hat's bits read back from -q) */
        const double *vb = G->vb, *cd = M->cd, *ce = M->ce;
        for (size_t i = a0; i < b0; i++) {
            double mv = cd[i] * vb[i];
            if (i > 0) mv += ce[i - 1] * vb[i - 1];
            if (i + 1 < n) mv += ce[i] * vb[i + 1];
            q[i] = -(-q[i] - mv);
        }
    }
}

/* Ramped inputs: the rate of block i's applied force from its inputs at the state's time,
 * u'(t) - mode mu_k N_ext'(t) (the normal force's rate only while N + N_ext > 0). */
double chain_ramp_rate(const chain_model *M, const double *vrel, const chain_state *s, size_t i)
{
    double u, du, Ne, dNe;
    chain_ramp_value(&M->rin, &M->ramp, 0, i, s->t, &u, &du);
    chain_ramp_value(&M->rin, &M->ramp, 1, i, s->t, &Ne, &dNe);
    const double dN = (M->N[i] + Ne > 0.0) ? dNe : 0.0;
    if (!chain_has_friction(M, i)) return du;
    const double mu = M->stribeck ? dfo_friction_mu(&M->law[i], chain_rel_speed(vrel, s, i)) : M->mu_k[i];
    return du - s->mode[i] * mu * dN;
}

/* Accept the trial for the span's blocks with end velocities V1 and friction forces F1 (constant
 * over the step for the moving blocks with friction): X, V, A, F, hA, the energy accounts (whole
 * chain only); not the time. */
static COLD_CALL void belt_finish(chain_model *M, chain_state *s, const span *G, const double *W, const double *F1,
                                  double t1);

void chain_finish(chain_model *M, chain_state *s, const span *G, const double *V1, const double *F1, double t1)
{
    if (G->vb) {
        belt_finish(M, s, G, V1, F1, t1);
        return;
    }
    M->jerk_valid = 0;
    const double c1 = M->kin.c1, cV = M->kin.corr_V, g1 = M->g1, hh = M->kin.h;
    if (M->energy && G->a == 0 && G->b == M->n) {
        const size_t n = M->n;
        double cw0, sw0, W = 0.0, Wf = 0.0;
        chain_phase_of(M, s, s->t, &cw0, &sw0);
        for (size_t i = 0; i < n; i++) {
            const double X1 = M->xp[i] + cV * V1[i];
            W += 0.5 * hh * ((chain_P_at(M, i, cw0, sw0) + M->u[i]) * s->V[i] +
                             (chain_P_at(M, i, M->cw1, M->sw1) + M->u[i]) * V1[i]);
            /* Stribeck: the force varies over the step (trapezoidal, as the oscillator's E_friction) */
            Wf += (M->stribeck ? 0.5 * (s->F[i] + F1[i]) : F1[i]) * (X1 - s->X[i]);
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

/* chain_finish with belts (G->vb): V = W + vb; a held block rides on its belt to t1 (X = X0 + vb (t1 -
 * t), as the oscillator's stuck phase), the others take Newmark's kinematics. */
static COLD_CALL void belt_finish(chain_model *M, chain_state *s, const span *G, const double *W, const double *F1,
                                  double t1)
{
    M->jerk_valid = 0;
    const double c1 = M->kin.c1, cV = M->kin.corr_V, g1 = M->g1, hh = M->kin.h, *vb = G->vb;
    if (M->energy && G->a == 0 && G->b == M->n) {
        const size_t n = M->n;
        double cw0, sw0, Wa = 0.0, Wf = 0.0;
        chain_phase_of(M, s, s->t, &cw0, &sw0);
        for (size_t i = 0; i < n; i++) {
            const int held = M->st[i] == 0 && M->l[i] > 0.0;
            const double V1 = W[i] + vb[i];
            const double X1 = held ? s->X[i] + vb[i] * (t1 - s->t) : M->xp[i] + cV * V1;
            Wa += 0.5 * hh * ((chain_P_at(M, i, cw0, sw0) + M->u[i]) * s->V[i] +
                              (chain_P_at(M, i, M->cw1, M->sw1) + M->u[i]) * V1);
            Wf += (M->stribeck ? 0.5 * (s->F[i] + F1[i]) : F1[i]) * (X1 - s->X[i]);
        }
        s->W_applied += Wa;
        s->W_friction += Wf;
        double *V1s = M->box; /* (free here) */
        for (size_t i = 0; i < n; i++) V1s[i] = W[i] + vb[i];
        s->D_damping += 0.5 * hh * (damping_power(M, s->V) + damping_power(M, V1s));
    }
    for (size_t i = G->a; i < G->b; i++) {
        const double V1 = W[i] + vb[i];
        if (M->st[i] == 0 && M->l[i] > 0.0) s->X[i] = s->X[i] + vb[i] * (t1 - s->t);
        else s->X[i] = M->xp[i] + cV * V1;
        s->A[i] = (V1 - s->V[i]) * c1 - g1 * M->A0p[i];
        s->V[i] = V1;
        s->F[i] = F1[i];
        s->hA[i] = hh;
    }
}

/* After a switch: the consistent restart of the span's new mode set (physical accelerations,
 * hA = 0) and the friction forces of its stuck blocks. */
void chain_restart(chain_model *M, chain_state *s, const span *G)
{
    M->jerk_valid = 0;
    chain_physical_accel(M, s, G, s->A);
    for (size_t i = G->a; i < G->b; i++) {
        s->hA[i] = 0.0;
        if (!chain_has_friction(M, i)) continue;
        if (s->mode[i] == 0) s->F[i] = -fmax(-M->Fb[i], fmin(M->Fb[i], M->S[i]));
        else s->F[i] = -s->mode[i] * chain_slide_mag(M, G->vrel, s, i);
    }
}

/* The next breakaway of block i, stuck at X with its neighbours where they are, by the oscillator's
 * closed form (friction.h): its excitation as a single block's, its static offset u - (K x)_i. */
double chain_block_breakaway(const chain_model *M, const chain_state *s, size_t i, int *dir)
{
    dfo_harmonic P;
    dfo_harmonic_init(&P, M->P0[i], M->omega, M->phi[i]);
    const dfo_loads L = {M->u[i], 0.0, M->mukN[i], M->Fb[i]};  /* (N is not read) */
    return dfo_next_breakaway(&P, &L, M->u[i] - chain_Kx(M, s->X, i), s->t_stick[i], dir);
}

/* Block i's kinetic coefficient at the state on the belts vb: mu_k, or (stribeck) mu(|v_rel|) */
static double kinetic_mu(const chain_model *M, const double *vb, const chain_state *s, size_t i)
{
    return M->stribeck ? dfo_friction_mu(&M->law[i], chain_rel_speed(vb, s, i)) : M->mu_k[i];
}

/* Block i's external force and kinetic friction magnitude under the inputs in. */
static void block_loads(const chain_model *M, const double *vb, const chain_state *s, const chain_inputs *in, size_t i,
                        double *u, double *mukN)
{
    const double N = (in && in->N_ext) ? fmax(M->N[i] + in->N_ext[i], 0.0) : M->N[i];
    *u = (in && in->F_ext) ? in->F_ext[i] : 0.0;
    *mukN = kinetic_mu(M, vb, s, i) * N;
}

void chain_new_inputs(const chain_model *M, const chain_inputs *old_in, const chain_inputs *new_in, chain_state *s)
{
    chain_new_inputs_ramped(M, old_in, new_in, NULL, NULL, s);
}

void chain_new_inputs_ramped(const chain_model *M, const chain_inputs *old_in, const chain_inputs *new_in,
                             const chain_ramp *ramp, const double *vb, chain_state *s)
{
    for (size_t i = 0; i < M->n; i++) {
        if (s->mode[i] == 0) continue;
        double u0, f0, u1, f1;
        block_loads(M, vb, s, old_in, i, &u0, &f0);
        if (ramp) { /* the new inputs' polynomials at the state's time (as the oscillator's dfo_new_inputs) */
            double Ne, rate;
            chain_ramp_value(new_in, ramp, 0, i, s->t, &u1, &rate);
            chain_ramp_value(new_in, ramp, 1, i, s->t, &Ne, &rate);
            f1 = kinetic_mu(M, vb, s, i) * fmax(M->N[i] + Ne, 0.0);
        } else {
            block_loads(M, vb, s, new_in, i, &u1, &f1);
        }
        const double dF = (u1 - u0) - s->mode[i] * (f1 - f0);
        if (dF == 0.0) continue;
        s->A[i] += dF / M->m[i];
        s->F[i] = -s->mode[i] * f1;
    }
}

void chain_step_problem(chain_model *M, const chain_inputs *in, const chain_state *s, double h,
                        double *d, double *e, double *q, double *l)
{
    chain_loads_init(M, in);
    M->jerk_valid = 0;
    span G = chain_whole(M, s, NULL, NULL);
    chain_trial(M, s, &G, h, dfo_cos(M->omega * (s->t + h) + M->phi0), dfo_sin(M->omega * (s->t + h) + M->phi0));
    for (size_t i = 0; i < M->n; i++) {
        d[i] = M->cd[i];
        if (i + 1 < M->n) e[i] = M->ce[i];
        q[i] = M->q[i];
        l[i] = (s->mode[i] == 0) ? M->Fb[i] : M->mukN[i];
    }
}
