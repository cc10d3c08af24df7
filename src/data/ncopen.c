#include "data/ncopen.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/nclock.h"

/* Limits of our own: far above what a weather model writes (a WRF file has a few hundred
 * variables of rank 4), far below what would let a header make us allocate much. */
#define NAME_MAX_BYTES 256 /* NC_MAX_NAME */
#define DIMS_MAX 65536
#define VARS_MAX 65536
#define ATTS_MAX 65536
#define RANK_MAX 1024 /* NC_MAX_VAR_DIMS */

#define TAG_DIMENSION 0x0A
#define TAG_VARIABLE 0x0B
#define TAG_ATTRIBUTE 0x0C

const char *data_nc_format_name(enum data_nc_format f)
{
    switch (f) {
    case DATA_NC_CLASSIC:
        return "classic";
    case DATA_NC_64BIT_OFFSET:
        return "64-bit offset";
    case DATA_NC_64BIT_DATA:
        return "64-bit data (CDF-5)";
    case DATA_NC_HDF5:
        return "NetCDF-4 (HDF5)";
    }
    return "?";
}

/* ---- reading the header: from memory or through a window on a descriptor -------------- */

struct cursor {
    const unsigned char *mem; /* the whole file, or NULL: read through FD */
    int fd;
    uint64_t size, pos;
    unsigned char window[65536];
    uint64_t window_at;
    size_t window_len;
    int version; /* 1, 2 or 5 */
    char *why;
    size_t why_size;
    bool failed;
};

static bool failf(struct cursor *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static bool failf(struct cursor *c, const char *fmt, ...)
{
    if (!c->failed) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->why, c->why_size, fmt, ap);
        va_end(ap);
        c->failed = true;
    }
    return false;
}

/* The N bytes (N <= 8) at the cursor into OUT, and the cursor past them. */
static bool take(struct cursor *c, size_t n, unsigned char *out, const char *what)
{
    if (c->failed)
        return false;
    if (n > c->size || c->pos > c->size - n)
        return failf(c, "the header ends early (at byte %llu, in %s): truncated?",
                     (unsigned long long)c->pos, what);
    if (c->mem) {
        memcpy(out, c->mem + c->pos, n);
    } else {
        if (c->pos < c->window_at || c->pos + n > c->window_at + c->window_len) {
            ssize_t got;
            do
                got = pread(c->fd, c->window, sizeof(c->window), (off_t)c->pos);
            while (got < 0 && errno == EINTR);
            if (got < (ssize_t)n)
                return failf(c, "cannot read the header at byte %llu: %s",
                             (unsigned long long)c->pos, got < 0 ? strerror(errno) : "end of file");
            c->window_at = c->pos;
            c->window_len = (size_t)got;
        }
        memcpy(out, c->window + (c->pos - c->window_at), n);
    }
    c->pos += n;
    return true;
}

static bool skip(struct cursor *c, uint64_t n, const char *what)
{
    if (c->failed)
        return false;
    if (n > c->size - c->pos)
        return failf(c, "%s runs past the end of the file (%llu bytes): truncated?", what,
                     (unsigned long long)c->size);
    c->pos += n;
    return true;
}

static bool u32(struct cursor *c, uint32_t *v, const char *what)
{
    unsigned char b[4];
    if (!take(c, 4, b, what))
        return false;
    *v = (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3];
    return true;
}

/* A count, length or size: 32 bits (CDF-1, CDF-2) or 64 (CDF-5), never negative. */
static bool count(struct cursor *c, uint64_t *v, const char *what)
{
    if (c->version != 5) {
        uint32_t x;
        if (!u32(c, &x, what))
            return false;
        if (x > INT32_MAX)
            return failf(c, "%s is negative (%lld)", what, (long long)(int32_t)x);
        *v = x;
        return true;
    }
    uint32_t hi, lo;
    if (!u32(c, &hi, what) || !u32(c, &lo, what))
        return false;
    if (hi > INT32_MAX)
        return failf(c, "%s is negative", what);
    *v = (uint64_t)hi << 32 | lo;
    return true;
}

/* An offset: 32 bits in CDF-1, 64 in CDF-2 and CDF-5, never negative. */
static bool offset(struct cursor *c, uint64_t *v, const char *what)
{
    if (c->version == 1) {
        uint32_t x;
        if (!u32(c, &x, what))
            return false;
        if (x > INT32_MAX)
            return failf(c, "%s is negative", what);
        *v = x;
        return true;
    }
    uint32_t hi, lo;
    if (!u32(c, &hi, what) || !u32(c, &lo, what))
        return false;
    if (hi > INT32_MAX)
        return failf(c, "%s is negative", what);
    *v = (uint64_t)hi << 32 | lo;
    return true;
}

