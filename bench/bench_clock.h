/* A monotonic clock for the benchmarks, in ns: clock_gettime on POSIX, QueryPerformanceCounter on
 * Windows (which has no clock_gettime), so that the cross builds compile every benchmark; the
 * thread's CPU time where there is one (bench_seconds); the parse of a list of sizes. */
#ifndef DFO_BENCH_CLOCK_H
#define DFO_BENCH_CLOCK_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
static double bench_now_ns(void)
{
    LARGE_INTEGER f, c;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&c);
    return 1e9 * ((double)c.QuadPart / (double)f.QuadPart);
}
#else
#include <time.h>
static double bench_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e9 * (double)ts.tv_sec + (double)ts.tv_nsec;
}
#endif

/* The clock of a timing (s): the thread's CPU time where POSIX has it (time the thread spends
 * descheduled on a shared machine is not the code's), else (or with wall) the monotonic clock. */
static inline double bench_seconds(int wall)
{
#if defined(CLOCK_THREAD_CPUTIME_ID) && !defined(_WIN32)
    struct timespec ts;
    if (!wall && clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) == 0)
        return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
#else
    (void)wall;
#endif
    return 1e-9 * bench_now_ns();
}

/* The options of a timed run that bench_chain and bench_engine share: --reps N, --periods P,
 * --steps-per-period S, --csv FILE, --n N[,N...] (at most max_n sizes into ns, nn of them).
 * bench_run_opt reads argv[*a] when it is one of them (then *a moves onto its value, and it
 * returns 1); bench_run_opts_bad says, in one line on stderr, what is out of range (1) or nothing
 * (0). */
typedef struct {
    int reps;
    double periods, spp;
    const char *csv;
    size_t *ns;
    int max_n, nn;
} bench_run_opts;

static inline int bench_sizes(char *list, size_t *ns, int max);

static inline int bench_run_opt(int argc, char **argv, int *a, bench_run_opts *o)
{
    if (*a + 1 >= argc) return 0;
    const char *k = argv[*a];
    if (!strcmp(k, "--reps")) o->reps = atoi(argv[++*a]);
    else if (!strcmp(k, "--periods")) o->periods = atof(argv[++*a]);
    else if (!strcmp(k, "--steps-per-period")) o->spp = atof(argv[++*a]);
    else if (!strcmp(k, "--csv")) o->csv = argv[++*a];
    else if (!strcmp(k, "--n")) o->nn = bench_sizes(argv[++*a], o->ns, o->max_n);
    else return 0;
    return 1;
}

static inline int bench_run_opts_bad(const bench_run_opts *o, const char *prog)
{
    int sizes_ok = o->nn >= 1;
    for (int j = 0; j < o->nn; j++) sizes_ok &= o->ns[j] >= 1;
    if (o->reps >= 1 && o->periods > 0.0 && o->spp >= 10.0 && sizes_ok) return 0;
    fprintf(stderr, "%s: --reps >= 1, --periods > 0, --steps-per-period >= 10, --n sizes >= 1\n", prog);
    return 1;
}

/* Where the CSV goes: --csv's file, else stdout; NULL (and one line on stderr) when it cannot be
 * written. */
static inline FILE *bench_out(const bench_run_opts *o, const char *prog)
{
    FILE *f = o->csv ? fopen(o->csv, "w") : stdout;
    if (!f) fprintf(stderr, "%s: cannot write %s\n", prog, o->csv);
    return f;
}

/* A comma-separated list of sizes ("1,8,64") into ns (at most max of them); how many were read. */
static inline int bench_sizes(char *list, size_t *ns, int max)
{
    int n = 0;
    for (char *tok = strtok(list, ","); tok && n < max; tok = strtok(NULL, ",")) ns[n++] = (size_t)atol(tok);
    return n;
}

#endif
