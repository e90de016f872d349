/* The friction engine's schemes (engine_step.h) over any model's operators, reached through
 * eng_ops's function pointers: eng_start, eng_advance, eng_new_inputs, eng_accelerations,
 * eng_contact_forces, eng_snap_target and the default friction solver eng_dense_friction (engine.h).
 * A model that instantiates engine_step.h with its own inline operators does not need this file. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "engine_private.h"

#include "engine_step.h" /* the schemes, the operators through eng_ops */
