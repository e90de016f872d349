/* The DryFrictionSystem's start values from its FMU's resources: the file resources/structure.bin a
 * structure's FMU carries (written by dryfriction.system.fmu), read once at instantiation and applied
 * again after every reset, so that the binary's defaults are the structure's whatever the host sets.
 *
 * The file, little-endian throughout (assembled byte by byte: the same on every platform):
 *   bytes  0..7   the magic "DFOSTRUC"
 *          8..11  uint32 version (1)
 *         12..15  uint32 the number of records
 *         16..23  uint64 n
 *         24..31  uint64 nc
 *   version 2 then: uint32 the number of layout entries, uint32 0, and each entry uint32 an array's
 *   own value reference, uint32 its first element's FMI 2.0 value reference: the layout of the FMI
 *   2.0 description written for n, nc (dryfriction.model.fmi2_layout, the generator's), every array
 *   once in the order of its value reference, each after the previous array's elements and within 32
 *   bits; an FMI 2.0 binary resolves value references through it (any n, nc), an FMI 3.0 binary
 *   checks it and has no use for it. Version 1 has none: an FMI 2.0 binary then serves its own sizes.
 *   then each record: uint32 a parameter's value reference (FMI 3.0's), uint32 0, uint64 the number
 *   of its values (1 for a scalar, its size at n, nc for an array), that many IEEE 754 doubles.
 * Every size is checked against the file's length and every value against the parameter's range;
 * the file must end with the last record. No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "sys_inst_resources.h"
#include "sys_instance.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define RES_MAGIC "DFOSTRUC"
#define RES_VERSION 2u /* the newest read; 1 is read too */
#define RES_LAY_HEAD 8u
#define RES_LAY_ENTRY 8u
#define RES_HEAD 32u
#define RES_REC_HEAD 16u

/* What was read: the file's bytes. */
typedef struct {
#if defined(DFO_SYSTEM_FIXED_N)
    sys_res_layout lay; /* first: sys_res_fmi2_first reads it through lc->res */
#endif
    size_t len;
    unsigned char bytes[];
} sys_res;

