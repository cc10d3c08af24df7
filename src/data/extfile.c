#include "data/extfile.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/nclock.h"
#include "data/ncopen.h"

#define DATE_LEN 19
#define MAX_STEPS 100000

static const char *axis_names[3] = {"x", "y", "z"};
static const char *bnds_names[3] = {"x_bnds", "y_bnds", "z_bnds"};
static const char *beta_names[2] = {"beta_ice", "beta_water"};

/* ---- dates ------------------------------------------------------------------------------ */

/* Days since 1970-01-01 of a proleptic Gregorian date. */
static long days_from_civil(long y, long m, long d)
{
    y -= m <= 2;
    long era = (y >= 0 ? y : y - 399) / 400;
    long yoe = y - era * 400;
    long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return era * 146097 + doe - 719468;
}

bool extfile_parse_date(const char *date, double *seconds)
{
    int y, mo, d, h, mi, s;
    char sep;
    if (!date || sscanf(date, "%4d-%2d-%2d%c%2d:%2d:%2d", &y, &mo, &d, &sep, &h, &mi, &s) != 7)
        return false;
    if ((sep != '_' && sep != ' ' && sep != 'T') || mo < 1 || mo > 12 || d < 1 || d > 31 || h < 0 ||
        h > 24 || mi < 0 || mi > 59 || s < 0 || s > 60)
        return false;
    *seconds = (double)days_from_civil(y, mo, d) * 86400.0 + h * 3600.0 + mi * 60.0 + s;
    return true;
}

/* ---- writing ---------------------------------------------------------------------------- */

struct extfile_writer {
    char *path, *tmp;
    char *source, *history, *species;
    struct grid3 grid;
    int ncid;
    bool defined, failed;
    int steps;
    bool dated; /* the time coordinate counts from the first step's date */
    double t0;
    int var_time, var_times, var_beta[2];
    float *layer;
};

static bool nc_ok(int st, const char *path, const char *what)
{
    if (st == NC_NOERR)
        return true;
    log_error("%s: %s: %s", path, what, nc_strerror(st));
    return false;
}

static char *dup_or_empty(const char *s)
{
    return strdup(s ? s : "");
}

struct extfile_writer *extfile_writer_create(const char *path, const struct grid3 *grid,
                                             const char *source, const char *history,
                                             const char *species_note)
{
    for (int a = 0; a < 3; a++) {
        if (grid->n[a] <= 0 || !(grid->spacing[a] > 0)) {
            log_error("%s: cannot write an extinction volume of %d x %d x %d voxels", path,
                      grid->n[0], grid->n[1], grid->n[2]);
            return NULL;
        }
    }
    struct extfile_writer *w = calloc(1, sizeof(*w));
    if (!w)
        goto error_oom;
    w->ncid = -1;
    w->grid = *grid;
    w->path = strdup(path);
    w->source = dup_or_empty(source);
    w->history = dup_or_empty(history);
    w->species = dup_or_empty(species_note);
    w->layer = malloc((size_t)grid->n[0] * grid->n[1] * sizeof(float));
    if (!w->path || !w->source || !w->history || !w->species || !w->layer)
        goto error_oom;
    if (!data_nc_create_beside(path, NC_CLOBBER | NC_NETCDF4, &w->tmp, &w->ncid)) {
        extfile_writer_destroy(w);
        return NULL;
    }
    return w;

error_oom:
    log_error("%s: out of memory", path);
    extfile_writer_destroy(w);
    return NULL;
}

static bool put_text(int ncid, int varid, const char *name, const char *text)
{
    return nc_put_att_text(ncid, varid, name, strlen(text), text) == NC_NOERR;
}

