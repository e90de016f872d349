/* The DryFrictionSystem's start values from its FMU's resources (sys_inst_resources.c): the hook of
 * dfo_lifecycle.resources (core/instance.h). No FMI types. */
#ifndef DFO_SYS_INST_RESOURCES_H
#define DFO_SYS_INST_RESOURCES_H

#include "instance.h"
#include "sys_instance.h" /* DFO_SYSTEM_FIXED_N, DFO_FMI2_ARRAYS */

#include <stddef.h>

/* The file under the resources folder that holds a structure's start values. */
#define SYS_RESOURCES_FILE "structure.bin"

/* op DFO_RES_LOAD: read dir/structure.bin (no file, or dir NULL: nothing to do) and make its values
 * the instance's start values; a bad or truncated file is DFO_INST_ERROR with one sentence naming
 * the file and the problem. DFO_RES_APPLY: those values again (after a reset). DFO_RES_FREE: release
 * what was read. */
dfo_inst_status sys_inst_resources(dfo_lifecycle *lc, const char *dir, int op);

#if defined(DFO_SYSTEM_FIXED_N)
/* An FMI 2.0 build: the layout the structure file gave, the head of what dfo_lifecycle.res holds (the
 * record of sys_inst_resources.c begins with it). */
typedef struct {
    int has_layout;                          /* 1: the file's layout, else the build's */
    unsigned int first[DFO_FMI2_NUM_ARRAYS]; /* each array's first element (DFO_FMI2_ARRAYS' order) */
} sys_res_layout;

/* The value reference of the first element of array a (DFO_FMI2_ARRAYS' order) for the instance's
 * sizes: the structure file's layout when it gives one, the build's otherwise. (Inline: the instance
 * core reads it without calling into the file's reader, which calls the core.) */
static inline unsigned int sys_res_fmi2_first(const dfo_lifecycle *lc, size_t a)
{
    const sys_res_layout *r = (const sys_res_layout *)lc->res;
    return (r && r->has_layout) ? r->first[a] : DFO_FMI2_ARRAYS[a].first;
}
#endif

#endif
