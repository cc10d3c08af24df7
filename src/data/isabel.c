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
#include "data/geo.h"
#include "data/wrf_write.h"

const char *const isabel_fields[ISABEL_FIELD_COUNT] = {
    "QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP", "QVAPOR", "CLOUD",
    "PRECIP", "P",     "TC",   "U",     "V",      "W",
};

static void resolve(const struct isabel_desc *d, int n[3], double extent[3])
{
    static const int def_n[3] = {500, 500, 100};
    static const double def_extent[3] = {2000e3, 2000e3, 19.8e3};
    for (int a = 0; a < 3; a++) {
        n[a] = d->n[a] > 0 ? d->n[a] : def_n[a];
        extent[a] = d->extent_m[a] > 0 ? d->extent_m[a] : def_extent[a];
    }
}

void isabel_grid(const struct isabel_desc *d, struct grid3 *out)
{
    memset(out, 0, sizeof(*out)); /* uniform z */
    double extent[3];
    resolve(d, out->n, extent);
    for (int a = 0; a < 2; a++) {
        out->spacing[a] = extent[a] / out->n[a];
        out->origin[a] = 0.0;
    }
    out->spacing[2] = extent[2] / (out->n[2] > 1 ? out->n[2] - 1 : 1);
    out->origin[2] = ISABEL_BOTTOM_M - 0.5 * out->spacing[2];
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

/* Reads one brick of COUNT values into OUT, converting and cleaning in place: a mass ratio
 * (MASS) outside [0, 1] or bad becomes 0, another field's land or bad values become NAN. */
static bool read_brick(const char *path, size_t count, float *out, struct isabel_stats *st,
                       bool mass)
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
        if (!mass) {
            if (isnan(x))
                st->nan++;
            else if (x >= 1.0e34f && isfinite(x))
                st->land++;
            else if (isinf(x))
                st->inf++;
            out[i] = isfinite(x) && x < 1.0e34f ? x : NAN;
            continue;
        }
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
    if (bad && mass)
        log_debug("%s: %zu land or bad values set to zero", path, bad);
    return true;
}

/* A brick of FIELD read into a new array (NULL with *MISSING when the brick is not there). */
static float *read_signed(const struct isabel_desc *d, const char *field, int step, size_t count,
                          bool *missing, bool *failed)
{
    char path[4096];
    isabel_brick_path(d, field, step, path, sizeof(path));
    *missing = !is_regular_file(path);
    if (*missing)
        return NULL;
    float *v = malloc(count * sizeof(float));
    struct isabel_stats st;
    memset(&st, 0, sizeof(st));
    if (!v) {
        log_error("%s: out of memory for %zu values", path, count);
    } else if (read_brick(path, count, v, &st, false)) {
        if (st.nan + st.inf)
            log_warn("%s: %zu NaN, %zu Inf replaced", path, st.nan, st.inf);
        return v;
    }
    free(v);
    *failed = true;
    return NULL;
}

/* QVAPOR, TC and U, V, W as D asks for them. */
static bool read_extras(const struct isabel_desc *d, int step, const struct grid3 *g,
                        struct field_volume *out)
{
    size_t count = grid3_count(g), plane = (size_t)g->n[0] * g->n[1];
    bool missing, failed = false;
    if (d->qvapor) {
        out->qvapor = read_signed(d, "QVAPOR", step, count, &missing, &failed);
        for (size_t i = 0; out->qvapor && i < count; i++)
            if (!(out->qvapor[i] >= 0.0f && out->qvapor[i] <= 1.0f))
                out->qvapor[i] = 0.0f;
    }
    if (!failed && d->temperature) {
        /* TC in degrees Celsius; land and bad points take the standard atmosphere there. */
        out->temperature = read_signed(d, "TC", step, count, &missing, &failed);
        for (size_t i = 0; out->temperature && i < count; i++) {
            if (isnan(out->temperature[i])) {
                double t, p;
                wrf_std_atmosphere(g->origin[2] + (i / plane + 0.5) * g->spacing[2], &t, &p);
                out->temperature[i] = (float)t;
            } else {
                out->temperature[i] += 273.15f;
            }
        }
        if (missing)
            log_warn("%s: no TC brick for step %d: temperature unavailable",
                     d->dir ? d->dir : ".", step + 1);
    }
    if (!failed && d->wind) {
        static const char *const comp[3] = {"U", "V", "W"};
        float *c[3] = {NULL, NULL, NULL};
        bool miss[3] = {false, false, false};
        for (int k = 0; k < 3 && !failed; k++)
            c[k] = read_signed(d, comp[k], step, count, &miss[k], &failed);
        if (!failed && c[0] && c[1]) {
            /* Kept components: land is zero in them too; else U's array becomes the speed. */
            out->wind = d->wind_components ? malloc(count * sizeof(float)) : c[0];
            if (!out->wind) {
                log_error("%s: out of memory for the wind speed", d->dir ? d->dir : ".");
                failed = true;
            }
            for (size_t i = 0; out->wind && i < count; i++) {
                for (int k = 0; k < 3; k++)
                    if (c[k] && isnan(c[k][i]))
                        c[k][i] = 0.0f;
                float u = c[0][i], v = c[1][i], w = c[2] ? c[2][i] : 0.0f;
                out->wind[i] = sqrtf(u * u + v * v + w * w);
            }
            if (!failed && d->wind_components) {
                out->u = c[0];
                out->v = c[1];
                out->w = c[2];
                c[1] = c[2] = NULL;
            }
            c[0] = NULL;
        } else if (!failed) {
            log_warn("%s: no U or V brick for step %d: wind speed unavailable",
                     d->dir ? d->dir : ".", step + 1);
        }
        for (int k = 0; k < 3; k++)
            free(c[k]);
    }
    return !failed;
}