static uint32_t u32_at(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t u64_at(const unsigned char *p)
{
    return (uint64_t)u32_at(p) | (uint64_t)u32_at(p + 4) << 32;
}

static double f64_at(const unsigned char *p)
{
    const uint64_t u = u64_at(p);
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* The layout section of a version 2 file at *pos (moved past it): every array of the model once, in
 * the order of its value reference, each element's value reference after its own and after the previous
 * array's elements, the last within 32 bits. Stored in res (an FMI 2.0 build; res NULL: only checked).
 * NULL, or the problem in buf. */
static const char *parse_layout(sys_res *res, const unsigned char *b, size_t len, size_t *pos, size_t n, size_t nc,
                                char *buf, size_t blen)
{
    if (len - *pos < RES_LAY_HEAD) {
        snprintf(buf, blen, "is truncated: its layout has no complete header (byte %lu of %lu)", (unsigned long)*pos,
                 (unsigned long)len);
        return buf;
    }
    const uint32_t nlay = u32_at(b + *pos);
    *pos += RES_LAY_HEAD;
    int narrays = 0;
    for (int j = 0; j < DFO_NUM_VARS; j++) narrays += DFO_VARS[j].array != 0;
    if (nlay != (uint32_t)narrays) {
        snprintf(buf, blen, "has a layout of %lu arrays; this FMU has %d", (unsigned long)nlay, narrays);
        return buf;
    }
    if ((len - *pos) / RES_LAY_ENTRY < nlay) {
        snprintf(buf, blen, "is truncated: its layout of %lu arrays needs %lu bytes, %lu are left", (unsigned long)nlay,
                 (unsigned long)(RES_LAY_ENTRY * nlay), (unsigned long)(len - *pos));
        return buf;
    }
    uint64_t end = 0;
    uint32_t prev = 0;
    for (uint32_t k = 0; k < nlay; k++, *pos += RES_LAY_ENTRY) {
        const uint32_t vr = u32_at(b + *pos), first = u32_at(b + *pos + 4);
        const dfo_var_info *var = dfo_find_var(vr);
        if (!var || !var->array) {
            snprintf(buf, blen, "has in layout entry %lu the value reference %lu, which is no array of this FMU",
                     (unsigned long)k + 1, (unsigned long)vr);
            return buf;
        }
        if (k > 0 && vr <= prev) {
            snprintf(buf, blen, "lists %s (value reference %lu) in its layout out of the order of the value references "
                     "(after %lu)", var->name, (unsigned long)vr, (unsigned long)prev);
            return buf;
        }
        const uint64_t count = (uint64_t)sys_var_count(var, n, nc);
        if ((uint64_t)first <= (uint64_t)vr || (uint64_t)first < end || (uint64_t)first + count - 1 > 0xFFFFFFFFu) {
            snprintf(buf, blen, "puts the %llu elements of %s at the value references from %lu; valid: from %llu "
                     "(after its own %lu and the previous array's elements), the last at most 4294967295",
                     (unsigned long long)count, var->name, (unsigned long)first,
                     (unsigned long long)(end > (uint64_t)vr + 1 ? end : (uint64_t)vr + 1), (unsigned long)vr);
            return buf;
        }
#if defined(DFO_SYSTEM_FIXED_N)
        /* the build's arrays, in the same order (the generator's DFO_FMI2_ARRAYS) */
        if (vr != DFO_FMI2_ARRAYS[k].vr) {
            snprintf(buf, blen, "has in layout entry %lu the array %s (value reference %lu); this FMU's entry %lu is "
                     "the array of value reference %u", (unsigned long)k + 1, var->name, (unsigned long)vr,
                     (unsigned long)k + 1, DFO_FMI2_ARRAYS[k].vr);
            return buf;
        }
        if (res) res->lay.first[k] = first;
#endif
        end = (uint64_t)first + count;
        prev = vr;
    }
#if defined(DFO_SYSTEM_FIXED_N)
    if (res) res->lay.has_layout = 1;
#else
    (void)res;
#endif
    return NULL;
}

/* Check the file (apply 0) or make its values the instance's (apply 1, after a check). NULL, or the
 * problem in buf. */
static const char *parse(sys_instance *in, sys_res *res, const unsigned char *b, size_t len, int apply, char *buf,
                         size_t blen)
{
    if (len < RES_HEAD) {
        snprintf(buf, blen, "is truncated: %lu bytes, fewer than its %u-byte header", (unsigned long)len, RES_HEAD);
        return buf;
    }
    if (memcmp(b, RES_MAGIC, 8) != 0) return "does not begin with the magic DFOSTRUC: not a structure file";
    const uint32_t version = u32_at(b + 8), nrec = u32_at(b + 12);
    if (version != 1u && version != RES_VERSION) {
        snprintf(buf, blen, "has the version %lu; this FMU reads versions 1 to %u", (unsigned long)version,
                 RES_VERSION);
        return buf;
    }
    const uint64_t n = u64_at(b + 16), nc = u64_at(b + 24);
    if (n < 1 || n > (uint64_t)MAX_n || nc > (uint64_t)MAX_nc) {
        snprintf(buf, blen, "gives n = %llu, nc = %llu; valid: n in [1, %d], nc in [0, %d]", (unsigned long long)n,
                 (unsigned long long)nc, (int)MAX_n, (int)MAX_nc);
        return buf;
    }
    size_t pos = RES_HEAD;
    const char *why = version == 1u ? NULL : parse_layout(res, b, len, &pos, (size_t)n, (size_t)nc, buf, blen);
    if (why) return why;
#if defined(DFO_SYSTEM_FIXED_N)
    /* version 1: the flattened elements' value references are the build's, laid out for its sizes */
    if (version == 1u && (n != (uint64_t)DFO_SYSTEM_FIXED_N || nc != (uint64_t)DFO_SYSTEM_FIXED_NC)) {
        snprintf(buf, blen, "gives n = %llu, nc = %llu and no layout (version 1), but without one this FMI 2.0 binary "
                 "serves n = %d, nc = %d only (its own layout)", (unsigned long long)n, (unsigned long long)nc,
                 (int)DFO_SYSTEM_FIXED_N, (int)DFO_SYSTEM_FIXED_NC);
        return buf;
    }
#endif
    if (apply) {
        if (sys_resize(in, "instantiate", (size_t)n, (size_t)nc) != DFO_INST_OK) return "cannot be applied (out of memory)";
        in->n_config = in->L.n;
        in->nc_config = in->L.nc;
    }
    for (uint32_t r = 0; r < nrec; r++) {
        if (len - pos < RES_REC_HEAD) {
            snprintf(buf, blen, "is truncated: record %lu of %lu has no complete header (byte %lu of %lu)",
                     (unsigned long)r + 1, (unsigned long)nrec, (unsigned long)pos, (unsigned long)len);
            return buf;
        }
        const uint32_t vr = u32_at(b + pos);
        const uint64_t count = u64_at(b + pos + 8);
        pos += RES_REC_HEAD;
        const dfo_var_info *var = dfo_find_var(vr);
        if (!var || var->causality != DFO_PARAMETER ||
            (var->home != DFO_IN_PARAMS && var->home != DFO_IN_ARRAYS)) {
            snprintf(buf, blen, "has in record %lu the value reference %lu, which is no parameter of this FMU",
                     (unsigned long)r + 1, (unsigned long)vr);
            return buf;
        }
        const size_t want = var->home == DFO_IN_ARRAYS ? sys_var_count(var, (size_t)n, (size_t)nc) : 1;
        if (count != (uint64_t)want) {
            snprintf(buf, blen, "gives %s %llu values; with n = %llu, nc = %llu it has %lu", var->name,
                     (unsigned long long)count, (unsigned long long)n, (unsigned long long)nc, (unsigned long)want);
            return buf;
        }
        if ((len - pos) / 8 < want) {
            if (want == 1)
                snprintf(buf, blen, "is truncated: the value of %s needs 8 bytes, %lu are left", var->name,
                         (unsigned long)(len - pos));
            else
                snprintf(buf, blen, "is truncated: the %lu values of %s need %lu bytes, %lu are left",
                         (unsigned long)want, var->name, (unsigned long)(8 * want), (unsigned long)(len - pos));
            return buf;
        }
        double *dst = apply ? in->vals + (var->home == DFO_IN_ARRAYS ? in->L.ap[var->slot] : in->L.sp + (size_t)var->slot)
                            : NULL;
        for (size_t i = 0; i < want; i++, pos += 8) {
            const double x = f64_at(b + pos);
            if (!apply && !(x >= var->min && x <= var->max)) {
                if (want > 1)
                    snprintf(buf, blen, "gives %s element %lu (0-based) the value %.17g; valid range: %s", var->name,
                             (unsigned long)i, x, var->range ? var->range : "finite");
                else
                    snprintf(buf, blen, "gives %s the value %.17g; valid range: %s", var->name, x,
                             var->range ? var->range : "finite");
                return buf;
            }
            if (!apply && var->type != DFO_REAL && x != (double)(long long)x) {
                snprintf(buf, blen, "gives %s the value %.17g, which is not a whole number", var->name, x);
                return buf;
            }
            if (apply) dst[i] = x;
        }
    }
    if (pos != len) {
        snprintf(buf, blen, "has %lu bytes after its last record (%lu records)", (unsigned long)(len - pos),
                 (unsigned long)nrec);
        return buf;
    }
    return NULL;
}

static dfo_inst_status load(sys_instance *in, const char *dir)
{
    dfo_lifecycle *lc = &in->lc;
    if (!dir || !*dir) return DFO_INST_OK;
    const size_t dlen = strlen(dir), flen = sizeof SYS_RESOURCES_FILE;
    const int sep = dir[dlen - 1] != '/' && dir[dlen - 1] != '\\';
    char *path = (char *)lc->host.alloc(lc->host.ctx, dlen + (size_t)sep + flen, 1);
    if (!path) return dfo_inst_fail(lc, "instantiate: out of memory for the resources' path.");
    memcpy(path, dir, dlen);
    if (sep) path[dlen] = '/';
    memcpy(path + dlen + (size_t)sep, SYS_RESOURCES_FILE, flen);
    FILE *f = fopen(path, "rb");
    if (!f) { /* no file: the FMU of no particular structure, its defaults the model description's */
        lc->host.free(lc->host.ctx, path);
        return DFO_INST_OK;
    }
    dfo_inst_status st = DFO_INST_OK;
    sys_res *res = NULL;
    long size = -1;
    if (fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (size < 0 || fseek(f, 0, SEEK_SET) != 0) {
        st = dfo_inst_fail(lc, "instantiate: the structure file %s cannot be read (its length is unknown).", path);
    } else {
        res = (sys_res *)lc->host.alloc(lc->host.ctx, sizeof(sys_res) + (size_t)size + 1, 1);
        if (!res) {
            st = dfo_inst_fail(lc, "instantiate: out of memory for the structure file %s (%ld bytes).", path, size);
        } else {
            res->len = (size_t)size;
#if defined(DFO_SYSTEM_FIXED_N)
            res->lay.has_layout = 0;
#endif
            if (fread(res->bytes, 1, res->len, f) != res->len)
                st = dfo_inst_fail(lc, "instantiate: the structure file %s cannot be read to its end.", path);
        }
    }
    fclose(f);
    if (st == DFO_INST_OK) {
        char buf[256];
        const char *why = parse(in, NULL, res->bytes, res->len, 0, buf, sizeof buf);
        if (!why) why = parse(in, res, res->bytes, res->len, 1, buf, sizeof buf);
        if (why) {
            st = dfo_inst_fail(lc, "instantiate: the structure file %s %s.", path, why);
        } else {
            lc->res = res;
            dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_ALL, "instantiate: start values from %s: n = %lu, nc = %lu.",
                         path, (unsigned long)in->L.n, (unsigned long)in->L.nc);
        }
    }
    if (st != DFO_INST_OK && res) lc->host.free(lc->host.ctx, res);
    lc->host.free(lc->host.ctx, path);
    return st;
}

dfo_inst_status sys_inst_resources(dfo_lifecycle *lc, const char *dir, int op)
{
    sys_instance *in = sysi(lc);
    sys_res *res = (sys_res *)lc->res;
    switch (op) {
    case DFO_RES_LOAD:
        if (res) return DFO_INST_OK;
        return load(in, dir);
    case DFO_RES_APPLY: {
        if (!res) return DFO_INST_OK;
        char buf[256];
        const char *why = parse(in, res, res->bytes, res->len, 1, buf, sizeof buf);
        return why ? dfo_inst_fail(lc, "reset: the structure's start values %s.", why) : DFO_INST_OK;
    }
    case DFO_RES_FREE:
        if (res) lc->host.free(lc->host.ctx, res);
        lc->res = NULL;
        return DFO_INST_OK;
    default:
        return DFO_INST_OK;
    }
}
