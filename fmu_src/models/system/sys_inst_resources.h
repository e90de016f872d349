/* The DryFrictionSystem's start values from its FMU's resources (sys_inst_resources.c): the hook of
 * dfo_lifecycle.resources (core/instance.h). No FMI types. */
#ifndef DFO_SYS_INST_RESOURCES_H
#define DFO_SYS_INST_RESOURCES_H

#include "instance.h"

/* The file under the resources folder that holds a structure's start values. */
#define SYS_RESOURCES_FILE "structure.bin"

/* op DFO_RES_LOAD: read dir/structure.bin (no file, or dir NULL: nothing to do) and make its values
 * the instance's start values; a bad or truncated file is DFO_INST_ERROR with one sentence naming
 * the file and the problem. DFO_RES_APPLY: those values again (after a reset). DFO_RES_FREE: release
 * what was read. */
dfo_inst_status sys_inst_resources(dfo_lifecycle *lc, const char *dir, int op);

#endif