/* Defines the file's layout; called with the first step (its date fixes the time units). */
static bool define(struct extfile_writer *w, const char *date)
{
    const struct grid3 *g = &w->grid;
    int nc = w->ncid, dt, dlen, dnv, dax[3], vax[3], vbnds[3];
    const char *p = w->tmp;
    w->dated = extfile_parse_date(date, &w->t0);
    if (!w->dated)
        w->t0 = 0.0;
    char units[64];
    if (w->dated)
        snprintf(units, sizeof(units), "seconds since %.10s %.8s", date, date + 11);
    else
        snprintf(units, sizeof(units), "seconds since 1970-01-01 00:00:00");

    if (!nc_ok(nc_def_dim(nc, "time", NC_UNLIMITED, &dt), p, "time") ||
        !nc_ok(nc_def_dim(nc, "z", (size_t)g->n[2], &dax[2]), p, "z") ||
        !nc_ok(nc_def_dim(nc, "y", (size_t)g->n[1], &dax[1]), p, "y") ||
        !nc_ok(nc_def_dim(nc, "x", (size_t)g->n[0], &dax[0]), p, "x") ||
        !nc_ok(nc_def_dim(nc, "nv", 2, &dnv), p, "nv") ||
        !nc_ok(nc_def_dim(nc, "date_len", DATE_LEN, &dlen), p, "date_len"))
        return false;
    static const char *axis_attr[3] = {"X", "Y", "Z"};
    static const char *long_names[3] = {"distance east of the volume's west edge",
                                        "distance north of the volume's south edge",
                                        "height above sea level"};
    for (int a = 0; a < 3; a++) {
        int bd[2] = {dax[a], dnv};
        if (!nc_ok(nc_def_var(nc, axis_names[a], NC_DOUBLE, 1, &dax[a], &vax[a]), p,
                   axis_names[a]) ||
            !nc_ok(nc_def_var(nc, bnds_names[a], NC_DOUBLE, 2, bd, &vbnds[a]), p, bnds_names[a]))
            return false;
        put_text(nc, vax[a], "units", "m");
        put_text(nc, vax[a], "axis", axis_attr[a]);
        put_text(nc, vax[a], "long_name", long_names[a]);
        put_text(nc, vax[a], "bounds", bnds_names[a]);
        if (a == 2)
            put_text(nc, vax[a], "positive", "up");
        put_text(nc, vbnds[a], "units", "m");
    }
    if (!nc_ok(nc_def_var(nc, "time", NC_DOUBLE, 1, &dt, &w->var_time), p, "time"))
        return false;
    put_text(nc, w->var_time, "units", units);
    put_text(nc, w->var_time, "calendar", "standard");
    put_text(nc, w->var_time, "standard_name", "time");
    put_text(nc, w->var_time, "axis", "T");
    int dtimes[2] = {dt, dlen};
    if (!nc_ok(nc_def_var(nc, "Times", NC_CHAR, 2, dtimes, &w->var_times), p, "Times"))
        return false;
    put_text(nc, w->var_times, "long_name", "model time as YYYY-MM-DD_hh:mm:ss");

    static const char *beta_long[2] = {
        "extinction coefficient of the ice phase (ice + snow + graupel)",
        "extinction coefficient of the water phase (cloud + rain)"};
    int d4[4] = {dt, dax[2], dax[1], dax[0]};
    size_t chunk[4] = {1, 1, (size_t)g->n[1], (size_t)g->n[0]};
    for (int b = 0; b < 2; b++) {
        if (!nc_ok(nc_def_var(nc, beta_names[b], NC_FLOAT, 4, d4, &w->var_beta[b]), p,
                   beta_names[b]) ||
            !nc_ok(nc_def_var_chunking(nc, w->var_beta[b], NC_CHUNKED, chunk), p, beta_names[b]) ||
            !nc_ok(nc_def_var_deflate(nc, w->var_beta[b], 1, 1, 1), p, beta_names[b]))
            return false;
        put_text(nc, w->var_beta[b], "units", "m-1");
        put_text(nc, w->var_beta[b], "long_name", beta_long[b]);
        float zero = 0.0f;
        nc_put_att_float(nc, w->var_beta[b], "valid_min", NC_FLOAT, 1, &zero);
    }
    put_text(nc, NC_GLOBAL, "Conventions", "CF-1.8");
    put_text(nc, NC_GLOBAL, "title", "anvil extinction volumes (Nes 2008, section 5.6)");
    put_text(nc, NC_GLOBAL, "source", w->source);
    put_text(nc, NC_GLOBAL, "history", w->history);
    put_text(nc, NC_GLOBAL, "anvil_format", "extinction 1");
    if (w->species[0])
        put_text(nc, NC_GLOBAL, "anvil_species", w->species);
    if (!nc_ok(nc_enddef(nc), p, "define"))
        return false;

    for (int a = 0; a < 3; a++) {
        int n = g->n[a];
        double *c = malloc((size_t)n * 3 * sizeof(double));
        if (!c) {
            log_error("%s: out of memory", p);
            return false;
        }
        double *b = c + n;
        for (int i = 0; i < n; i++) {
            c[i] = g->origin[a] + (i + 0.5) * g->spacing[a];
            b[2 * i] = g->origin[a] + i * g->spacing[a];
            b[2 * i + 1] = g->origin[a] + (i + 1) * g->spacing[a];
        }
        if (a == 2 && grid3_stretched(g)) {
            /* The model's levels: their centres, cells half way between them (the box's
             * bottom and top outside), as the reader takes them back. */
            double top = g->origin[2] + n * g->spacing[2];
            for (int i = 0; i < n; i++) {
                c[i] = g->z_centre[i];
                b[2 * i] = i ? 0.5 * (g->z_centre[i - 1] + g->z_centre[i]) : g->origin[2];
                b[2 * i + 1] = i < n - 1 ? 0.5 * (g->z_centre[i] + g->z_centre[i + 1]) : top;
            }
        }
        bool ok = nc_ok(nc_put_var_double(nc, vax[a], c), p, axis_names[a]) &&
                  nc_ok(nc_put_var_double(nc, vbnds[a], b), p, bnds_names[a]);
        free(c);
        if (!ok)
            return false;
    }
    return true;
}

