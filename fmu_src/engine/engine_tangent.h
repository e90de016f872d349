/* The located scheme's tangent (eng_setup.tangent): part of engine_step.h's template, included by it
 * after the trial step and before the schemes.
 *
 * The located map is a product of (sub-)steps in fixed modes and switches. A (sub-)step of length hh
 * from the state (X, V, A, hA, s, t) in its modes is affine in the state and smooth in hh and t:
 * its tangent is the same Bossak step applied to the derivatives (x_pred, p_hat, the constrained
 * solve with M_hat's derivative in hh, the corrector), every held contact's constraint kept (its
 * slip's derivative 0; a stuck Jenkins slider's with its compliance), every sliding force constant
 * (Coulomb). The re-basing of A on another step length (method.md section 8) adds the jerks'
 * derivatives. A sub-step that ends at a located switch has the length hs where the switching
 * contact's margin is 0: d hs = -dg / g', g' the margin's rate in hh (the saltation). The switch's
 * consistent restart gives the accelerations' derivatives (the held solve on the mass slot), a
 * Jenkins breakaway the slider's jump. Each column of the tangent (eng_state.tan) holds the
 * derivatives of X, V, A, hA, the sliders and the time with respect to one start value.
 *
 * Every (sub-)step's columns: a column with dhh = 0 (res_c) plus the column's dhh times the
 * derivative in hh (res_h): dhh is the root's d hs at a switch, -dt for the remainder of a step
 * (its end t_end is fixed), 0 for a whole step from the grid. */

#define TAN_XO 0
#define TAN_VO(n) (n)
#define TAN_AO(n) (2 * (n))
#define TAN_HO(n) (3 * (n))
#define TAN_SO(n) (4 * (n))
#define TAN_TO(n, nc) (4 * (n) + (nc))

static size_t tan_L(const eng *E) { return 4 * ENG_N(E) + ENG_NC(E) + 1; }
static size_t tan_nz(const eng *E) { return 2 * ENG_N(E) + ENG_NC(E); }

/* The held set k of slot: its contacts (held[j]), their columns A_slot^-1 w_j, their Delassus
 * matrix (plus comp on the diagonal where given) and its Cholesky factor, kept for the solves of
 * every column. */
static void tan_prep(eng *E, int k, int slot, const int *held, const double *comp)
{
    const eng_setup *S = &E->S;
    tan_set *T = &E->tset[k];
    const size_t nc = ENG_NC(E);
    size_t m = 0;
    for (size_t j = 0; j < nc; j++)
        if (held[j]) T->sel[m++] = (int)j;
    T->slot = slot;
    T->m = m;
    if (m == 0) return;
    memcpy(E->sel, T->sel, m * sizeof(int));
    columns(E, slot, m);
    for (size_t a = 0; a < m; a++) T->col[a] = E->colp[a];
    for (size_t a = 0; a < m; a++) {
        const eng_row *Ra = &S->rows[T->sel[a]];
        for (size_t c = 0; c <= a; c++) T->D[a * m + c] = T->D[c * m + a] = row_dot(Ra, T->col[c]);
        if (comp) T->D[a * m + a] += comp[T->sel[a]];
    }
    chol(m, T->D, m, T->L, T->dep);
}

/* y = A_slot^-1 (r + W_S' f_S) with W_S y (+ comp_S f_S) = target_S (NULL: 0), S held set k; f_S
 * into f (nc; the other entries untouched). r and y may be the same array. */
static void tan_csolve(eng *E, int k, const double *r, const double *target, double *y, double *f)
{
    const eng_setup *S = &E->S;
    const tan_set *T = &E->tset[k];
    const size_t n = ENG_N(E), m = T->m;
    ENG_SOLVE(E, T->slot, r, y);
    if (m == 0) return;
    for (size_t a = 0; a < m; a++)
        E->trhs[a] = (target ? target[T->sel[a]] : 0.0) - row_dot(&S->rows[T->sel[a]], y);
    chol_solve(m, T->L, m, T->dep, E->trhs, E->tsol);
    /* (the forces shared over dependent rows as csolve shares them: linear, so their derivatives too) */
    const double *fs = dependent_share(E, m, T->sel, T->D, T->L, T->dep, E->tsol);
    for (size_t a = 0; a < m; a++) {
        const double fa = E->tsol[a];
        const double *col = T->col[a];
        for (size_t i = 0; i < n; i++) y[i] += col[i] * fa;
        f[T->sel[a]] = fs[a];
    }
}

