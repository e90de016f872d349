/* The TwoMass model's physics (fmu_src/models/two_mass) through the friction engine, for
 * tests/test_two_mass.py: parameters as name=value arguments (the fields of tm_params; t_end and dt
 * the run and its communication step), one line per communication point on stdout:
 *     t x1 x2 v1 v2 mode_g mode_c
 * with %.17g. Exit status 2 and one line on stderr for a bad argument or a failed step. */
#include "engine.h"
#include "two_mass.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *d_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void d_free(void *env, void *p) { (void)env; free(p); }

int main(int argc, char **argv)
{
    tm_params p;
    memset(&p, 0, sizeof p);
    p.m1 = 1.0;
    p.m2 = 1.0;
    p.alpha = -0.1;
    p.scheme = DFO_SCHEME_LOCATED;
    p.frictionUpdates = 1;
    p.fastPaths = 1;
    double t_end = 1.0, dt = 0.1;
    struct {
        const char *name;
        double *v;
    } reals[] = {{"m1", &p.m1},       {"m2", &p.m2},       {"k1", &p.k1},         {"k2", &p.k2},
                 {"k12", &p.k12},     {"c1", &p.c1},       {"c2", &p.c2},         {"c12", &p.c12},
                 {"P1", &p.P1},       {"P2", &p.P2},       {"omega", &p.omega},   {"phi", &p.phi},
                 {"N_g", &p.N_g},     {"mu_s_g", &p.mu_s_g}, {"mu_k_g", &p.mu_k_g}, {"N_c", &p.N_c},
                 {"mu_s_c", &p.mu_s_c}, {"mu_k_c", &p.mu_k_c}, {"x1_0", &p.x1_0},   {"x2_0", &p.x2_0},
                 {"v1_0", &p.v1_0},   {"v2_0", &p.v2_0},   {"h", &p.h},           {"alpha", &p.alpha},
                 {"t_end", &t_end},   {"dt", &dt}};
    for (int i = 1; i < argc; i++) {
        const char *eq = strchr(argv[i], '=');
        if (!eq) {
            fprintf(stderr, "two_mass_driver: expected name=value, got '%s'\n", argv[i]);
            return 2;
        }
        const size_t nlen = (size_t)(eq - argv[i]);
        char *end = NULL;
        const double val = strtod(eq + 1, &end);
        if (end == eq + 1 || *end != '\0') {
            fprintf(stderr, "two_mass_driver: '%s' is not a number\n", argv[i]);
            return 2;
        }
        int found = 0;
        for (size_t k = 0; k < sizeof reals / sizeof reals[0] && !found; k++)
            if (strlen(reals[k].name) == nlen && !strncmp(reals[k].name, argv[i], nlen)) {
                *reals[k].v = val;
                found = 1;
            }
        if (!found && nlen == 6 && !strncmp(argv[i], "scheme", 6)) { p.scheme = (int)val; found = 1; }
        if (!found) {
            fprintf(stderr, "two_mass_driver: unknown parameter in '%s'\n", argv[i]);
            return 2;
        }
    }
    const eng_alloc al = {d_alloc, d_free, NULL};
    static tm_model m; /* the engine points into it: it stays put */
    char buf[256];
    const char *err = NULL;
    if (!tm_model_init(&m, &p, &al, buf, sizeof buf, &err)) {
        fprintf(stderr, "two_mass_driver: %s\n", err);
        return 2;
    }
    eng_state s;
    if (!eng_state_init(m.E, &s, 0)) {
        fprintf(stderr, "two_mass_driver: out of memory\n");
        return 2;
    }
    eng_inputs in;
    memset(&in, 0, sizeof in);
    const double x0[2] = {p.x1_0, p.x2_0}, v0[2] = {p.v1_0, p.v2_0};
    eng_start(m.E, &in, 0.0, x0, v0, &s);
    const long steps = (long)floor(t_end / dt + 0.5);
    for (long k = 0; k <= steps; k++) {
        if (k > 0) {
            const eng_status st = eng_advance(m.E, &in, &s, (double)k * dt, NULL);
            if (st != ENG_OK) {
                fprintf(stderr, "two_mass_driver: step to %g failed: %s\n", (double)k * dt, eng_status_text(st));
                return 2;
            }
        }
        printf("%.17g %.17g %.17g %.17g %.17g %d %d\n", (double)k * dt, s.X[0], s.X[1], s.V[0], s.V[1], s.mode[0],
               s.mode[1]);
    }
    eng_state_free(m.E, &s);
    tm_model_free(&m, &al);
    return 0;
}