bool isabel_brick_stats(const struct isabel_desc *d, const char *field, int step,
                        struct isabel_brick_stats *out)
{
    memset(out, 0, sizeof(*out));
    int n[3];
    double extent[3];
    resolve(d, n, extent);
    size_t count = (size_t)n[0] * n[1] * n[2];
    bool missing, failed = false;
    float *v = read_signed(d, field, step, count, &missing, &failed);
    if (!v)
        return !failed;
    out->present = true;
    out->min = INFINITY;
    out->max = -INFINITY;
    for (size_t i = 0; i < count; i++) {
        if (isnan(v[i])) {
            out->land++;
            continue;
        }
        out->min = fmin(out->min, v[i]);
        out->max = fmax(out->max, v[i]);
    }
    if (out->land == count)
        out->min = out->max = 0.0;
    free(v);
    return true;
}

bool isabel_geo(const struct isabel_desc *d, struct geo_map *out)
{
    int n[3];
    double extent[3];
    resolve(d, n, extent);
    memset(out, 0, sizeof(*out));
    if (n[0] < 2 || n[1] < 2)
        return false;
    size_t count = (size_t)n[0] * n[1];
    float *lat = malloc(count * sizeof(float)), *lon = malloc(count * sizeof(float));
    bool ok = lat && lon;
    for (int j = 0; ok && j < n[1]; j++)
        for (int i = 0; i < n[0]; i++) {
            lon[i + (size_t)n[0] * j] =
                (float)(ISABEL_LON_WEST + (ISABEL_LON_EAST - ISABEL_LON_WEST) * i / (n[0] - 1));
            lat[i + (size_t)n[0] * j] =
                (float)(ISABEL_LAT_SOUTH + (ISABEL_LAT_NORTH - ISABEL_LAT_SOUTH) * j / (n[1] - 1));
        }
    if (!ok)
        log_error("out of memory for the Isabel map");
    ok = ok && geo_map_init_grid(out, lat, lon, n[0], n[1], extent[0] / n[0], extent[1] / n[1]);
    free(lat);
    free(lon);
    return ok;
}

bool isabel_read_step(const struct isabel_desc *d, int step, struct field_volume *out,
                      struct isabel_stats *stats)
{
    memset(out, 0, sizeof(*out));
    struct isabel_stats local;
    if (!stats)
        stats = &local;
    memset(stats, 0, sizeof(*stats));
    isabel_grid(d, &out->grid);
    const int *n = out->grid.n;
    size_t count = grid3_count(&out->grid);
    /* What the step allocates, judged before reading: the species, vapour, temperature, and
     * for the wind its three components (one kept as the speed, or all three kept and the
     * speed beside them). */
    int arrays = SPECIES_COUNT + d->qvapor + d->temperature + 3 * d->wind +
                 (d->wind && d->wind_components);
    double bytes = (double)count * sizeof(float) * arrays;
    if (d->memory_mb > 0 && bytes > d->memory_mb * 1048576.0) {
        log_error("%s: a step of %d x %d x %d points needs %.0f MiB, above the budget "
                  "data.memory = %.0f MiB: check data.isabel_size or raise data.memory",
                  d->dir ? d->dir : ".", n[0], n[1], n[2], bytes / 1048576.0, d->memory_mb);
        return false;
    }
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
        if (!read_brick(path, count, out->q[f], stats, true))
            goto error;
        stats->present[f] = true;
        found++;
    }
    if (!found) {
        isabel_brick_path(d, "QCLOUD", step, path, sizeof(path));
        log_error("%s: no brick of any species for step %d", path, step + 1);
        goto error;
    }
    if (!read_extras(d, step, &out->grid, out))
        goto error;
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
