/* A tally of checks for the C FMI hosts (tests/fmi_c, tests/fmi3_c): EXPECT(cond) counts, prints
 * the first 50 failures with their place, and tally_done() prints the closing line CI reads. */
#ifndef DFO_TESTS_TALLY_H
#define DFO_TESTS_TALLY_H

#include <stdio.h>

typedef struct {
    long checks, failures;
} tally;

static inline int expect_(tally *T, int ok, const char *file, int line, const char *what)
{
    T->checks++;
    if (!ok) {
        T->failures++;
        if (T->failures <= 50) fprintf(stderr, "%s:%d: FAILED: %s\n", file, line, what);
    }
    return ok;
}
#define EXPECT(cond) expect_(T, (cond) ? 1 : 0, __FILE__, __LINE__, #cond)

static inline int tally_done(const tally *T, const char *name)
{
    printf("%s: %ld checks, %ld failed\n", name, T->checks, T->failures);
    printf("%ld passed, %ld failed\n", T->checks - T->failures, T->failures);
    return T->failures ? 1 : 0;
}

#endif
