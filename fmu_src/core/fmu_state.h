/* The one serialised FMU-state format of every model: a header written and checked here, then the
 * model's own fields, written by the model through the cursor below (fixed-size little-endian
 * fields, the same bytes on every platform), the run (dfo_run) among them.
 *
 *   bytes  0 ..  7  magic "DFOSTATE"
 *          8 .. 11  format version (u32, DFO_STATE_VERSION)
 *         12 .. 15  size of the body, the bytes after the header (u32)
 *         16 .. 23  checksum (u64, FNV-1a) of every byte from 24 to the end
 *         24 .. 31  model hash (u64, FNV-1a of the model's GUID): a state of another model is refused
 *         32 ..     the model's fields
 *
 * Version 4 was the first of this format; version 5 adds the oscillator's open stuck stretch (the
 * start of the stick being observed); in version 6 (the models on the friction engine) the mode of a
 * contact without friction is the direction of its slip relative to its belt (before: of the
 * block's velocity); version 7 adds each contact's mode changes in the observation window to the
 * structure's observables. Earlier versions (the oscillator's 3, magic "DFOSTATE",
 * and the chain's 1, magic "DFCSTATE", each with a 24-byte header) are refused with a sentence
 * naming the version found and the one expected. No FMI types. */
#ifndef DFO_FMU_STATE_H
#define DFO_FMU_STATE_H

#include "instance.h"

#include <stddef.h>
#include <stdint.h>

#define DFO_STATE_VERSION 7u
#define DFO_STATE_HEADER_BYTES 32u
#define DFO_STATE_RUN_BYTES 40u /* a dfo_run: time, start, stop (f64), stop_defined, phase, event (i32 x 4) */

/* ---- FMU states in memory: blocks from the host that start with the model's tag (a uint64_t) ---- */

/* The block when state is one tagged so, else NULL (logged, fn naming the caller). */
void *dfo_state_block(const dfo_lifecycle *lc, const char *fn, const void *state, uint64_t tag);
/* *state made a block of size bytes tagged so: kept when it is one (*fresh 0), a new zeroed one when
 * *state is NULL (*fresh 1); DFO_INST_ERROR (logged) when it is another's or memory is short. */
dfo_inst_status dfo_state_take(const dfo_lifecycle *lc, const char *fn, void **state, uint64_t tag, size_t size,
                               int *fresh);
/* Whether *state is NULL or one of tag's (logged when neither); dfo_state_drop then frees the block
 * (the model has released what it holds) and sets *state to NULL. */
int dfo_state_droppable(const dfo_lifecycle *lc, const char *fn, void *const *state, uint64_t tag);
void dfo_state_drop(const dfo_lifecycle *lc, void **state);

/* ---- serialised FMU states ---- */

/* FNV-1a over n bytes. */
uint64_t dfo_state_checksum(const unsigned char *p, size_t n);

/* Write the header before a body of `body` bytes already at buf + DFO_STATE_HEADER_BYTES. */
void dfo_state_seal(unsigned char *buf, size_t body, const char *guid);
/* Check the header of size bytes at buf against the model (guid): magic, version, model, size and
 * checksum; on success *body is the body's size. Logs why not (fn names the caller). */
dfo_inst_status dfo_state_open(const dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                               const char *guid, size_t *body);

/* Fixed-size little-endian fields: p writes, q reads. */
typedef struct {
    unsigned char *p;
    const unsigned char *q;
} dfo_cursor;

void dfo_put_u64(dfo_cursor *c, uint64_t x);
void dfo_put_u32(dfo_cursor *c, uint32_t x);
void dfo_put_i32(dfo_cursor *c, int x);
void dfo_put_f64(dfo_cursor *c, double x);
void dfo_put_f64s(dfo_cursor *c, const double *x, size_t n);
void dfo_put_bytes(dfo_cursor *c, const void *x, size_t n);
uint64_t dfo_get_u64(dfo_cursor *c);
uint32_t dfo_get_u32(dfo_cursor *c);
int dfo_get_i32(dfo_cursor *c);
double dfo_get_f64(dfo_cursor *c);
void dfo_get_f64s(dfo_cursor *c, double *x, size_t n);
void dfo_get_bytes(dfo_cursor *c, void *x, size_t n);

/* The run's DFO_STATE_RUN_BYTES (host time first). */
void dfo_put_run(dfo_cursor *c, const dfo_run *r);
void dfo_get_run(dfo_cursor *c, dfo_run *r);

/* ---- a model whose whole state is one fixed-size block of values (plain data, no pointers) ----
 * In memory: the tag, the run and a copy of the values; serialised: the values' bytes, then the
 * run. The model checks what it reads back (dfo_values_state_read hands it the values and the run
 * before anything is stored). */

/* Store the run and vsize bytes of values into *state (made a block tagged so when NULL). */
dfo_inst_status dfo_values_state_store(const dfo_lifecycle *lc, const char *fn, void **state, uint64_t tag,
                                       const dfo_run *run, const void *values, size_t vsize);
/* The stored values of a state tagged so (its run into *run), else NULL (logged). */
const void *dfo_values_state_get(const dfo_lifecycle *lc, const char *fn, const void *state, uint64_t tag,
                                 dfo_run *run);
/* The serialised size of a state tagged so, else 0. */
size_t dfo_values_state_size(const void *state, uint64_t tag, size_t vsize);
/* Serialise a state tagged so into buf (size bytes; the model's GUID in the header). */
dfo_inst_status dfo_values_state_serialize(const dfo_lifecycle *lc, const char *fn, const void *state, uint64_t tag,
                                           size_t vsize, unsigned char *buf, size_t size, const char *guid);
/* Read a serialised state (header checked against guid, its body of exactly vsize + the run's
 * bytes) into values and *run; logs why not. */
dfo_inst_status dfo_values_state_read(const dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                                      const char *guid, size_t vsize, void *values, dfo_run *run);
/* instance.h's dfo_inst_free_state, dfo_inst_state_size and dfo_inst_serialize of such a model (its
 * values type VALUES, its tag TAG, its GUID): the model writes get, set and deserialize itself. */
#define DFO_VALUES_STATE_ENTRY_POINTS(VALUES, TAG, GUID)                                                        \
    dfo_inst_status dfo_inst_free_state(dfo_lifecycle *lc, const char *fn, void **state)                       \
    {                                                                                                          \
        if (!dfo_state_droppable(lc, fn, state, (TAG))) return DFO_INST_ERROR;                                 \
        dfo_state_drop(lc, state);                                                                             \
        return DFO_INST_OK;                                                                                    \
    }                                                                                                          \
    size_t dfo_inst_state_size(const dfo_lifecycle *lc, const void *state)                                     \
    {                                                                                                          \
        (void)lc;                                                                                              \
        return dfo_values_state_size(state, (TAG), sizeof(VALUES));                                            \
    }                                                                                                          \
    dfo_inst_status dfo_inst_serialize(dfo_lifecycle *lc, const char *fn, const void *state, unsigned char *buf, \
                                       size_t size)                                                            \
    {                                                                                                          \
        return dfo_values_state_serialize(lc, fn, state, (TAG), sizeof(VALUES), buf, size, (GUID));            \
    }

#endif
