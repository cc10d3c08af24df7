#include "data/isabel.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/log.h"

static void resolve(const struct isabel_desc *d, int n[3], double extent[3])
{
    static const int def_n[3] = {500, 500, 100};
    static const double def_extent[3] = {2000e3, 2000e3, 20e3};
    for (int a = 0; a < 3; a++) {
        n[a] = d->n[a] > 0 ? d->n[a] : def_n[a];
        extent[a] = d->extent_m[a] > 0 ? d->extent_m[a] : def_extent[a];
    }
}

void isabel_brick_path(const struct isabel_desc *d, const char *field, int step, char *buf,
                       size_t size)
{
    snprintf(buf, size, "%s/%sf%02d.bin", d->dir ? d->dir : ".", field, step + 1);
}

static bool is_regular_file(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

int isabel_step_count(const struct isabel_desc *d)
{
    int steps = 0;
    for (;; steps++) {
        bool any = false;
        char path[4096];
        for (int f = 0; f < SPECIES_COUNT && !any; f++) {
            isabel_brick_path(d, species_wrf_name((enum species)f), steps, path, sizeof(path));
            any = is_regular_file(path);
        }
        if (!any)
            break;
    }
    if (steps == 0)
        log_error("%s: no Isabel bricks (QCLOUDf01.bin, QRAINf01.bin, ...) found",
                  d->dir ? d->dir : ".");
    return steps;
}

static float from_big_endian(uint32_t raw)
{
    const unsigned char *b = (const unsigned char *)&raw;
    uint32_t v = (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3];
    float f;
    memcpy(&f, &v, sizeof(f));
    return f;
}

/* Reads one brick of COUNT values into OUT, converting and cleaning in place. */
static bool read_brick(const char *path, size_t count, float *out, struct isabel_stats *st)
{
    char why[160];
    int fd = file_open_regular(path, why, sizeof(why));
    FILE *fp = fd >= 0 ? fdopen(fd, "rb") : NULL;
    if (!fp) {
        log_error("%s: %s", path, fd >= 0 ? strerror(errno) : why);
        if (fd >= 0)
            close(fd);
        return false;
    }
    struct stat sb;
    if (fstat(fileno(fp), &sb) != 0) {
        log_error("%s: cannot read: %s", path, strerror(errno));
        fclose(fp);
        return false;
    }
    if ((uint64_t)sb.st_size != (uint64_t)count * 4) {
        log_error("%s: %lld bytes, expected %zu (%zu big-endian floats: check data.isabel_size)",
                  path, (long long)sb.st_size, count * 4, count);
        fclose(fp);
        return false;
    }
    size_t got = fread(out, 4, count, fp);
    fclose(fp);
    if (got != count) {
        log_error("%s: read %zu of %zu values", path, got, count);
        return false;
    }
    size_t bad0 = st->land + st->nan + st->inf + st->negative + st->absurd;
    for (size_t i = 0; i < count; i++) {
        uint32_t raw;
        memcpy(&raw, &out[i], 4);
        float x = from_big_endian(raw);
        if (isnan(x))
            st->nan++;
        else if (x >= 1.0e34f && isfinite(x))
            st->land++;
        else if (isinf(x))
            st->inf++;
        else if (x < 0.0f)
            st->negative++;
        else if (x > 1.0f)
            st->absurd++;
        else {
            out[i] = x;
            continue;
        }
        out[i] = 0.0f;
    }
    size_t bad = st->land + st->nan + st->inf + st->negative + st->absurd - bad0;
    if (bad)
        log_debug("%s: %zu land or bad values set to zero", path, bad);
    return true;
}

bool isabel_read_step(const struct isabel_desc *d, int step, struct field_volume *out,
                      struct isabel_stats *stats)
{
    memset(out, 0, sizeof(*out));
    struct isabel_stats local;
    if (!stats)
        stats = &local;
    memset(stats, 0, sizeof(*stats));
    int n[3];
    double extent[3];
    resolve(d, n, extent);
    for (int a = 0; a < 3; a++) {
        out->grid.n[a] = n[a];
        out->grid.spacing[a] = extent[a] / n[a];
        out->grid.origin[a] = 0.0;
    }
    size_t count = grid3_count(&out->grid);
    int found = 0;
    char path[4096];
    for (int f = 0; f < SPECIES_COUNT; f++) {
        isabel_brick_path(d, species_wrf_name((enum species)f), step, path, sizeof(path));
        if (!is_regular_file(path))
            continue;
        out->q[f] = malloc(count * sizeof(float));
        if (!out->q[f]) {
            log_error("%s: out of memory for %zu values", path, count);
            goto error;
        }
        if (!read_brick(path, count, out->q[f], stats))
            goto error;
        stats->present[f] = true;
        found++;
    }
    if (!found) {
        isabel_brick_path(d, "QCLOUD", step, path, sizeof(path));
        log_error("%s: no brick of any species for step %d", path, step + 1);
        goto error;
    }
    size_t bad = stats->nan + stats->inf + stats->negative + stats->absurd;
    if (bad)
        log_warn("%s: step %d: %zu NaN, %zu Inf, %zu negative, %zu above 1 kg/kg set to zero",
                 d->dir ? d->dir : ".", step + 1, stats->nan, stats->inf, stats->negative,
                 stats->absurd);
    return true;

error:
    field_volume_finish(out);
    return false;
}

bool isabel_probe(const char *dir)
{
    struct stat st;
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
        return false;
    struct isabel_desc d = {.dir = dir};
    char path[4096];
    for (int f = 0; f < SPECIES_COUNT; f++) {
        isabel_brick_path(&d, species_wrf_name((enum species)f), 0, path, sizeof(path));
        if (is_regular_file(path))
            return true;
    }
    return false;
}

void isabel_grid(const struct isabel_desc *d, struct grid3 *out)
{
    int n[3];
    double extent[3];
    resolve(d, n, extent);
    for (int a = 0; a < 3; a++) {
        out->n[a] = n[a];
        out->spacing[a] = extent[a] / n[a];
        out->origin[a] = 0.0;
    }
}
