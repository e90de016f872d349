/* The one assertion kit of the C tests: the physics' unit tests (tests/c), the C FMI hosts
 * (tests/fmi_c, tests/fmi3_c) and the instance core's test.
 *
 * A test keeps a `checks` record (no global state) and passes it around; the macros expect a
 * pointer to it named `T` in scope. A failed check prints file:line, what was checked, the
 * expected and the obtained value, and is counted; the first CHECK_MAX_REPORT failures of a run
 * are printed, the rest only counted. checks_done() prints the tally and gives the exit code.
 *
 * The FMI hosts' names are kept as thin synonyms: `tally` is `checks`, EXPECT(cond) is CHECK(cond)
 * (expect_() is check_true_()), and tally_done() is checks_done() followed by the hosts' second
 * closing line "<passed> passed, <failed> failed". ctest decides on the exit code alone (no
 * PASS_REGULAR_EXPRESSION in the CMake files); the closing lines are for the reader and the logs. */
#ifndef DFO_TEST_CHECK_H
#define DFO_TEST_CHECK_H

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#ifndef CHECK_MAX_REPORT
#define CHECK_MAX_REPORT 40
#endif

typedef struct {
    long checks, failures;
    const char *context;  /* printed with every failure: the case being tested */
    char context_buf[512];
} checks;

static inline void check_fail_header(checks *T, const char *file, int line)
{
    T->failures++;
    if (T->failures <= CHECK_MAX_REPORT)
        fprintf(stderr, "%s:%d: FAILED%s%s\n", file, line, T->context ? " in " : "",
                T->context ? T->context : "");
    else if (T->failures == CHECK_MAX_REPORT + 1)
        fprintf(stderr, "... further failures are counted, not printed\n");
}

/* Describe the case under test (printf format), shown with any failure until changed. */
static inline void check_context(checks *T, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(T->context_buf, sizeof T->context_buf, fmt, ap);
    va_end(ap);
    T->context = T->context_buf;
}

static inline int check_true_(checks *T, int ok, const char *file, int line, const char *expr)
{
    T->checks++;
    if (ok) return 1;
    check_fail_header(T, file, line);
    if (T->failures <= CHECK_MAX_REPORT) fprintf(stderr, "    expected true: %s\n", expr);
    return 0;
}

static inline int check_int_(checks *T, long long expected, long long got, const char *file, int line,
                      const char *expr)
{
    T->checks++;
    if (expected == got) return 1;
    check_fail_header(T, file, line);
    if (T->failures <= CHECK_MAX_REPORT)
        fprintf(stderr, "    %s: expected %lld, got %lld\n", expr, expected, got);
    return 0;
}

/* |got - expected| <= tol (NaN never passes). */
static inline int check_near_(checks *T, double expected, double got, double tol, const char *file, int line,
                       const char *expr)
{
    T->checks++;
    if (fabs(got - expected) <= tol) return 1;
    check_fail_header(T, file, line);
    if (T->failures <= CHECK_MAX_REPORT)
        fprintf(stderr, "    %s: expected %.17g, got %.17g (difference %.3g, tolerance %.3g)\n", expr,
                expected, got, got - expected, tol);
    return 0;
}

/* Bit-for-bit equality of two doubles (so NaN == NaN with the same payload, +0 != -0). */
static inline int check_same_(checks *T, double expected, double got, const char *file, int line, const char *expr)
{
    T->checks++;
    if (memcmp(&expected, &got, sizeof expected) == 0) return 1;
    check_fail_header(T, file, line);
    if (T->failures <= CHECK_MAX_REPORT)
        fprintf(stderr, "    %s: expected %.17g, got %.17g (not bit-identical)\n", expr, expected, got);
    return 0;
}

/* lo <= got <= hi */
static inline int check_range_(checks *T, double lo, double hi, double got, const char *file, int line,
                        const char *expr)
{
    T->checks++;
    if (got >= lo && got <= hi) return 1;
    check_fail_header(T, file, line);
    if (T->failures <= CHECK_MAX_REPORT)
        fprintf(stderr, "    %s: expected in [%.6g, %.6g], got %.17g\n", expr, lo, hi, got);
    return 0;
}

#define CHECK(cond) check_true_(T, (cond) ? 1 : 0, __FILE__, __LINE__, #cond)
#define CHECK_INT(expected, got) check_int_(T, (long long)(expected), (long long)(got), __FILE__, __LINE__, #got)
#define CHECK_NEAR(expected, got, tol) check_near_(T, (expected), (got), (tol), __FILE__, __LINE__, #got)
#define CHECK_SAME(expected, got) check_same_(T, (expected), (got), __FILE__, __LINE__, #got)
#define CHECK_RANGE(lo, hi, got) check_range_(T, (lo), (hi), (got), __FILE__, __LINE__, #got)

/* Print the tally; the process exit code (0 only when nothing failed). */
static inline int checks_done(checks *T, const char *name)
{
    printf("%s: %ld checks, %ld failed\n", name, T->checks, T->failures);
    return T->failures == 0 ? 0 : 1;
}

/* ---- the FMI hosts' names (tests/fmi_c, tests/fmi3_c) ---- */

typedef checks tally;

static inline int expect_(checks *T, int ok, const char *file, int line, const char *what)
{
    return check_true_(T, ok, file, line, what);
}
#define EXPECT(cond) CHECK(cond)

/* checks_done() and the hosts' second closing line; the exit code. */
static inline int tally_done(checks *T, const char *name)
{
    const int rc = checks_done(T, name);
    printf("%ld passed, %ld failed\n", T->checks - T->failures, T->failures);
    return rc;
}

/* splitmix64: a fixed-seed generator private to each test (no rand() global state). */
typedef struct { unsigned long long s; } rng;

static inline unsigned long long rng_next(rng *r)
{
    unsigned long long z = (r->s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

/* uniform in [0, 1) with 53 random bits */
static inline double rng_uniform(rng *r) { return (double)(rng_next(r) >> 11) * 0x1.0p-53; }

/* uniform in [a, b) */
static inline double rng_range(rng *r, double a, double b) { return a + (b - a) * rng_uniform(r); }

/* log-uniform magnitude in [10^e0, 10^e1) */
static inline double rng_decades(rng *r, double e0, double e1) { return pow(10.0, rng_range(r, e0, e1)); }

/* integer in [0, n) */
static inline int rng_int(rng *r, int n) { return (int)(rng_next(r) % (unsigned long long)n); }

#endif
