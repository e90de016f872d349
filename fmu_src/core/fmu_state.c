/* The serialised FMU-state format (fmu_state.h): header, checksum, fixed-size fields. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "fmu_state.h"

#include <string.h>

#define MAGIC "DFOSTATE"
#define OLD_CHAIN_MAGIC "DFCSTATE" /* the chain's format before version 4 */

uint64_t dfo_state_checksum(const unsigned char *p, size_t n)
{
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

void *dfo_state_block(const dfo_lifecycle *lc, const char *fn, const void *state, uint64_t tag)
{
    uint64_t t = 0;
    if (state) memcpy(&t, state, sizeof t);
    if (state && t == tag) return (void *)state;
    dfo_inst_fail(lc, "%s: FMUstate is NULL or not a state of this FMU.", fn);
    return NULL;
}

dfo_inst_status dfo_state_take(const dfo_lifecycle *lc, const char *fn, void **state, uint64_t tag, size_t size,
                               int *fresh)
{
    *fresh = 0;
    if (*state) {
        uint64_t t = 0;
        memcpy(&t, *state, sizeof t);
        return t == tag ? DFO_INST_OK : dfo_inst_fail(lc, "%s: *FMUstate is not a state of this FMU.", fn);
    }
    void *block = lc->host.alloc(lc->host.ctx, 1, size);
    if (!block) return dfo_inst_fail(lc, "%s: out of memory.", fn);
    memcpy(block, &tag, sizeof tag);
    *state = block;
    *fresh = 1;
    return DFO_INST_OK;
}

int dfo_state_droppable(const dfo_lifecycle *lc, const char *fn, void *const *state, uint64_t tag)
{
    if (!*state) return 1;
    uint64_t t = 0;
    memcpy(&t, *state, sizeof t);
    if (t == tag) return 1;
    dfo_inst_fail(lc, "%s: *FMUstate is not a state of this FMU.", fn);
    return 0;
}

void dfo_state_drop(const dfo_lifecycle *lc, void **state)
{
    if (!*state) return;
    const uint64_t none = 0;
    memcpy(*state, &none, sizeof none); /* a freed state is never taken for one */
    lc->host.free(lc->host.ctx, *state);
    *state = NULL;
}

static uint64_t model_hash(const char *guid) { return dfo_state_checksum((const unsigned char *)guid, strlen(guid)); }

void dfo_state_seal(unsigned char *buf, size_t body, const char *guid)
{
    dfo_cursor c = {buf, NULL};
    dfo_put_bytes(&c, MAGIC, 8);
    dfo_put_u32(&c, DFO_STATE_VERSION);
    dfo_put_u32(&c, (uint32_t)body);
    unsigned char *sum = c.p;
    c.p += 8;
    dfo_put_u64(&c, model_hash(guid));
    c.p = sum;
    dfo_put_u64(&c, dfo_state_checksum(buf + 24, DFO_STATE_HEADER_BYTES - 24 + body));
}

dfo_inst_status dfo_state_open(const dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                               const char *guid, size_t *body)
{
    if (size < 16 || (memcmp(buf, MAGIC, 8) != 0 && memcmp(buf, OLD_CHAIN_MAGIC, 8) != 0))
        return dfo_inst_fail(lc, "%s: %lu bytes that are not a serialised state of this FMU.", fn,
                             (unsigned long)size);
    dfo_cursor c = {NULL, buf + 8};
    const uint32_t version = dfo_get_u32(&c), n = dfo_get_u32(&c);
    if (version != DFO_STATE_VERSION || memcmp(buf, MAGIC, 8) != 0)
        return dfo_inst_fail(lc, "%s: not a serialised state of this FMU version: the state has format version %u "
                             "(%s), this FMU reads format version %u only; restore it with the FMU that wrote it.",
                             fn, (unsigned)version, version < DFO_STATE_VERSION ? "an earlier one" : "an unknown one",
                             DFO_STATE_VERSION);
    if (size < DFO_STATE_HEADER_BYTES || size - DFO_STATE_HEADER_BYTES != (size_t)n)
        return dfo_inst_fail(lc, "%s: %lu bytes given, the state's header says %lu.", fn, (unsigned long)size,
                             (unsigned long)(DFO_STATE_HEADER_BYTES + (size_t)n));
    const uint64_t sum = dfo_get_u64(&c), model = dfo_get_u64(&c);
    if (dfo_state_checksum(buf + 24, size - 24) != sum)
        return dfo_inst_fail(lc, "%s: checksum mismatch, the serialised state is corrupted.", fn);
    if (model != model_hash(guid))
        return dfo_inst_fail(lc, "%s: not a serialised state of this FMU: it was written by another model (its "
                             "GUID hash differs from this FMU's).", fn);
    *body = n;
    return DFO_INST_OK;
}

void dfo_put_u64(dfo_cursor *c, uint64_t x)
{
    for (int b = 0; b < 8; b++) *c->p++ = (unsigned char)(x >> (8 * b));
}
void dfo_put_u32(dfo_cursor *c, uint32_t x)
{
    for (int b = 0; b < 4; b++) *c->p++ = (unsigned char)(x >> (8 * b));
}
void dfo_put_i32(dfo_cursor *c, int x) { dfo_put_u32(c, (uint32_t)x); }
void dfo_put_f64(dfo_cursor *c, double x)
{
    uint64_t u;
    memcpy(&u, &x, 8);
    dfo_put_u64(c, u);
}
void dfo_put_f64s(dfo_cursor *c, const double *x, size_t n)
{
    for (size_t i = 0; i < n; i++) dfo_put_f64(c, x[i]);
}
void dfo_put_bytes(dfo_cursor *c, const void *x, size_t n)
{
    memcpy(c->p, x, n);
    c->p += n;
}
uint64_t dfo_get_u64(dfo_cursor *c)
{
    uint64_t x = 0;
    for (int b = 0; b < 8; b++) x |= (uint64_t)*c->q++ << (8 * b);
    return x;
}
uint32_t dfo_get_u32(dfo_cursor *c)
{
    uint32_t x = 0;
    for (int b = 0; b < 4; b++) x |= (uint32_t)*c->q++ << (8 * b);
    return x;
}
int dfo_get_i32(dfo_cursor *c) { return (int)(int32_t)dfo_get_u32(c); }
double dfo_get_f64(dfo_cursor *c)
{
    const uint64_t u = dfo_get_u64(c);
    double x;
    memcpy(&x, &u, 8);
    return x;
}
void dfo_get_f64s(dfo_cursor *c, double *x, size_t n)
{
    for (size_t i = 0; i < n; i++) x[i] = dfo_get_f64(c);
}
void dfo_get_bytes(dfo_cursor *c, void *x, size_t n)
{
    memcpy(x, c->q, n);
    c->q += n;
}

void dfo_put_run(dfo_cursor *c, const dfo_run *r)
{
    dfo_put_f64(c, r->time);
    dfo_put_f64(c, r->start_time);
    dfo_put_f64(c, r->stop_time);
    dfo_put_i32(c, r->stop_defined);
    dfo_put_i32(c, (int)r->phase);
    dfo_put_i32(c, r->event_pending);
    dfo_put_i32(c, r->event_from);
}

void dfo_get_run(dfo_cursor *c, dfo_run *r)
{
    r->time = dfo_get_f64(c);
    r->start_time = dfo_get_f64(c);
    r->stop_time = dfo_get_f64(c);
    r->stop_defined = dfo_get_i32(c);
    r->phase = (dfo_phase)dfo_get_i32(c);
    r->event_pending = dfo_get_i32(c);
    r->event_from = dfo_get_i32(c);
}

/* ---- a model whose whole state is one fixed-size block of values ---- */

/* The block: the tag, the run, then the values at an offset kept aligned for any of their fields. */
typedef struct {
    uint64_t tag;
    dfo_run run;
} values_head;
#define VALUES_OFFSET ((sizeof(values_head) + 15u) / 16u * 16u)

dfo_inst_status dfo_values_state_store(const dfo_lifecycle *lc, const char *fn, void **state, uint64_t tag,
                                       const dfo_run *run, const void *values, size_t vsize)
{
    int fresh;
    if (dfo_state_take(lc, fn, state, tag, VALUES_OFFSET + vsize, &fresh) != DFO_INST_OK) return DFO_INST_ERROR;
    values_head *h = (values_head *)*state;
    h->run = *run;
    memcpy((unsigned char *)*state + VALUES_OFFSET, values, vsize);
    return DFO_INST_OK;
}

const void *dfo_values_state_get(const dfo_lifecycle *lc, const char *fn, const void *state, uint64_t tag,
                                 dfo_run *run)
{
    const values_head *h = (const values_head *)dfo_state_block(lc, fn, state, tag);
    if (!h) return NULL;
    if (run) *run = h->run;
    return (const unsigned char *)h + VALUES_OFFSET;
}

size_t dfo_values_state_size(const void *state, uint64_t tag, size_t vsize)
{
    uint64_t t = 0;
    if (state) memcpy(&t, state, sizeof t);
    return (state && t == tag) ? DFO_STATE_HEADER_BYTES + vsize + DFO_STATE_RUN_BYTES : 0;
}

dfo_inst_status dfo_values_state_serialize(const dfo_lifecycle *lc, const char *fn, const void *state, uint64_t tag,
                                           size_t vsize, unsigned char *buf, size_t size, const char *guid)
{
    dfo_run run;
    const void *values = dfo_values_state_get(lc, fn, state, tag, &run);
    if (!values) return DFO_INST_ERROR;
    const size_t body = vsize + DFO_STATE_RUN_BYTES;
    if (size < DFO_STATE_HEADER_BYTES + body)
        return dfo_inst_fail(lc, "%s: buffer of %lu bytes is too small (%lu needed).", fn, (unsigned long)size,
                             (unsigned long)(DFO_STATE_HEADER_BYTES + body));
    dfo_cursor c = {buf + DFO_STATE_HEADER_BYTES, NULL};
    dfo_put_bytes(&c, values, vsize);
    dfo_put_run(&c, &run);
    dfo_state_seal(buf, body, guid);
    return DFO_INST_OK;
}

dfo_inst_status dfo_values_state_read(const dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                                      const char *guid, size_t vsize, void *values, dfo_run *run)
{
    size_t body = 0;
    if (dfo_state_open(lc, fn, buf, size, guid, &body) != DFO_INST_OK) return DFO_INST_ERROR;
    if (body != vsize + DFO_STATE_RUN_BYTES)
        return dfo_inst_fail(lc, "%s: %lu bytes given, a state of this FMU has %lu.", fn, (unsigned long)size,
                             (unsigned long)(DFO_STATE_HEADER_BYTES + vsize + DFO_STATE_RUN_BYTES));
    dfo_cursor c = {NULL, buf + DFO_STATE_HEADER_BYTES};
    dfo_get_bytes(&c, values, vsize);
    dfo_get_run(&c, run);
    return DFO_INST_OK;
}