static uint64_t pad4(uint64_t n)
{
    return (n + 3) & ~(uint64_t)3;
}

/* A name: its length, then its bytes padded to 4.  Kept in OUT (NAME_MAX_BYTES + 1). */
static bool name(struct cursor *c, char *out, const char *what)
{
    uint64_t n = 0; /* set by count; -O3 cannot see that on every path */
    if (!count(c, &n, what))
        return false;
    if (n == 0 || n > NAME_MAX_BYTES)
        return failf(c, "%s: a name of %llu bytes (expected 1 to %d)", what, (unsigned long long)n,
                     NAME_MAX_BYTES);
    for (uint64_t i = 0; i < n; i++) {
        unsigned char ch;
        if (!take(c, 1, &ch, what))
            return false;
        if (ch == '\0')
            return failf(c, "%s: a NUL byte in a name", what);
        out[i] = (char)ch;
    }
    out[n] = '\0';
    return skip(c, pad4(n) - n, what);
}

/* Bytes of one value of external type TYPE, 0 when the version has no such type. */
static unsigned type_size(const struct cursor *c, uint32_t type)
{
    static const unsigned sizes[12] = {0, 1, 1, 2, 4, 4, 8, 1, 2, 4, 8, 8};
    if (type >= 1 && type <= 6)
        return sizes[type];
    if (c->version == 5 && type >= 7 && type <= 11)
        return sizes[type];
    return 0;
}

/* A list header: ABSENT (a zero tag and a zero count) or TAG and a count of at most MAX. */
static bool list(struct cursor *c, uint32_t want, uint64_t max, uint64_t *n, const char *what)
{
    uint32_t tag;
    if (!u32(c, &tag, what) || !count(c, n, what))
        return false;
    if (tag == 0 && *n == 0)
        return true;
    if (tag != want)
        return failf(c, "%s: expected its tag %u or an absent list, found tag %u", what, want, tag);
    if (*n > max)
        return failf(c, "%s: %llu entries (at most %llu)", what, (unsigned long long)*n,
                     (unsigned long long)max);
    return true;
}

static bool attributes(struct cursor *c, const char *owner)
{
    char what[NAME_MAX_BYTES + 48], att[NAME_MAX_BYTES + 1];
    snprintf(what, sizeof(what), "the attributes of %s", owner);
    uint64_t n;
    if (!list(c, TAG_ATTRIBUTE, ATTS_MAX, &n, what))
        return false;
    for (uint64_t i = 0; i < n; i++) {
        uint32_t type;
        uint64_t values;
        if (!name(c, att, what) || !u32(c, &type, what) || !count(c, &values, what))
            return false;
        unsigned size = type_size(c, type);
        if (!size)
            return failf(c, "attribute %s of %s: unknown type %u", att, owner, type);
        if (values > (c->size - c->pos) / size)
            return failf(c, "attribute %s of %s: %llu values run past the end of the file", att,
                         owner, (unsigned long long)values);
        snprintf(what, sizeof(what), "attribute %.256s", att);
        if (!skip(c, pad4(values * size), what))
            return false;
    }
    return true;
}

struct var {
    char name[NAME_MAX_BYTES + 1];
    bool record;
    uint64_t slab;  /* bytes of one record (record variables) or of all the data */
    uint64_t begin; /* file offset of the data */
};