/* dP/dt + dF_ext/dt (rate) and its derivative (rate2) at t */
static void tan_rates(eng *E, const eng_inputs *in, double t, double *rate, double *rate2)
{
    const eng_harmonic *H = &E->S.exc;
    const double th = H->omega * t + H->phi0, cw = dfo_cos(th), sw = dfo_sin(th), w = H->omega;
    const int rp = ramped(in);
    for (size_t i = 0; i < ENG_N(E); i++) {
        const double pc = H->Pc ? H->Pc[i] : 0.0, ps = H->Ps ? H->Ps[i] : 0.0;
        rate[i] = (rp ? poly_rate(in->dF_ext, in, i, t) : 0.0) - w * (pc * sw + ps * cw);
        rate2[i] = ((rp && in->dF_ext[1]) ? in->dF_ext[1][i] : 0.0) - w * w * (pc * cw - ps * sw);
    }
}

/* The rigid contacts held in the modes (the mass slot's constraints) into E->theld */
static void tan_held_rigid(eng *E, const int *mode)
{
    for (size_t j = 0; j < ENG_NC(E); j++) E->theld[j] = mode[j] == 0 && has_friction(E, j) && !is_jenk(E, j);
}

/* Column c's physical accelerations' derivative at the state s in its modes (phys_accel's): held set
 * 1 of the mass slot prepped for s->mode (tan_held_rigid), E->trate the loads' rate at s->t. From
 * dX, dV, dS, dt of column T into da. */
static void tan_phys_col(eng *E, const eng_state *s, const double *T, double *da)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    double *r = E->tw1, *y = E->tw2;
    const double dt = T[TAN_TO(n, nc)];
    for (size_t i = 0; i < n; i++) r[i] = E->trate[i] * dt;
    minus_kc(E, T + TAN_XO, T + TAN_VO(n), r, y);
    for (size_t j = 0; j < nc; j++)
        if (is_jenk(E, j) && has_friction(E, j) && s->mode[j] == 0)
            row_axpy(&S->rows[j], -S->k_t[j] * (row_dot(&S->rows[j], T + TAN_XO) - T[TAN_SO(n) + j]), r);
    tan_csolve(E, 1, r, NULL, da, E->tfh);
}

/* The restart's derivatives (restart's consistent accelerations of s in its modes at its time, hA 0)
 * for every column of s->tan */
static void tan_restart(eng *E, const eng_inputs *in, const eng_state *s)
{
    const size_t n = ENG_N(E), L = tan_L(E), nz = tan_nz(E);
    loads_at(E, in, s->t);
    tan_rates(E, in, s->t, E->trate, E->trate2);
    factor_slot(E, ENG_SLOT_MASS, 1.0, 0.0, 0.0);
    tan_held_rigid(E, s->mode);
    tan_prep(E, 1, ENG_SLOT_MASS, E->theld, NULL);
    for (size_t c = 0; c < nz; c++) {
        double *T = s->tan + c * L;
        tan_phys_col(E, s, T, T + TAN_AO(n));
        for (size_t i = 0; i < n; i++) T[TAN_HO(n) + i] = 0.0;
    }
}

/* The seed at the run's start: the identity on x0, v0 and the Jenkins sliders, then the restart's */
static void tan_seed(eng *E, const eng_inputs *in, eng_state *s)
{
    const size_t n = ENG_N(E), nc = ENG_NC(E), L = tan_L(E), nz = tan_nz(E);
    for (size_t k = 0; k < nz * L; k++) s->tan[k] = 0.0;
    for (size_t i = 0; i < 2 * n; i++) s->tan[i * L + i] = 1.0;
    for (size_t j = 0; j < nc; j++) {
        if (!is_jenk(E, j)) continue;
        if (!(has_friction(E, j) && s->mode[j] != 0)) {
            s->tan[(2 * n + j) * L + TAN_SO(n) + j] = 1.0;
            continue;
        }
        /* a sliding slider sits where its kinetic force puts it: w_j . x less a constant (s0 not read) */
        for (size_t c = 0; c < nz; c++)
            s->tan[c * L + TAN_SO(n) + j] = row_dot(&E->S.rows[j], s->tan + c * L + TAN_XO);
    }
    s->tan_lost = 0;
    tan_restart(E, in, s);
}