static bool same_grid(const struct grid3 *a, const struct grid3 *b)
{
    for (int i = 0; i < 3; i++) {
        if (a->n[i] != b->n[i] || fabs(a->spacing[i] - b->spacing[i]) > 1e-6 * a->spacing[i] ||
            fabs(a->origin[i] - b->origin[i]) > 1e-6 * a->spacing[i])
            return false;
    }
    if (a->z_levels != b->z_levels)
        return false;
    for (int k = 0; k < a->z_levels; k++)
        if (fabs(a->z_centre[k] - b->z_centre[k]) > 1e-6 * a->spacing[2])
            return false;
    return true;
}

bool extfile_writer_add(struct extfile_writer *w, const struct ext_volume *v, const char *date)
{
    if (w->failed)
        return false;
    if (!same_grid(&w->grid, &v->grid)) {
        log_error("%s: step %d's grid (%d x %d x %d voxels of %g x %g x %g m) differs from the "
                  "first step's (%d x %d x %d of %g x %g x %g m)",
                  w->path, w->steps, v->grid.n[0], v->grid.n[1], v->grid.n[2], v->grid.spacing[0],
                  v->grid.spacing[1], v->grid.spacing[2], w->grid.n[0], w->grid.n[1], w->grid.n[2],
                  w->grid.spacing[0], w->grid.spacing[1], w->grid.spacing[2]);
        w->failed = true;
        return false;
    }
    if (!date)
        date = "";
    data_nc_lock_file(w->path, "writing", true);
    bool ok = true;
    if (!w->defined) {
        ok = define(w, date);
        w->defined = true;
    }
    const struct grid3 *g = &w->grid;
    size_t t = (size_t)w->steps;
    if (ok) {
        double secs;
        double tv = (w->dated && extfile_parse_date(date, &secs)) ? secs - w->t0 : (double)t;
        char padded[DATE_LEN + 1];
        memset(padded, ' ', DATE_LEN);
        memcpy(padded, date, strnlen(date, DATE_LEN));
        size_t s2[2] = {t, 0}, c2[2] = {1, DATE_LEN};
        ok = nc_ok(nc_put_var1_double(w->ncid, w->var_time, &t, &tv), w->tmp, "time") &&
             nc_ok(nc_put_vara_text(w->ncid, w->var_times, s2, c2, padded), w->tmp, "Times");
    }
    size_t plane = (size_t)g->n[0] * g->n[1];
    for (int b = 0; b < 2 && ok; b++) {
        for (int k = 0; k < g->n[2] && ok; k++) {
            const float *src = v->beta + 2 * plane * (size_t)k + b;
            for (size_t i = 0; i < plane; i++)
                w->layer[i] = src[2 * i];
            size_t s4[4] = {t, (size_t)k, 0, 0}, c4[4] = {1, 1, (size_t)g->n[1], (size_t)g->n[0]};
            ok = nc_ok(nc_put_vara_float(w->ncid, w->var_beta[b], s4, c4, w->layer), w->tmp,
                       beta_names[b]);
        }
    }
    data_nc_unlock();
    if (ok)
        w->steps++;
    else
        w->failed = true;
    return ok;
}

