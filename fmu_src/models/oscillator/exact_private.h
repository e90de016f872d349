/* What the exact scheme's files share (private: exact.h is the public header): the rounding level
 * of their zero tests and the inlining of the event loop (exact_loop.h). */
#ifndef DFO_EXACT_PRIVATE_H
#define DFO_EXACT_PRIVATE_H

#include "dfo_inline.h"
#include "exact.h"

#include <float.h>

/* the relative rounding level of the zero tests (as the 40-digit references) */
#define DFO_EXACT_ROUND (64.0 * DBL_EPSILON)

/* For exact_loop.h, exact_spring.c and exact_free.c: the event loop is compiled once for each kind of
 * inputs (held, polynomial: a constant in each), so that the loop of held inputs carries none of the
 * polynomial inputs' code. */
#define DFO_EXACT_INLINE DFO_FORCE_INLINE

#endif