/* The DOFs a held contact pins alone at rest exactly (rest_exact's): their V, A, hA derivatives 0 */
static void tan_rest_exact(eng *E, eng_state *s)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), L = tan_L(E), nz = tan_nz(E);
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (s->mode[j] != 0 || !has_friction(E, j) || is_jenk(E, j) || S->rows[j].nnz != 1) continue;
        const size_t i = S->rows[j].idx[0];
        for (size_t c = 0; c < nz; c++) {
            double *T = s->tan + c * L;
            T[TAN_VO(n) + i] = T[TAN_AO(n) + i] = T[TAN_HO(n) + i] = 0.0;
        }
    }
}

/* The phase start's jerk derivatives (E->tjk, nz x n; with damping through the physical
 * accelerations' derivatives), once per phase: jerks' equation differentiated */
static void tan_phase_jerks(eng *E, const eng_inputs *in, const eng_state *s)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E), L = tan_L(E), nz = tan_nz(E);
    if (E->tjk_ok) return;
    loads_at(E, in, s->t);
    tan_rates(E, in, s->t, E->trate, E->trate2);
    factor_slot(E, ENG_SLOT_MASS, 1.0, 0.0, 0.0);
    tan_held_rigid(E, s->mode);
    tan_prep(E, 1, ENG_SLOT_MASS, E->theld, NULL);
    double *r = E->tw3, *y = E->tw4, *da = E->tw5;
    for (size_t c = 0; c < nz; c++) {
        const double *T = s->tan + c * L;
        if (ENG_HAS_C(E)) tan_phys_col(E, s, T, da);
        const double dt = T[TAN_TO(n, nc)];
        for (size_t i = 0; i < n; i++) r[i] = E->trate2[i] * dt;
        ENG_APPLY_K(E, T + TAN_VO(n), y);
        for (size_t i = 0; i < n; i++) r[i] -= y[i];
        if (ENG_HAS_C(E)) {
            ENG_APPLY_C(E, da, y);
            for (size_t i = 0; i < n; i++) r[i] -= y[i];
        }
        for (size_t j = 0; j < nc; j++)
            if (is_jenk(E, j) && has_friction(E, j) && s->mode[j] == 0)
                row_axpy(&S->rows[j], -S->k_t[j] * row_dot(&S->rows[j], T + TAN_VO(n)), r);
        tan_csolve(E, 1, r, NULL, E->tjk + c * n, E->tfh);
    }
    E->tjk_ok = 1;
}

/* Which DOFs' A the trial of length hh from s re-based (rebase_into's rule) into E->trb; 0: none */
static int tan_rebased(eng *E, const eng_inputs *in, const eng_state *s, double hh)
{
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E);
    if (S->alpha == 0.0) return 0;
    int other = E->rpin_ok;
    for (size_t i = 0; i < n && !other; i++) other = hh != s->hA[i];
    if (!other) return 0;
    const double tol = 1e-12 * hh + 4.0 * DBL_EPSILON * fabs(s->t);
    const int *pin = rebase_pins(E, in, s);
    int any = 0;
    for (size_t i = 0; i < n; i++) any |= E->trb[i] = (pin[i] == 0) & rebases_len(S, s->hA[i], hh, tol);
    return any;
}

/* The trial's per-step constants: set 0 (its held contacts, Jenkins compliances), M V1 and K V1
 * (M_hat's derivative in hh), the re-based DOFs; the loads' rate at its end t1. */
static void tan_trial_prep(eng *E, const eng_inputs *in, const eng_state *s, const trial *T, double t1)
{
    const size_t nc = ENG_NC(E);
    for (size_t j = 0; j < nc; j++) {
        E->theld[j] = has_friction(E, j) && E->st[j] == 0;
        E->tcomp[j] = is_jenk(E, j) ? 1.0 / (E->S.k_t[j] * T->kin.corr_V) : 0.0; /* (solve_trial's) */
    }
    tan_prep(E, 0, T->slot, E->theld, ENG_HAS_JENKINS(E) ? E->tcomp : NULL);
    ENG_APPLY_M(E, E->V1, E->tMV);
    ENG_APPLY_K(E, E->V1, E->tKV);
    E->tany_rb = tan_rebased(E, in, s, T->kin.h);
    if (E->tany_rb) {
        tan_phase_jerks(E, in, s);
        if (!E->jk_ok) phase_jerks(E, in, s);
    }
    loads_at(E, in, t1);
    tan_rates(E, in, t1, E->trate, E->trate2);
}

/* One column through the trial (its constants by tan_trial_prep): from column c of s->tan (the phase
 * start's derivatives; c = nz: zeros, the derivative in hh) and the step length's derivative dhh,
 * into T1 the end's (X, V, A, hA, sliders, time) and df the contacts' forces' (held ones; the
 * others 0). */