bool extfile_writer_finish(struct extfile_writer *w)
{
    if (!w)
        return false;
    bool ok = data_nc_finish_beside(w->path, &w->tmp, &w->ncid, !w->failed, w->steps);
    extfile_writer_destroy(w);
    return ok;
}

void extfile_writer_destroy(struct extfile_writer *w)
{
    if (!w)
        return;
    data_nc_abandon(&w->tmp, &w->ncid);
    free(w->path);
    free(w->source);
    free(w->history);
    free(w->species);
    free(w->layer);
    free(w);
}

/* ---- reading ---------------------------------------------------------------------------- */

struct extfile {
    char *path;
    int ncid;
    struct data_nc_layout layout;
    int steps;
    char (*dates)[DATE_LEN + 1];
    struct grid3 grid;
    int var_beta[2];
    float *layer;
};

/* Heights whose centres are not even (a file written from the model's own levels) make the
 * grid stretched: the centres from z, the box from the first and last cell bounds. */
static bool read_levels(struct extfile *f)
{
    struct grid3 *g = &f->grid;
    int n = g->n[2], vz, vb;
    double *c = malloc((size_t)n * sizeof(double)), last[2];
    size_t s[2] = {(size_t)n - 1, 0}, cnt[2] = {1, 2};
    if (!c) {
        log_error("%s: out of memory", f->path);
        return false;
    }
    bool ok = nc_inq_varid(f->ncid, "z", &vz) == NC_NOERR &&
              nc_get_var_double(f->ncid, vz, c) == NC_NOERR &&
              nc_inq_varid(f->ncid, "z_bnds", &vb) == NC_NOERR &&
              nc_get_vara_double(f->ncid, vb, s, cnt, last) == NC_NOERR;
    if (!ok) {
        free(c);
        log_error("%s: variables z, z_bnds: cannot read the level heights", f->path);
        return false;
    }
    bool even = true;
    for (int k = 0; k < n && even; k++)
        even = fabs(c[k] - (g->origin[2] + (k + 0.5) * g->spacing[2])) <= 1e-4 * g->spacing[2];
    if (!even) {
        if (n > GRID3_LEVELS_MAX) {
            log_error("%s: variable z: %d uneven levels: expected at most %d", f->path, n,
                      GRID3_LEVELS_MAX);
            ok = false;
        } else if (!grid3_set_levels(g, c, n, g->origin[2], last[1])) {
            log_error("%s: variables z, z_bnds: expected level heights increasing inside their "
                      "cells",
                      f->path);
            ok = false;
        }
    }
    free(c);
    return ok;
}

static bool read_axis(struct extfile *f, int a, int dimid)
{
    size_t n;
    nc_inq_dimlen(f->ncid, dimid, &n);
    if (n == 0 || n > (1u << 20)) {
        log_error("%s: dimension %s: bad length %zu", f->path, axis_names[a], n);
        return false;
    }
    f->grid.n[a] = (int)n;
    int vb;
    double b[2];
    size_t s[2] = {0, 0}, c[2] = {1, 2};
    if (nc_inq_varid(f->ncid, bnds_names[a], &vb) != NC_NOERR ||
        nc_get_vara_double(f->ncid, vb, s, c, b) != NC_NOERR || !(b[1] > b[0]) || !isfinite(b[0])) {
        log_error("%s: variable %s: missing or not increasing cell bounds (metres)", f->path,
                  bnds_names[a]);
        return false;
    }
    f->grid.origin[a] = b[0];
    f->grid.spacing[a] = b[1] - b[0];
    double top = b[0] + (double)n * (b[1] - b[0]);
    if (f->grid.spacing[a] < DATA_SPACING_MIN_M || f->grid.spacing[a] > DATA_SPACING_MAX_M) {
        log_error("%s: variable %s: cells of %g m: expected %g m to %g km", f->path, bnds_names[a],
                  f->grid.spacing[a], DATA_SPACING_MIN_M, DATA_SPACING_MAX_M / 1000.0);
        return false;
    }
    if (a == 2 && (b[0] < DATA_HEIGHT_MIN_M || top > DATA_HEIGHT_MAX_M)) {
        log_error("%s: variable z_bnds: heights from %g m to %g m: expected %g m to %g km above "
                  "sea level",
                  f->path, b[0], top, DATA_HEIGHT_MIN_M, DATA_HEIGHT_MAX_M / 1000.0);
        return false;
    }
    if (!(fabs(b[0]) < 1e9)) {
        log_error("%s: variable %s: the first cell starts at %g m", f->path, bnds_names[a], b[0]);
        return false;
    }
    return a < 2 || read_levels(f);
}

