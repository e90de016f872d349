/* bench_engine's one block: the engine's schemes (fmu_src/engine/engine_step.h) specialised by the
 * block's inline operators (engine_models.h) and its sizes (one DOF, one contact: the loops
 * unroll), as blk_eng_start and blk_eng_advance. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */

#include "engine_models.h"

#define ENG_FN(name) blk_##name
#define ENG_N(E) ((void)(E), (size_t)1)
#define ENG_NC(E) ((void)(E), (size_t)1)
#define ENG_CTX(E) ((E)->S.ops.ctx)
#define ENG_APPLY_K(E, x, y) blk_K(ENG_CTX(E), (x), (y))
#define ENG_APPLY_C(E, v, y) blk_C(ENG_CTX(E), (v), (y))
#define ENG_HAS_C(E) ((void)(E), 1)
#define ENG_APPLY_M(E, a, y) blk_M(ENG_CTX(E), (a), (y))
#define ENG_FACTOR(E, slot, cM, cC, cK) blk_factor(ENG_CTX(E), (slot), (cM), (cC), (cK))
#define ENG_SOLVE(E, slot, b, x) blk_solve(ENG_CTX(E), (slot), (b), (x))
#define ENG_HAS_FRICTION(E) ((void)(E), 1)
#define ENG_FRICTION(E, P, what, mode, V1, f, pivots) blk_friction(ENG_CTX(E), (P), (what), (mode), (V1), (f), (pivots))
#define ENG_HAS_BREAKAWAY(E) ((E)->S.ops.breakaway != NULL)
#define ENG_BREAKAWAY(E, s, in, Fb) blk_breakaway(ENG_CTX(E), &(E)->S.exc, (s), (in), (Fb))

#include "engine_step.h"