/* Parses the header and checks every variable's data against the file's size. */
static bool check(struct cursor *c, uint64_t *need)
{
    unsigned char magic[4];
    if (!take(c, 4, magic, "the magic number"))
        return false;
    if (magic[0] != 'C' || magic[1] != 'D' || magic[2] != 'F' ||
        (magic[3] != 1 && magic[3] != 2 && magic[3] != 5))
        return failf(c, "not a classic NetCDF file (expected \"CDF\" and version 1, 2 or 5)");
    c->version = magic[3];
    uint64_t numrecs;
    bool streaming = false;
    if (c->version == 5) {
        uint32_t hi, lo;
        if (!u32(c, &hi, "the record count") || !u32(c, &lo, "the record count"))
            return false;
        streaming = hi == UINT32_MAX && lo == UINT32_MAX;
        if (!streaming && hi > INT32_MAX)
            return failf(c, "the record count is negative");
        numrecs = (uint64_t)hi << 32 | lo;
    } else {
        uint32_t x;
        if (!u32(c, &x, "the record count"))
            return false;
        streaming = x == UINT32_MAX;
        numrecs = x;
    }

    uint64_t ndims;
    if (!list(c, TAG_DIMENSION, DIMS_MAX, &ndims, "the dimension list"))
        return false;
    uint64_t *dims = calloc(ndims ? ndims : 1, sizeof(*dims));
    struct var *vars = NULL;
    if (!dims)
        return failf(c, "out of memory reading the header");
    int64_t record_dim = -1;
    bool ok = true;
    for (uint64_t i = 0; ok && i < ndims; i++) {
        char dname[NAME_MAX_BYTES + 1];
        ok = name(c, dname, "a dimension") && count(c, &dims[i], "a dimension's length");
        if (ok && dims[i] == 0) {
            if (record_dim >= 0)
                ok = failf(c, "dimension %s: a second record dimension", dname);
            record_dim = (int64_t)i;
        }
    }
    ok = ok && attributes(c, "the file");
    uint64_t nvars = 0;
    ok = ok && list(c, TAG_VARIABLE, VARS_MAX, &nvars, "the variable list");
    if (ok && !(vars = calloc(nvars ? nvars : 1, sizeof(*vars))))
        ok = failf(c, "out of memory reading the header");
    int record_vars = 0;
    for (uint64_t i = 0; ok && i < nvars; i++) {
        struct var *v = &vars[i];
        uint64_t rank;
        ok = name(c, v->name, "a variable") && count(c, &rank, "a variable's rank");
        if (ok && rank > RANK_MAX)
            ok = failf(c, "variable %s: rank %llu (at most %d)", v->name, (unsigned long long)rank,
                       RANK_MAX);
        uint64_t elements = 1;
        bool overflow = false;
        for (uint64_t k = 0; ok && k < rank; k++) {
            uint64_t id;
            ok = count(c, &id, "a variable's dimension");
            if (ok && id >= ndims)
                ok = failf(c, "variable %s: dimension %llu of %llu there are", v->name,
                           (unsigned long long)id, (unsigned long long)ndims);
            if (!ok)
                break;
            if ((int64_t)id == record_dim) {
                if (k != 0)
                    ok = failf(c, "variable %s: the record dimension is not its first", v->name);
                v->record = true;
                continue;
            }
            overflow = overflow || __builtin_mul_overflow(elements, dims[id], &elements);
        }
        uint32_t type;
        uint64_t vsize;
        ok = ok && attributes(c, v->name) && u32(c, &type, "a variable's type") &&
             count(c, &vsize, "a variable's size") && offset(c, &v->begin, "a variable's offset");
        unsigned size = ok ? type_size(c, type) : 0;
        if (ok && !size)
            ok = failf(c, "variable %s: unknown type %u", v->name, type);
        if (ok && (overflow || __builtin_mul_overflow(elements, (uint64_t)size, &v->slab)))
            ok = failf(c, "variable %s: more bytes than 64 bits count", v->name);
        record_vars += v->record;
    }
    /* Data: after the header, inside the file.  Records follow one another at the record
     * size, the sum of the record variables' slabs padded to 4 (unpadded when there is only
     * one record variable); the last record need not be padded. */
    uint64_t header = c->pos, end = header, recsize = 0;
    for (uint64_t i = 0; ok && i < nvars; i++) {
        if (!vars[i].record)
            continue;
        uint64_t slab = record_vars > 1 ? pad4(vars[i].slab) : vars[i].slab;
        if (__builtin_add_overflow(recsize, slab, &recsize))
            ok = failf(c, "the record size is more than 64 bits count");
    }
    for (uint64_t i = 0; ok && i < nvars; i++) {
        const struct var *v = &vars[i];
        uint64_t last = v->begin;
        if (v->begin < header) {
            ok = failf(c,
                       "variable %s: its data begins at byte %llu, inside the header (%llu "
                       "bytes)",
                       v->name, (unsigned long long)v->begin, (unsigned long long)header);
            break;
        }
        bool overflow = false;
        if (v->record && !streaming && numrecs > 0) {
            uint64_t before;
            overflow = __builtin_mul_overflow(numrecs - 1, recsize, &before) ||
                       __builtin_add_overflow(last, before, &last) ||
                       __builtin_add_overflow(last, v->slab, &last);
        } else if (!v->record) {
            overflow = __builtin_add_overflow(last, v->slab, &last);
        } else {
            last = header; /* no records yet: the data may begin at the end of the file */
        }
        if (overflow || last > c->size) {
            /* The file, the variable and how many bytes are missing. */
            char missing[64] = "";
            if (!overflow)
                snprintf(missing, sizeof(missing), " (%llu bytes missing)",
                         (unsigned long long)(last - c->size));
            if (v->record)
                ok = failf(c,
                           "variable %s: %llu records need the file to reach byte %s%llu, "
                           "it has %llu bytes%s: truncated or damaged",
                           v->name, (unsigned long long)numrecs, overflow ? "beyond " : "",
                           (unsigned long long)(overflow ? UINT64_MAX : last),
                           (unsigned long long)c->size, missing);
            else
                ok = failf(c,
                           "variable %s: its data needs the file to reach byte %s%llu, it has "
                           "%llu bytes%s: truncated or damaged",
                           v->name, overflow ? "beyond " : "",
                           (unsigned long long)(overflow ? UINT64_MAX : last),
                           (unsigned long long)c->size, missing);
        }
        if (last > end)
            end = last;
    }
    free(dims);
    free(vars);
    if (ok && need)
        *need = end;
    return ok;
}

