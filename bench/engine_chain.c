/* bench_engine's chain: the engine's schemes (fmu_src/engine/engine_step.h) specialised by the
 * chain's inline operators (engine_models.h: Thomas's tridiagonal solve, the box LCP), as
 * chn_eng_start and chn_eng_advance. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */

#include "engine_models.h"

#define ENG_FN(name) chn_##name
#define ENG_CTX(E) ((E)->S.ops.ctx)
#define ENG_APPLY_K(E, x, y) chn_K(ENG_CTX(E), (x), (y))
#define ENG_APPLY_C(E, v, y) ((void)(E), (void)(v), (void)(y))
#define ENG_HAS_C(E) ((void)(E), 0)
#define ENG_APPLY_M(E, a, y) chn_M(ENG_CTX(E), (a), (y))
#define ENG_FACTOR(E, slot, cM, cC, cK) chn_factor(ENG_CTX(E), (slot), (cM), (cC), (cK))
#define ENG_SOLVE(E, slot, b, x) chn_solve(ENG_CTX(E), (slot), (b), (x))
#define ENG_HAS_FRICTION(E) ((void)(E), 1)
#define ENG_FRICTION(E, P, what, mode, V1, f, pivots) chn_friction(ENG_CTX(E), (P), (what), (mode), (V1), (f), (pivots))
#define ENG_STEP_HELD(E, F, s) chn_step_held(ENG_CTX(E), (F), (s))

#include "engine_step.h"