bool extfile_probe(const char *path)
{
    int nc, var;
    char why[512];
    data_nc_lock_file(path, "reading", false);
    bool yes = data_nc_open(path, &nc, NULL, why, sizeof(why));
    if (yes) {
        yes = nc_inq_varid(nc, beta_names[0], &var) == NC_NOERR;
        nc_close(nc);
    }
    data_nc_unlock();
    return yes;
}

struct extfile *extfile_open(const char *path, double memory_mb)
{
    struct extfile *f = calloc(1, sizeof(*f));
    if (!f) {
        log_error("%s: out of memory", path);
        return NULL;
    }
    f->ncid = -1;
    f->path = strdup(path);
    if (!f->path) {
        free(f);
        log_error("%s: out of memory", path);
        return NULL;
    }
    data_nc_lock_file(f->path, "reading", false);
    char why[512];
    if (!data_nc_open(path, &f->ncid, &f->layout, why, sizeof(why))) {
        log_error("%s: %s", path, why);
        goto error;
    }
    int dims[4];
    const char *dnames[4] = {"time", "z", "y", "x"};
    for (int i = 0; i < 4; i++) {
        if (nc_inq_dimid(f->ncid, dnames[i], &dims[i]) != NC_NOERR) {
            log_error("%s: not an extinction file: no dimension %s", path, dnames[i]);
            goto error;
        }
    }
    size_t nt;
    nc_inq_dimlen(f->ncid, dims[0], &nt);
    if (nt == 0 || nt > MAX_STEPS) {
        log_error("%s: dimension time: %zu steps", path, nt);
        goto error;
    }
    f->steps = (int)nt;
    for (int a = 0; a < 3; a++) {
        if (!read_axis(f, a, dims[3 - a]))
            goto error;
    }
    /* A step becomes two floats per voxel; judged from the dimensions, in double (their
     * product may not fit a size_t). */
    const int *n = f->grid.n;
    double step_bytes = 2.0 * sizeof(float) * n[0] * n[1] * n[2] + sizeof(float) * n[0] * n[1];
    if ((memory_mb > 0 && step_bytes > memory_mb * 1048576.0) || step_bytes > 0x1p62) {
        log_error("%s: one time step of %d x %d x %d voxels needs %.0f MiB, above the budget "
                  "data.memory = %.0f MiB",
                  path, n[0], n[1], n[2], step_bytes / 1048576.0, memory_mb);
        goto error;
    }
    for (int b = 0; b < 2; b++) {
        nc_type type;
        int nd, vd[NC_MAX_VAR_DIMS];
        if (nc_inq_varid(f->ncid, beta_names[b], &f->var_beta[b]) != NC_NOERR) {
            log_error("%s: not an extinction file: no variable %s", path, beta_names[b]);
            goto error;
        }
        nc_inq_var(f->ncid, f->var_beta[b], NULL, &type, &nd, vd, NULL);
        if ((type != NC_FLOAT && type != NC_DOUBLE) || nd != 4 || vd[0] != dims[0] ||
            vd[1] != dims[1] || vd[2] != dims[2] || vd[3] != dims[3]) {
            log_error("%s: variable %s: expected float %s(time, z, y, x)", path, beta_names[b],
                      beta_names[b]);
            goto error;
        }
    }
    f->dates = calloc(nt, sizeof(*f->dates));
    f->layer = malloc((size_t)f->grid.n[0] * f->grid.n[1] * sizeof(float));
    if (!f->dates || !f->layer) {
        log_error("%s: out of memory", path);
        goto error;
    }
    int vt;
    if (nc_inq_varid(f->ncid, "Times", &vt) == NC_NOERR) {
        for (size_t t = 0; t < nt; t++) {
            size_t s2[2] = {t, 0}, c2[2] = {1, DATE_LEN};
            if (nc_get_vara_text(f->ncid, vt, s2, c2, f->dates[t]) != NC_NOERR)
                f->dates[t][0] = '\0';
            f->dates[t][DATE_LEN] = '\0';
            for (int i = DATE_LEN - 1; i >= 0 && (f->dates[t][i] == ' ' || !f->dates[t][i]); i--)
                f->dates[t][i] = '\0';
        }
    }
    data_nc_unlock();
    return f;

error:
    data_nc_unlock();
    extfile_close(f);
    return NULL;
}