bool data_nc_check_classic(const void *data, size_t len, char *why, size_t why_size, uint64_t *need)
{
    struct cursor *c = calloc(1, sizeof(*c));
    if (!c) {
        snprintf(why, why_size, "out of memory");
        return false;
    }
    c->mem = data;
    c->fd = -1;
    c->size = len;
    c->why = why;
    c->why_size = why_size;
    bool ok = check(c, need);
    free(c);
    return ok;
}

/* The HDF5 signature at 0 or at 512 times a power of two (a user block before it). */
static bool hdf5_signature(int fd, uint64_t size)
{
    static const unsigned char sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    for (uint64_t at = 0; at + 8 <= size && at <= ((uint64_t)1 << 30); at = at ? 2 * at : 512) {
        unsigned char b[8];
        if (pread(fd, b, 8, (off_t)at) == 8 && memcmp(b, sig, 8) == 0)
            return true;
    }
    return false;
}

bool data_nc_open(const char *path, int *ncid, struct data_nc_layout *layout, char *why,
                  size_t why_size)
{
    *ncid = -1;
    struct data_nc_layout l = {0};
    int fd = file_open_regular(path, why, why_size);
    if (fd < 0)
        return false;
    struct stat st;
    if (fstat(fd, &st) != 0) {
        snprintf(why, why_size, "cannot read: %s", strerror(errno));
        close(fd);
        return false;
    }
    l.file_size = (uint64_t)st.st_size;
    l.dev = st.st_dev;
    l.ino = st.st_ino;
    unsigned char magic[4] = {0};
    bool ok = pread(fd, magic, 4, 0) == 4;
    if (ok && magic[0] == 'C' && magic[1] == 'D' && magic[2] == 'F') {
        struct cursor *c = calloc(1, sizeof(*c));
        if (!c) {
            snprintf(why, why_size, "out of memory");
            close(fd);
            return false;
        }
        c->fd = fd;
        c->size = l.file_size;
        c->window_len = 0;
        c->why = why;
        c->why_size = why_size;
        ok = check(c, &l.need);
        l.format = (enum data_nc_format)c->version;
        free(c);
        if (!ok && l.format) {
            char detail[512];
            snprintf(detail, sizeof(detail), "%s", why);
            snprintf(why, why_size, "%s NetCDF header: %s", data_nc_format_name(l.format), detail);
        }
    } else if (hdf5_signature(fd, l.file_size)) {
        l.format = DATA_NC_HDF5;
    } else {
        snprintf(why, why_size,
                 "not a NetCDF file (neither the classic \"CDF\" nor the HDF5 "
                 "signature at its start)");
        ok = false;
    }
    close(fd);
    if (!ok)
        return false;
    data_nc_lock_file(path, "opening", false);
    int status = nc_open(path, NC_NOWRITE, ncid);
    data_nc_unlock();
    if (status != NC_NOERR) {
        *ncid = -1;
        snprintf(why, why_size, "cannot open as NetCDF: %s", nc_strerror(status));
        return false;
    }
    if (layout)
        *layout = l;
    return true;
}

bool data_nc_still_whole(const char *path, const struct data_nc_layout *layout)
{
    if (!layout || layout->need == 0)
        return true;
    struct stat st;
    if (stat(path, &st) != 0 || st.st_dev != layout->dev || st.st_ino != layout->ino)
        return true;
    if ((uint64_t)st.st_size >= layout->need)
        return true;
    log_error("%s: the file has %lld bytes now, its header says %llu (%llu bytes missing): it was "
              "cut short after it was opened (missing data would read as zeros)",
              path, (long long)st.st_size, (unsigned long long)layout->need,
              (unsigned long long)(layout->need - (uint64_t)st.st_size));
    return false;
}