static void tan_trial_col(eng *E, const eng_state *s, const trial *T, size_t c, double dhh, double *T1, double *df)
{
    const double *T0 = (c < tan_nz(E)) ? s->tan + c * tan_L(E) : NULL;
    const eng_setup *S = &E->S;
    const size_t n = ENG_N(E), nc = ENG_NC(E);
    const dfo_bossak_kin K = T->kin;
    const double a = S->alpha, g = E->g, b = E->b, g1 = E->g1, hh = K.h;
    /* the kinematics' derivatives in hh */
    const double dc1 = -K.c1 / hh, dpV = 1.0 - b / g, dpA = 2.0 * hh * (0.5 - b / g), dcV = b / g;
    const double dcM = (1.0 - a) * dc1, dcK = b / g;
    double *dA0 = E->tw1, *dxp = E->tw2, *r = E->tw3, *y = E->tw4, *tg = E->tw5;
    static const double zero = 0.0;
    const double dt = T0 ? T0[TAN_TO(n, nc)] : 0.0, dt1 = dt + dhh;
#define TAN_IN(off, i) (T0 ? T0[(off) + (i)] : zero)
    for (size_t i = 0; i < n; i++) {
        double d = TAN_IN(TAN_AO(n), i);
        if (E->tany_rb && E->trb[i])
            d += a * ((dhh - TAN_IN(TAN_HO(n), i)) * E->jk[i] + (hh - s->hA[i]) * (T0 ? E->tjk[c * n + i] : 0.0));
        dA0[i] = d;
        dxp[i] = TAN_IN(TAN_XO, i) + K.pred_V * TAN_IN(TAN_VO(n), i) + K.pred_A * d +
                 dhh * (dpV * s->V[i] + dpA * E->A0[i]);
        tg[i] = -a * d + (1.0 - a) * (TAN_IN(TAN_VO(n), i) * K.c1 + s->V[i] * dc1 * dhh + g1 * d);
    }
    ENG_APPLY_M(E, tg, r);
    ENG_APPLY_K(E, dxp, y);
    for (size_t i = 0; i < n; i++) r[i] += E->trate[i] * dt1 - y[i] - dhh * (dcM * E->tMV[i] + dcK * E->tKV[i]);
    /* the held contacts' targets: rigid 0 (still belts over the step), a stuck Jenkins slider's
     * shifted target and compliance differentiated */
    double *tgt = NULL;
    if (ENG_HAS_JENKINS(E)) {
        tgt = E->ttgt;
        for (size_t j = 0; j < nc; j++) {
            tgt[j] = 0.0;
            if (!is_jenk(E, j) || !(has_friction(E, j) && E->st[j] == 0)) continue; /* (set 0's) */
            const double cV = K.corr_V;
            const double vbj = ((s->slider[j] + hh * E->vb[j]) - row_dot(&S->rows[j], E->xp)) / cV;
            const double comp = 1.0 / (S->k_t[j] * cV);
            const double dvbj = (TAN_IN(TAN_SO(n), j) + dhh * E->vb[j] - row_dot(&S->rows[j], dxp)) / cV -
                                vbj * dcV * dhh / cV;
            const double dcomp = -comp * dcV * dhh / cV;
            tgt[j] = dvbj - dcomp * E->f[j];
        }
    }
    for (size_t j = 0; j < nc; j++) df[j] = 0.0;
    double *dV1 = T1 + TAN_VO(n);
    tan_csolve(E, 0, r, tgt, dV1, df);
    for (size_t i = 0; i < n; i++) {
        T1[TAN_XO + i] = dxp[i] + K.corr_V * dV1[i] + dcV * dhh * E->V1[i];
        T1[TAN_AO(n) + i] = (dV1[i] - TAN_IN(TAN_VO(n), i)) * K.c1 + (E->V1[i] - s->V[i]) * dc1 * dhh - g1 * dA0[i];
        T1[TAN_HO(n) + i] = dhh;
    }
    for (size_t j = 0; j < nc; j++) {
        double dS = 0.0;
        if (is_jenk(E, j))
            dS = (has_friction(E, j) && E->st[j] == 0) ? TAN_IN(TAN_SO(n), j) + dhh * E->vb[j]
                                                         : row_dot(&S->rows[j], T1 + TAN_XO);
        T1[TAN_SO(n) + j] = dS;
    }
    T1[TAN_TO(n, nc)] = dt1;
#undef TAN_IN
}

/* Contact j's margin's derivative in the trial (margin's: a sliding one's slip, a held one's force's
 * distance to its limit) from the end's derivatives T1 and the forces' df */