void extfile_close(struct extfile *f)
{
    if (!f)
        return;
    if (f->ncid >= 0) {
        data_nc_lock_file(f->path, "closing", false);
        nc_close(f->ncid);
        data_nc_unlock();
    }
    free(f->path);
    free(f->dates);
    free(f->layer);
    free(f);
}

int extfile_step_count(const struct extfile *f)
{
    return f->steps;
}

const char *extfile_step_date(const struct extfile *f, int step)
{
    return (step >= 0 && step < f->steps) ? f->dates[step] : "";
}

const struct grid3 *extfile_grid(const struct extfile *f)
{
    return &f->grid;
}

bool extfile_read_step(struct extfile *f, int step, struct ext_volume *out,
                       struct extfile_stats *stats)
{
    memset(out, 0, sizeof(*out));
    struct extfile_stats local;
    if (!stats)
        stats = &local;
    memset(stats, 0, sizeof(*stats));
    if (step < 0 || step >= f->steps) {
        log_error("%s: time step %d out of range (0 to %d)", f->path, step, f->steps - 1);
        return false;
    }
    if (!data_nc_still_whole(f->path, &f->layout) || !ext_volume_init(out, &f->grid))
        return false;
    const struct grid3 *g = &f->grid;
    size_t plane = (size_t)g->n[0] * g->n[1];
    bool ok = true;
    data_nc_lock_file(f->path, "reading", false);
    for (int b = 0; b < 2 && ok; b++) {
        float fv = NC_FILL_FLOAT;
        bool has_fv = nc_get_att_float(f->ncid, f->var_beta[b], "_FillValue", &fv) == NC_NOERR;
        for (int k = 0; k < g->n[2] && ok; k++) {
            size_t s4[4] = {(size_t)step, (size_t)k, 0, 0};
            size_t c4[4] = {1, 1, (size_t)g->n[1], (size_t)g->n[0]};
            int st = nc_get_vara_float(f->ncid, f->var_beta[b], s4, c4, f->layer);
            if (st != NC_NOERR) {
                log_error("%s: variable %s, step %d: %s", f->path, beta_names[b], step,
                          nc_strerror(st));
                ok = false;
                break;
            }
            float *dst = out->beta + 2 * plane * (size_t)k + b;
            for (size_t i = 0; i < plane; i++) {
                float x = f->layer[i];
                if (isnan(x))
                    stats->nan++;
                else if (isinf(x))
                    stats->inf++;
                else if (x == NC_FILL_FLOAT || (has_fv && x == fv))
                    stats->fill++;
                else if (x < 0.0f)
                    stats->negative++;
                else {
                    dst[2 * i] = x;
                    continue;
                }
                dst[2 * i] = 0.0f;
            }
        }
    }
    data_nc_unlock();
    if (!ok) {
        ext_volume_finish(out);
        return false;
    }
    size_t bad = stats->nan + stats->inf + stats->fill + stats->negative;
    if (bad)
        log_warn("%s: step %d: %zu NaN, %zu Inf, %zu fill, %zu negative extinction values set "
                 "to zero",
                 f->path, step, stats->nan, stats->inf, stats->fill, stats->negative);
    return true;
}