static double tan_margin(const eng *E, size_t j, const double *T1, const double *df)
{
    const size_t n = ENG_N(E);
    if (E->st[j] != 0) return E->st[j] * row_dot(&E->S.rows[j], T1 + TAN_VO(n));
    return -(double)sgn(E->f[j]) * df[j];
}

/* The contact whose margin ends the located sub-step (the smallest among the candidates) */
static size_t tan_root_contact(const eng *E)
{
    size_t js = ENG_NC(E);
    double gm = INFINITY;
    for (size_t j = 0; j < ENG_NC(E); j++) {
        if (!E->cand[j]) continue;
        const double gj = margin(E, E->st, j, E->V1, E->f);
        if (js == ENG_NC(E) || gj < gm) { gm = gj; js = j; }
    }
    return js;
}

/* The root's d hs per column (E->tdh), from the trial at hs as solved in the phase's modes (before a
 * stopping contact is held): the margin of the root's contact js stays 0; its columns stay in E->tg2
 * and E->th (tan_accept's where no contact stops). A margin whose rate in hh is 0 (a grazing) loses
 * the tangent. Returns 1 when the columns were made. */
static int tan_root(eng *E, const eng_inputs *in, eng_state *s, const trial *T, double t1)
{
    const size_t nz = tan_nz(E), L = tan_L(E);
    const size_t js = tan_root_contact(E);
    if (js == ENG_NC(E)) { s->tan_lost = 1; return 0; }
    tan_trial_prep(E, in, s, T, t1);
    tan_trial_col(E, s, T, nz, 1.0, E->th, E->tdf);
    const double gh = tan_margin(E, js, E->th, E->tdf);
    if (!(fabs(gh) > 0.0) || !isfinite(gh)) { s->tan_lost = 1; return 0; }
    for (size_t c = 0; c < nz; c++) {
        tan_trial_col(E, s, T, c, 0.0, E->tg2 + c * L, E->tdf);
        E->tdh[c] = -tan_margin(E, js, E->tg2 + c * L, E->tdf) / gh;
    }
    return 1;
}

/* The (sub-)step's end derivatives into s->tan (before finish moves the state): each column's
 * res_c + dhh res_h, dhh its E->tdh (root: tan_root's) or -dt (a remainder to the step's end). */
static void tan_accept(eng *E, const eng_inputs *in, eng_state *s, const trial *T, double t1, int root, int same)
{
    const size_t n = ENG_N(E), nc = ENG_NC(E), nz = tan_nz(E), L = tan_L(E);
    if (s->tan_lost) return;
    /* same: tan_root's columns (E->tg2, E->th) are of this trial and held set (no contact stopped
     * in it): only their combination is left */
    if (!same) tan_trial_prep(E, in, s, T, t1);
    int need_h = root;
    for (size_t c = 0; c < nz && !need_h; c++) need_h = s->tan[c * L + TAN_TO(n, nc)] != 0.0;
    if (need_h && !same) tan_trial_col(E, s, T, nz, 1.0, E->th, E->tdf);
    for (size_t c = 0; c < nz; c++) {
        double *T0 = s->tan + c * L, *T1 = E->tg2 + c * L;
        if (!same) tan_trial_col(E, s, T, c, 0.0, T1, E->tdf);
        const double dhh = root ? E->tdh[c] : -T0[TAN_TO(n, nc)];
        if (need_h && dhh != 0.0)
            for (size_t k = 0; k < L; k++) T1[k] += dhh * E->th[k];
    }
    double *t = s->tan;
    s->tan = E->tg2;
    E->tg2 = t;
}

/* A switch applied at the state (apply_switches' modes and restart done): the Jenkins sliders that
 * broke away jumped to their spring's kinetic length (E->smode: the modes before), the restart's
 * accelerations, the held DOFs at rest exactly. */
static void tan_switched(eng *E, const eng_inputs *in, eng_state *s)
{
    const size_t n = ENG_N(E), nc = ENG_NC(E), nz = tan_nz(E), L = tan_L(E);
    if (s->tan_lost) return;
    for (size_t j = 0; j < nc; j++) {
        if (!is_jenk(E, j) || !has_friction(E, j) || E->smode[j] != 0 || s->mode[j] == 0) continue;
        for (size_t c = 0; c < nz; c++)
            s->tan[c * L + TAN_SO(n) + j] = row_dot(&E->S.rows[j], s->tan + c * L + TAN_XO);
    }
    tan_restart(E, in, s);
    tan_rest_exact(E, s);
}
