#include "data/wrf.h"

#include <float.h>
#include <glob.h>
#include <pthread.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/log.h"
#include "common/parallel.h"
#include "data/derived.h"
#include "data/extfile.h"
#include "data/nclock.h"
#include "data/ncopen.h"
#include "data/wrf_write.h"

static const char *var_names[WRF_VAR_COUNT] = {
    "QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP", "QVAPOR", "P", "PB", "T", "PH", "PHB",
    "U",      "V",     "W",
};

/* Variables every file must have: density needs P, PB, T; heights need PH, PHB. */
static const enum wrf_var required_vars[] = {WRF_P, WRF_PB, WRF_T, WRF_PH, WRF_PHB};

struct wrf_file {
    char *path;
    int ncid;
    struct data_nc_layout layout; /* what the header promised at open */
    double dx, dy;                /* global DX, DY */
    int ntimes;
    int varid[WRF_VAR_COUNT]; /* -1 when absent */
};

struct wrf_step {
    char date[WRF_DATE_LEN + 1];
    int file;
    int index; /* time index inside the file */
};

struct wrf {
    struct wrf_file *files;
    int file_count;
    struct wrf_step *steps;
    int step_count;
    struct wrf_meta meta;
    int nzs;         /* bottom_top_stag */
    double auto_top; /* the highest model top of the first step, m: data.top = 0 */
    double *mean_zw; /* nzs: each staggered level's mean height over the first step's columns,
                        m (the native levels' mean column) */
    bool moves;      /* XLAT/XLONG differ between the first and the last step (wrf_moves) */
    struct wrf_meta *step_meta; /* step_count, each step's 2-D fields, when it moves (and
                                   they fit); NULL otherwise */
};

const char *wrf_var_name(enum wrf_var v)
{
    return (v >= 0 && v < WRF_VAR_COUNT) ? var_names[v] : "?";
}

void wrf_desc_defaults(struct wrf_desc *d)
{
    memset(d, 0, sizeof(*d));
    for (int i = 0; i < 6; i++)
        d->crop[i] = -1;
}

size_t wrf_var_stats_bad(const struct wrf_var_stats *s)
{
    return s->nan + s->inf + s->fill + s->negative + s->absurd;
}

static bool is_mass_ratio(enum wrf_var v)
{
    return v <= WRF_QVAPOR;
}

static bool is_wind(enum wrf_var v)
{
    return v == WRF_U || v == WRF_V || v == WRF_W;
}

/* ---- opening ---------------------------------------------------------------------------- */

static bool dim_len(const char *path, int ncid, const char *name, int *len, int *dimid_out)
{
    int dimid, st = nc_inq_dimid(ncid, name, &dimid);
    if (st != NC_NOERR) {
        log_error("%s: not a WRF file: no dimension %s", path, name);
        return false;
    }
    size_t n;
    st = nc_inq_dimlen(ncid, dimid, &n);
    if (st != NC_NOERR || n == 0 || n > INT32_MAX) {
        log_error("%s: dimension %s: %s", path, name,
                  st != NC_NOERR ? nc_strerror(st) : "bad length");
        return false;
    }
    *len = (int)n;
    if (dimid_out)
        *dimid_out = dimid;
    return true;
}

/* The length and id of dimension NAME, without logging when it is absent. */
static bool dim_len_quiet(int ncid, const char *name, int *len, int *dimid)
{
    size_t n;
    if (nc_inq_dimid(ncid, name, dimid) != NC_NOERR ||
        nc_inq_dimlen(ncid, *dimid, &n) != NC_NOERR || n == 0 || n > INT32_MAX)
        return false;
    *len = (int)n;
    return true;
}

/* Checks that VAR is float or double over (Time, LEVEL_DIM, south_north, west_east). */
static bool check_var(const char *path, int ncid, const char *name, int varid, const int dims[4])
{
    nc_type type;
    int ndims, vdims[NC_MAX_VAR_DIMS];
    int st = nc_inq_var(ncid, varid, NULL, &type, &ndims, vdims, NULL);
    if (st != NC_NOERR) {
        log_error("%s: variable %s: %s", path, name, nc_strerror(st));
        return false;
    }
    if (type != NC_FLOAT && type != NC_DOUBLE) {
        log_error("%s: variable %s: expected float or double values, found type %d", path, name,
                  (int)type);
        return false;
    }
    if (ndims != 4) {
        log_error("%s: variable %s: expected 4 dimensions (Time, bottom_top%s, south_north, "
                  "west_east), found %d",
                  path, name, (name[0] == 'P' && name[1] == 'H') ? "_stag" : "", ndims);
        return false;
    }
    for (int i = 0; i < 4; i++) {
        if (vdims[i] != dims[i]) {
            char dname[NC_MAX_NAME + 1] = "?", want[NC_MAX_NAME + 1] = "?";
            nc_inq_dimname(ncid, vdims[i], dname);
            nc_inq_dimname(ncid, dims[i], want);
            log_error("%s: variable %s: dimension %d is %s, expected %s", path, name, i + 1, dname,
                      want);
            return false;
        }
    }
    return true;
}

static bool read_times(const char *path, int ncid, int time_dim, int ntimes, struct wrf_step *out,
                       int file_index)
{
    for (int t = 0; t < ntimes; t++) {
        out[t].date[0] = '\0';
        out[t].file = file_index;
        out[t].index = t;
    }
    int varid;
    if (nc_inq_varid(ncid, "Times", &varid) != NC_NOERR) {
        log_warn("%s: no Times variable: steps keep the file's order and have no dates", path);
        return true;
    }
    nc_type type;
    int ndims, dims[NC_MAX_VAR_DIMS];
    if (nc_inq_var(ncid, varid, NULL, &type, &ndims, dims, NULL) != NC_NOERR || type != NC_CHAR ||
        ndims != 2 || dims[0] != time_dim) {
        log_error("%s: variable Times: expected char Times(Time, <string length>)", path);
        return false;
    }
    size_t len;
    if (nc_inq_dimlen(ncid, dims[1], &len) != NC_NOERR || len == 0 || len > 256) {
        log_error("%s: variable Times: bad string length", path);
        return false;
    }
    char *buf = malloc((size_t)ntimes * len);
    if (!buf) {
        log_error("%s: out of memory reading Times", path);
        return false;
    }
    int st = nc_get_var_text(ncid, varid, buf);
    if (st != NC_NOERR) {
        log_error("%s: variable Times: %s", path, nc_strerror(st));
        free(buf);
        return false;
    }
    bool ok = true;
    for (int t = 0; t < ntimes && ok; t++) {
        size_t n = len < WRF_DATE_LEN ? len : WRF_DATE_LEN;
        memcpy(out[t].date, buf + (size_t)t * len, n);
        out[t].date[n] = '\0';
        /* Strip trailing NULs/spaces some writers pad with. */
        for (int i = (int)n - 1; i >= 0 && (out[t].date[i] == ' ' || out[t].date[i] == '\0'); i--)
            out[t].date[i] = '\0';
        double seconds;
        if (out[t].date[0] &&
            (strlen(out[t].date) != WRF_DATE_LEN || !extfile_parse_date(out[t].date, &seconds))) {
            char shown[WRF_DATE_LEN * 4 + 1];
            size_t k = 0;
            for (const char *p = out[t].date; *p && k + 4 < sizeof(shown); p++)
                k += (size_t)snprintf(shown + k, sizeof(shown) - k,
                                      (*p >= ' ' && *p <= '~') ? "%c" : "\\x%02x",
                                      (unsigned char)*p);
            log_error("%s: variable Times, time %d: \"%s\" is not a date YYYY-MM-DD_hh:mm:ss", path,
                      t, shown);
            ok = false;
        }
    }
    free(buf);
    return ok;
}

static int compare_steps(const void *a, const void *b)
{
    const struct wrf_step *x = a, *y = b;
    int c = strcmp(x->date, y->date);
    if (c)
        return c;
    if (x->file != y->file)
        return x->file < y->file ? -1 : 1;
    return x->index - y->index;
}

static double global_double(int ncid, const char *name, double fallback)
{
    double v;
    if (nc_get_att_double(ncid, NC_GLOBAL, name, &v) != NC_NOERR || !isfinite(v))
        return fallback;
    return v;
}

/* Reads a 2-D field (south_north, west_east), with or without a leading Time dimension (first
 * time then), into a new array.  Absent → *out NULL, true.  Wrong shape → logged, false. */
static bool read_meta_2d(const char *path, int ncid, const char *name, int nx, int ny, float **out,
                         size_t time)
{
    *out = NULL;
    int varid, ndims, dims[NC_MAX_VAR_DIMS];
    if (nc_inq_varid(ncid, name, &varid) != NC_NOERR)
        return true;
    nc_type type;
    if (nc_inq_var(ncid, varid, NULL, &type, &ndims, dims, NULL) != NC_NOERR)
        return true;
    if (ndims != 2 && ndims != 3) {
        log_error("%s: variable %s: expected 2 or 3 dimensions ([Time,] south_north, "
                  "west_east), found %d",
                  path, name, ndims);
        return false;
    }
    size_t ylen = 0, xlen = 0;
    nc_inq_dimlen(ncid, dims[ndims - 2], &ylen);
    nc_inq_dimlen(ncid, dims[ndims - 1], &xlen);
    if ((int)ylen != ny || (int)xlen != nx) {
        log_error("%s: variable %s: expected %d x %d columns, found %zu x %zu", path, name, nx, ny,
                  xlen, ylen);
        return false;
    }
    float *buf = malloc((size_t)nx * ny * sizeof(float));
    if (!buf) {
        log_error("%s: out of memory reading %s", path, name);
        return false;
    }
    size_t start[3] = {time, 0, 0}, count[3] = {1, (size_t)ny, (size_t)nx};
    size_t *s = ndims == 3 ? start : start + 1, *c = ndims == 3 ? count : count + 1;
    int st = nc_get_vara_float(ncid, varid, s, c, buf);
    if (st != NC_NOERR) {
        log_error("%s: variable %s: %s", path, name, nc_strerror(st));
        free(buf);
        return false;
    }
    *out = buf;
    return true;
}

/* META's latitude and longitude range from its XLAT and XLONG (NAN without them). */
static void latlon_range(struct wrf_meta *m)
{
    m->lat_min = m->lat_max = m->lon_min = m->lon_max = NAN;
    if (m->xlat && m->xlong) {
        double a = INFINITY, b = -INFINITY, c = INFINITY, d = -INFINITY;
        for (size_t i = 0; i < (size_t)m->nx * m->ny; i++) {
            if (isfinite(m->xlat[i]) && fabsf(m->xlat[i]) <= 90.0f) {
                a = fmin(a, m->xlat[i]);
                b = fmax(b, m->xlat[i]);
            }
            if (isfinite(m->xlong[i]) && fabsf(m->xlong[i]) <= 360.0f) {
                c = fmin(c, m->xlong[i]);
                d = fmax(d, m->xlong[i]);
            }
        }
        if (a <= b && c <= d) {
            m->lat_min = a;
            m->lat_max = b;
            m->lon_min = c;
            m->lon_max = d;
        }
    }
}

/* The 2-D fields of time TIME of the open file PATH into M (XLAT, XLONG, HGT, LANDMASK,
 * LU_INDEX, MAPFAC_M; each NULL where the file lacks it), and their lat/lon range.  M's nx
 * and ny are set. */
static bool read_meta_fields(const char *path, int ncid, size_t time, struct wrf_meta *m)
{
    if (!read_meta_2d(path, ncid, "XLAT", m->nx, m->ny, &m->xlat, time) ||
        !read_meta_2d(path, ncid, "XLONG", m->nx, m->ny, &m->xlong, time) ||
        !read_meta_2d(path, ncid, "HGT", m->nx, m->ny, &m->hgt, time) ||
        !read_meta_2d(path, ncid, "LANDMASK", m->nx, m->ny, &m->landmask, time) ||
        !read_meta_2d(path, ncid, "LU_INDEX", m->nx, m->ny, &m->lu_index, time) ||
        !read_meta_2d(path, ncid, "MAPFAC_M", m->nx, m->ny, &m->mapfac_m, time))
        return false;
    for (size_t i = 0; m->mapfac_m && i < (size_t)m->nx * m->ny; i++) {
        float v = m->mapfac_m[i];
        if (!(v >= 0.01f && v <= 100.0f)) { /* NaN too */
            log_warn("%s: MAPFAC_M: %g at column %zu of %d x %d is not a map scale factor (0.01 "
                     "to 100): the vertical vorticity is taken on the map's grid",
                     path, v, i, m->nx, m->ny);
            free(m->mapfac_m);
            m->mapfac_m = NULL;
        }
    }
    latlon_range(m);
    return true;
}

static void meta_fields_free(struct wrf_meta *m)
{
    free(m->xlat);
    free(m->xlong);
    free(m->hgt);
    free(m->landmask);
    free(m->lu_index);
    free(m->mapfac_m);
    m->xlat = m->xlong = m->hgt = m->landmask = m->lu_index = m->mapfac_m = NULL;
}

/* Opening's budget for every step's 2-D fields of a moving domain, beside MEMORY_MB. */
#define MOTION_BYTES_MAX ((size_t)1 << 30)

/* A domain that moves (WRF's moving nests, prescribed or following a vortex): its XLAT and
 * XLONG at the last step differ from the first's.  Then every step's 2-D fields are read, so
 * that the map, the terrain and the latitude and longitude of a step are its own
 * (wrf_step_meta); where they would not fit the budget, the first step's stand for all, with
 * a warning. */
static bool read_motion(struct wrf *w, double memory_mb)
{
    const struct wrf_meta *m = &w->meta;
    if (!m->xlat || !m->xlong || w->step_count < 2)
        return true;
    const struct wrf_step *last = &w->steps[w->step_count - 1];
    const struct wrf_file *f = &w->files[last->file];
    struct wrf_meta e = {.nx = m->nx, .ny = m->ny};
    data_nc_lock_file(f->path, "reading", false);
    bool ok = read_meta_2d(f->path, f->ncid, "XLAT", m->nx, m->ny, &e.xlat, (size_t)last->index) &&
              read_meta_2d(f->path, f->ncid, "XLONG", m->nx, m->ny, &e.xlong, (size_t)last->index);
    data_nc_unlock();
    double moved = 0.0;
    for (size_t i = 0; ok && e.xlat && e.xlong && i < (size_t)m->nx * m->ny; i++) {
        double a = fabs((double)e.xlat[i] - m->xlat[i]), b = fabs((double)e.xlong[i] - m->xlong[i]);
        if (isfinite(a) && isfinite(b))
            moved = fmax(moved, fmax(a, b));
    }
    meta_fields_free(&e);
    if (!ok)
        return false;
    if (!(moved > 1e-4))
        return true;
    w->moves = true;
    size_t plane = (size_t)m->nx * m->ny, bytes = 6 * plane * sizeof(float) * w->step_count;
    if (bytes > MOTION_BYTES_MAX || (memory_mb > 0.0 && (double)bytes > memory_mb * 1048576.0)) {
        log_warn("%s: the domain moves (a moving nest, up to %.2f degrees from its first step): "
                 "its steps' positions would take %.0f MiB, so the first step's map, terrain "
                 "and latitude and longitude stand for every step",
                 f->path, moved, (double)bytes / 1048576.0);
        return true;
    }
    w->step_meta = calloc((size_t)w->step_count, sizeof(*w->step_meta));
    if (!w->step_meta) {
        log_error("out of memory for the positions of %d time steps", w->step_count);
        return false;
    }
    for (int k = 0; k < w->step_count; k++) {
        struct wrf_meta *sm = &w->step_meta[k];
        *sm = *m;
        sm->xlat = sm->xlong = sm->hgt = sm->landmask = sm->lu_index = sm->mapfac_m = NULL;
        const struct wrf_file *fk = &w->files[w->steps[k].file];
        data_nc_lock_file(fk->path, "reading", false);
        ok = read_meta_fields(fk->path, fk->ncid, (size_t)w->steps[k].index, sm);
        data_nc_unlock();
        if (!ok)
            return false;
    }
    return true; /* the session says where it goes (player_create), info too */
}

bool wrf_moves(const struct wrf *w)
{
    return w->moves;
}

const struct wrf_meta *wrf_step_meta(const struct wrf *w, int step)
{
    if (w->step_meta && step >= 0 && step < w->step_count)
        return &w->step_meta[step];
    return &w->meta;
}

/* The height grid's automatic top: the highest model top (last staggered level) over all
 * columns of the first step in time order.  Fixed for the series so that every step has the
 * same grid. */
static bool compute_auto_top(struct wrf *w)
{
    const struct wrf_file *f = &w->files[w->steps[0].file];
    size_t plane = (size_t)w->meta.nx * w->meta.ny;
    float *a = malloc(plane * sizeof(float)), *b = malloc(plane * sizeof(float));
    if (!a || !b) {
        free(a);
        free(b);
        log_error("%s: out of memory", f->path);
        return false;
    }
    w->mean_zw = calloc((size_t)w->nzs, sizeof(double));
    if (!w->mean_zw) {
        free(a);
        free(b);
        log_error("%s: out of memory", f->path);
        return false;
    }
    /* Every staggered level's mean height (the native levels' mean column), the top level's
     * highest value the automatic top. */
    int st = NC_NOERR;
    double top = 0.0, wild = 0.0;
    for (int k = 0; k < w->nzs && st == NC_NOERR; k++) {
        size_t start[4] = {(size_t)w->steps[0].index, (size_t)k, 0, 0};
        size_t count[4] = {1, 1, (size_t)w->meta.ny, (size_t)w->meta.nx};
        st = nc_get_vara_float(f->ncid, f->varid[WRF_PH], start, count, a);
        if (st == NC_NOERR)
            st = nc_get_vara_float(f->ncid, f->varid[WRF_PHB], start, count, b);
        double sum = 0.0;
        size_t used = 0;
        for (size_t i = 0; st == NC_NOERR && i < plane; i++) {
            double z = ((double)a[i] + (double)b[i]) / WRF_G;
            bool out = z < DATA_HEIGHT_MIN_M || z > DATA_HEIGHT_MAX_M;
            if (isfinite(z) && out && k == w->nzs - 1 && wild == 0.0) {
                wild = z; /* other levels' wild heights are refused where a step is read */
            } else if (isfinite(z) && !out) {
                sum += z;
                used++;
                if (k == w->nzs - 1 && z > top)
                    top = z;
            }
        }
        w->mean_zw[k] = used ? sum / (double)used : NAN;
    }
    free(a);
    free(b);
    if (st != NC_NOERR) {
        log_error("%s: variables PH, PHB: cannot read the model top: %s", f->path, nc_strerror(st));
        return false;
    }
    if (wild != 0.0) {
        log_error("%s: variables PH, PHB: a model top at %g m: expected %g m to %g km above sea "
                  "level",
                  f->path, wild, DATA_HEIGHT_MIN_M, DATA_HEIGHT_MAX_M / 1000.0);
        return false;
    }
    if (!(top > 0.0)) {
        log_error("%s: variables PH, PHB: no usable model top height in the first step", f->path);
        return false;
    }
    w->auto_top = top;
    return true;
}

static bool read_meta(struct wrf *w)
{
    struct wrf_meta *m = &w->meta;
    const struct wrf_file *f = &w->files[w->steps[0].file];
    int ncid = f->ncid;
    m->dx = f->dx;
    m->dy = f->dy;
    m->map_proj = (int)global_double(ncid, "MAP_PROJ", 0);
    m->mp_physics = (int)global_double(ncid, "MP_PHYSICS", -1);
    m->cen_lat = global_double(ncid, "CEN_LAT", NAN);
    m->cen_lon = global_double(ncid, "CEN_LON", NAN);
    m->truelat1 = global_double(ncid, "TRUELAT1", NAN);
    m->truelat2 = global_double(ncid, "TRUELAT2", NAN);
    m->stand_lon = global_double(ncid, "STAND_LON", NAN);
    for (int s = 0; s < SPECIES_COUNT; s++)
        m->has_species[s] = f->varid[s] >= 0;
    m->has_qvapor = f->varid[WRF_QVAPOR] >= 0;
    m->has_wind = f->varid[WRF_U] >= 0 && f->varid[WRF_V] >= 0;
    m->has_w = m->has_wind && f->varid[WRF_W] >= 0;

    if (!read_meta_fields(f->path, ncid, (size_t)w->steps[0].index, m))
        return false;
    size_t lu_len = 0;
    if (nc_inq_attlen(ncid, NC_GLOBAL, "MMINLU", &lu_len) == NC_NOERR &&
        lu_len < sizeof(m->land_use) &&
        nc_get_att_text(ncid, NC_GLOBAL, "MMINLU", m->land_use) == NC_NOERR)
        m->land_use[lu_len] = '\0';
    else
        m->land_use[0] = '\0';
    return true;
}

/* U, V and W are optional: a wrong shape makes the wind speed unavailable (one log_warn), not
 * the file unreadable.  DIMS: Time, bottom_top, south_north, west_east; ZSTAG bottom_top_stag. */
static bool wind_shape_ok(const struct wrf_file *f, enum wrf_var v, const int dims[4], int zstag,
                          int nx, int ny)
{
    static const char *const stag_names[3] = {"west_east_stag", "south_north_stag",
                                              "bottom_top_stag"};
    int axis = v - WRF_U; /* 0 x, 1 y, 2 z */
    int want[4] = {dims[0], dims[1], dims[2], dims[3]}, len = 0;
    if (axis == 2) {
        want[1] = zstag;
    } else {
        int id;
        if (!dim_len_quiet(f->ncid, stag_names[axis], &len, &id) ||
            len != (axis == 0 ? nx : ny) + 1) {
            log_warn("%s: variable %s present but dimension %s is missing or not %d: wind speed "
                     "unavailable",
                     f->path, var_names[v], stag_names[axis], (axis == 0 ? nx : ny) + 1);
            return false;
        }
        want[3 - axis] = id;
    }
    nc_type type;
    int ndims, vdims[NC_MAX_VAR_DIMS];
    bool ok = nc_inq_var(f->ncid, f->varid[v], NULL, &type, &ndims, vdims, NULL) == NC_NOERR &&
              (type == NC_FLOAT || type == NC_DOUBLE) && ndims == 4;
    for (int i = 0; ok && i < 4; i++)
        ok = vdims[i] == want[i];
    if (!ok)
        log_warn("%s: variable %s is not float (Time, %s, %s, %s): wind speed unavailable",
                 f->path, var_names[v], axis == 2 ? "bottom_top_stag" : "bottom_top",
                 axis == 1 ? "south_north_stag" : "south_north",
                 axis == 0 ? "west_east_stag" : "west_east");
    return ok;
}

/* Opens one file and checks it against the first (REF NULL for the first). */
static bool open_file(struct wrf_file *f, const struct wrf *ref_w, const struct wrf_file *ref,
                      int *nx, int *ny, int *nz, int *nzs)
{
    char why[512];
    if (!data_nc_open(f->path, &f->ncid, &f->layout, why, sizeof(why))) {
        log_error("%s: %s", f->path, why);
        return false;
    }
    int dims[4], dstag[4], lx, ly, lz, lzs, lt;
    if (!dim_len(f->path, f->ncid, "west_east", &lx, &dims[3]) ||
        !dim_len(f->path, f->ncid, "south_north", &ly, &dims[2]) ||
        !dim_len(f->path, f->ncid, "bottom_top", &lz, &dims[1]) ||
        !dim_len(f->path, f->ncid, "bottom_top_stag", &lzs, &dstag[1]) ||
        !dim_len(f->path, f->ncid, "Time", &lt, &dims[0]))
        return false;
    dstag[0] = dims[0];
    dstag[2] = dims[2];
    dstag[3] = dims[3];
    if (lzs != lz + 1) {
        log_error("%s: bottom_top_stag is %d, expected bottom_top + 1 = %d", f->path, lzs, lz + 1);
        return false;
    }
    f->dx = global_double(f->ncid, "DX", NAN);
    f->dy = global_double(f->ncid, "DY", NAN);
    if (!(f->dx > 0) || !(f->dy > 0)) {
        log_error("%s: global attributes DX and DY (grid spacing, m) missing or not positive",
                  f->path);
        return false;
    }
    if (f->dx < DATA_SPACING_MIN_M || f->dx > DATA_SPACING_MAX_M || f->dy < DATA_SPACING_MIN_M ||
        f->dy > DATA_SPACING_MAX_M) {
        log_error("%s: global attributes DX = %g m, DY = %g m: expected a grid spacing from %g m "
                  "to %g km",
                  f->path, f->dx, f->dy, DATA_SPACING_MIN_M, DATA_SPACING_MAX_M / 1000.0);
        return false;
    }
    if (ref && (fabs(f->dx - ref->dx) > 1e-6 * ref->dx || fabs(f->dy - ref->dy) > 1e-6 * ref->dy)) {
        log_error("%s: grid spacing DX = %g m, DY = %g m differs from %s's DX = %g m, DY = %g m "
                  "(the files are not one series)",
                  f->path, f->dx, f->dy, ref->path, ref->dx, ref->dy);
        return false;
    }
    if (ref_w && (lx != *nx || ly != *ny || lz != *nz)) {
        log_error("%s: grid %d x %d x %d (west_east x south_north x bottom_top) differs from "
                  "%s's %d x %d x %d",
                  f->path, lx, ly, lz, ref->path, *nx, *ny, *nz);
        return false;
    }
    *nx = lx;
    *ny = ly;
    *nz = lz;
    *nzs = lzs;
    f->ntimes = lt;
    for (int v = 0; v < WRF_VAR_COUNT; v++) {
        if (nc_inq_varid(f->ncid, var_names[v], &f->varid[v]) != NC_NOERR) {
            f->varid[v] = -1;
            continue;
        }
        if (is_wind((enum wrf_var)v)) {
            if (!wind_shape_ok(f, (enum wrf_var)v, dims, dstag[1], lx, ly))
                f->varid[v] = -1;
            continue;
        }
        bool stag = v == WRF_PH || v == WRF_PHB;
        if (!check_var(f->path, f->ncid, var_names[v], f->varid[v], stag ? dstag : dims))
            return false;
    }
    for (size_t r = 0; r < sizeof(required_vars) / sizeof(required_vars[0]); r++) {
        enum wrf_var v = required_vars[r];
        if (f->varid[v] < 0) {
            log_error("%s: required variable %s is missing (P, PB, T give air density; PH, "
                      "PHB give heights)",
                      f->path, var_names[v]);
            return false;
        }
    }
    if (ref) {
        for (int v = 0; v <= WRF_QVAPOR; v++) {
            if ((f->varid[v] >= 0) != (ref->varid[v] >= 0)) {
                log_error("%s: variable %s is %s here but %s in %s", f->path, var_names[v],
                          f->varid[v] >= 0 ? "present" : "missing",
                          ref->varid[v] >= 0 ? "present" : "missing", ref->path);
                return false;
            }
        }
    }
    return true;
}

static bool has_glob_chars(const char *s)
{
    return strpbrk(s, "*?[") != NULL;
}

/* Expands patterns into a list of owned strings. */
static char **expand_paths(const char *const *paths, int count, int *n_out)
{
    int n = 0, cap = 0;
    char **list = NULL;
    for (int i = 0; i < count; i++) {
        glob_t g;
        memset(&g, 0, sizeof(g));
        const char *const *names = &paths[i];
        size_t nn = 1;
        bool globbed = false;
        if (has_glob_chars(paths[i])) {
            int st = glob(paths[i], 0, NULL, &g);
            if (st != 0 || g.gl_pathc == 0) {
                log_error("%s: no file matches", paths[i]);
                globfree(&g);
                goto error;
            }
            names = (const char *const *)g.gl_pathv;
            nn = g.gl_pathc;
            globbed = true;
        }
        for (size_t k = 0; k < nn; k++) {
            if (n == cap) {
                cap = cap ? cap * 2 : 8;
                char **grown = realloc(list, (size_t)cap * sizeof(*list));
                if (!grown) {
                    if (globbed)
                        globfree(&g);
                    goto error_oom;
                }
                list = grown;
            }
            list[n] = strdup(names[k]);
            if (!list[n]) {
                if (globbed)
                    globfree(&g);
                goto error_oom;
            }
            n++;
        }
        if (globbed)
            globfree(&g);
    }
    *n_out = n;
    return list;

error_oom:
    log_error("out of memory listing WRF files");
error:
    for (int i = 0; i < n; i++)
        free(list[i]);
    free(list);
    return NULL;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* A series whose steps are evenly spaced but for a gap of whole steps lacks those steps, most
 * likely a file: one warning per gap (a glob matches only the files that are there). */
static void warn_gaps(const struct wrf *w)
{
    int n = w->step_count;
    if (n < 3)
        return;
    double *t = malloc((size_t)n * sizeof(double)), *dt = malloc((size_t)n * sizeof(double));
    bool ok = t && dt;
    for (int s = 0; ok && s < n; s++)
        ok = extfile_parse_date(w->steps[s].date, &t[s]);
    if (ok) {
        for (int s = 1; s < n; s++)
            dt[s - 1] = t[s] - t[s - 1];
        qsort(dt, (size_t)(n - 1), sizeof(double), compare_doubles);
        double usual = dt[(n - 1) / 2]; /* the median interval */
        for (int s = 1; usual > 0 && s < n; s++) {
            double k = (t[s] - t[s - 1]) / usual;
            if (k > 1.5 && fabs(k - round(k)) < 1e-6)
                log_warn("%s: no step between %s and %s (%.0f missing: the other steps are "
                         "%g s apart); a file missing from the series?",
                         w->files[w->steps[s].file].path, w->steps[s - 1].date, w->steps[s].date,
                         round(k) - 1.0, usual);
        }
    }
    free(t);
    free(dt);
}

/* What opening allocates, in bytes, judged from the dimensions before anything is read: up to
 * six 2-D metadata fields (XLAT, XLONG, HGT, LANDMASK, LU_INDEX, MAPFAC_M) and two planes of
 * the model top's scratch, the dates and the steps of every file. */
static bool open_fits(const struct wrf *w, double memory_mb)
{
    const char *path = w->files[0].path;
    double plane = (double)w->meta.nx * w->meta.ny * sizeof(float), steps = 0.0;
    for (int i = 0; i < w->file_count; i++)
        steps += w->files[i].ntimes;
    double need = 8.0 * plane + steps * (256.0 + sizeof(struct wrf_step));
    if (memory_mb > 0 && need > memory_mb * 1048576.0) {
        log_error("%s: opening a grid of %d x %d columns and %.0f time steps needs %.0f MiB, "
                  "above the budget data.memory = %.0f MiB",
                  path, w->meta.nx, w->meta.ny, steps, need / 1048576.0, memory_mb);
        return false;
    }
    if (steps > INT32_MAX) {
        log_error("%s: %.0f time steps in all: more than anvil counts", path, steps);
        return false;
    }
    return true;
}

struct wrf *wrf_open(const char *const *paths, int count, double memory_mb)
{
    if (count <= 0) {
        log_error("no WRF files given");
        return NULL;
    }
    struct wrf *w = calloc(1, sizeof(*w));
    if (!w) {
        log_error("out of memory opening WRF files");
        return NULL;
    }
    int n = 0;
    char **list = expand_paths(paths, count, &n);
    if (!list) {
        free(w);
        return NULL;
    }
    w->files = calloc((size_t)n, sizeof(*w->files));
    if (!w->files) {
        for (int i = 0; i < n; i++)
            free(list[i]);
        free(list);
        free(w);
        log_error("out of memory opening WRF files");
        return NULL;
    }
    for (int i = 0; i < n; i++) {
        w->files[i].path = list[i];
        w->files[i].ncid = -1;
    }
    free(list);
    w->file_count = n;

    data_nc_lock();
    int total = 0;
    for (int i = 0; i < n; i++) {
        data_nc_lock_file(w->files[i].path, "reading", false);
        bool ok = open_file(&w->files[i], i ? w : NULL, i ? &w->files[0] : NULL, &w->meta.nx,
                            &w->meta.ny, &w->meta.nz, &w->nzs);
        data_nc_unlock();
        if (!ok)
            goto error;
    }
    if (!open_fits(w, memory_mb))
        goto error;
    for (int i = 0; i < n; i++)
        total += w->files[i].ntimes; /* at most INT32_MAX in all (open_fits) */
    w->steps = calloc((size_t)total, sizeof(*w->steps));
    if (!w->steps) {
        log_error("out of memory for %d time steps", total);
        goto error;
    }
    int dims_time;
    for (int i = 0, at = 0; i < n; i++) {
        data_nc_lock_file(w->files[i].path, "reading", false);
        nc_inq_dimid(w->files[i].ncid, "Time", &dims_time);
        bool ok = read_times(w->files[i].path, w->files[i].ncid, dims_time, w->files[i].ntimes,
                             w->steps + at, i);
        data_nc_unlock();
        if (!ok)
            goto error;
        at += w->files[i].ntimes;
    }
    w->step_count = total;
    bool dated = true;
    for (int s = 0; s < total; s++)
        dated = dated && w->steps[s].date[0];
    if (dated) {
        qsort(w->steps, (size_t)total, sizeof(*w->steps), compare_steps);
        for (int s = 1; s < total; s++) {
            if (!strcmp(w->steps[s].date, w->steps[s - 1].date)) {
                log_error("%s: time %s also appears in %s", w->files[w->steps[s].file].path,
                          w->steps[s].date, w->files[w->steps[s - 1].file].path);
                goto error;
            }
        }
    }
    data_nc_lock_file(w->files[w->steps[0].file].path, "reading", false);
    bool meta_ok = read_meta(w) && compute_auto_top(w);
    data_nc_unlock();
    if (!meta_ok)
        goto error;
    data_nc_unlock();
    if (!read_motion(w, memory_mb))
        goto error;
    if (dated)
        warn_gaps(w);
    return w;

error:
    data_nc_unlock();
    wrf_close(w);
    return NULL;
}

void wrf_close(struct wrf *w)
{
    if (!w)
        return;
    for (int i = 0; i < w->file_count; i++) {
        if (w->files[i].ncid >= 0) {
            data_nc_lock_file(w->files[i].path, "closing", false);
            nc_close(w->files[i].ncid);
            data_nc_unlock();
        }
        free(w->files[i].path);
    }
    free(w->files);
    free(w->steps);
    free(w->mean_zw);
    for (int k = 0; w->step_meta && k < w->step_count; k++)
        meta_fields_free(&w->step_meta[k]);
    free(w->step_meta);
    meta_fields_free(&w->meta);
    free(w);
}

const struct wrf_meta *wrf_get_meta(const struct wrf *w)
{
    return &w->meta;
}

int wrf_step_count(const struct wrf *w)
{
    return w->step_count;
}

const char *wrf_step_date(const struct wrf *w, int step)
{
    return (step >= 0 && step < w->step_count) ? w->steps[step].date : "";
}

const char *wrf_step_path(const struct wrf *w, int step)
{
    return (step >= 0 && step < w->step_count) ? w->files[w->steps[step].file].path : "";
}

/* ---- reading a step -------------------------------------------------------------------- */

struct selection;
static bool output_grid(const struct wrf *w, const struct wrf_desc *d, const struct selection *s,
                        struct grid3 *g);

/* The selection a desc makes, in file columns and output levels. */
struct selection {
    int x0, sx, nx; /* first column, stride, count */
    int y0, sy, ny;
    int z0, sz, nz; /* first output level of the full grid, stride, count */
    int levels;     /* full grid: regular levels, or the native levels under the top */
};

static bool axis_select(const char *axis, int len, int lo, int hi, int stride, int *first,
                        int *step, int *count)
{
    if (lo < 0)
        lo = 0;
    if (hi < 0 || hi >= len)
        hi = len - 1;
    if (stride <= 0)
        stride = 1;
    if (lo > hi) {
        log_error("data.crop: %s range [%d, %d] is empty for an axis of %d", axis, lo, hi, len);
        return false;
    }
    *first = lo;
    *step = stride;
    *count = (hi - lo) / stride + 1;
    return true;
}

/* The native levels: the mean column's mass levels, half way between its staggered levels,
 * that lie inside the height grid (BOTTOM, TOP); their count, and their heights into ZC
 * (NULL: only counted). */
static int native_levels(const struct wrf *w, double bottom, double top, double *zc)
{
    int n = 0;
    for (int k = 0; k < w->meta.nz; k++) {
        double z = 0.5 * (w->mean_zw[k] + w->mean_zw[k + 1]);
        if (z > bottom && z < top) {
            if (zc)
                zc[n] = z;
            n++;
        }
    }
    return n;
}

static bool make_selection(const struct wrf *w, const struct wrf_desc *d, struct selection *s)
{
    s->levels = d->levels > 0 ? d->levels : w->meta.nz;
    if (d->native_levels && d->native_from) {
        s->levels = d->native_from->n[2];
    } else if (d->native_levels) {
        double top = d->top_m > 0 ? d->top_m : w->auto_top;
        s->levels = native_levels(w, d->bottom_m, top, NULL);
        if (s->levels < 1) {
            log_error("%s: no model level between %.0f m and %.0f m (data.top)",
                      w->files[w->steps[0].file].path, d->bottom_m, top);
            return false;
        }
    }
    return axis_select("x", w->meta.nx, d->crop[0], d->crop[1], d->stride[0], &s->x0, &s->sx,
                       &s->nx) &&
           axis_select("y", w->meta.ny, d->crop[2], d->crop[3], d->stride[1], &s->y0, &s->sy,
                       &s->ny) &&
           axis_select("z", s->levels, d->crop[4], d->crop[5], d->stride[2], &s->z0, &s->sz,
                       &s->nz);
}

/* The grid a step is read onto: the selection's columns; the regular height levels, or the
 * selected native levels (faces half way between the selected levels, the outer ones half
 * way to the next level, or at the grid's bottom and top). */
static bool output_grid(const struct wrf *w, const struct wrf_desc *d, const struct selection *s,
                        struct grid3 *g)
{
    const char *path = w->files[w->steps[0].file].path;
    double bottom = d->bottom_m;
    double top = d->top_m > 0 ? d->top_m : w->auto_top;
    if (!(top > bottom)) {
        log_error("%s: height grid top %.0f m is not above its bottom %.0f m", path, top, bottom);
        return false;
    }
    memset(g, 0, sizeof(*g));
    g->n[0] = s->nx;
    g->n[1] = s->ny;
    g->spacing[0] = w->meta.dx * s->sx;
    g->spacing[1] = w->meta.dy * s->sy;
    g->origin[0] = (s->x0 + 0.5) * w->meta.dx - 0.5 * g->spacing[0];
    g->origin[1] = (s->y0 + 0.5) * w->meta.dy - 0.5 * g->spacing[1];
    if (!d->native_levels) {
        double dzf = (top - bottom) / s->levels;
        g->n[2] = s->nz;
        g->spacing[2] = dzf * s->sz;
        g->origin[2] = bottom + (s->z0 + 0.5) * dzf - 0.5 * g->spacing[2];
        return true;
    }
    if (s->nz > GRID3_LEVELS_MAX) {
        log_error("%s: %d model levels: native levels hold at most %d (data.stride or "
                  "data.crop along z, or data.vertical = \"uniform\")",
                  path, s->nz, GRID3_LEVELS_MAX);
        return false;
    }
    double all[GRID3_LEVELS_MAX * 4], zc[GRID3_LEVELS_MAX];
    if (s->levels > GRID3_LEVELS_MAX * 4) {
        log_error("%s: %d model levels: native levels hold at most %d", path, s->levels,
                  GRID3_LEVELS_MAX * 4);
        return false;
    }
    if (d->native_from) { /* another file's levels (nests: the outermost domain's) */
        const struct grid3 *f = d->native_from;
        for (int k = 0; k < f->n[2]; k++)
            all[k] = grid3_centre_z(f, k);
        bottom = f->origin[2];
        top = f->origin[2] + f->n[2] * f->spacing[2];
    } else {
        native_levels(w, bottom, top, all);
    }
    for (int k = 0; k < s->nz; k++)
        zc[k] = all[s->z0 + k * s->sz];
    int first = s->z0, last = s->z0 + (s->nz - 1) * s->sz;
    double lo = first > 0 ? 0.5 * (all[first - 1] + all[first]) : bottom;
    double hi = last < s->levels - 1 ? 0.5 * (all[last] + all[last + 1]) : top;
    if (s->nz > 1) { /* with a stride the faces lie half way to the neighbours kept */
        lo = fmax(lo, zc[0] - 0.5 * (zc[1] - zc[0]));
        hi = fmin(hi, zc[s->nz - 1] + 0.5 * (zc[s->nz - 1] - zc[s->nz - 2]));
    }
    /* Levels already even (a file on height levels, anvil synth's) make the uniform grid they
     * are: nothing to map, the same picture as data.vertical = "uniform". */
    double dz = (hi - lo) / s->nz;
    bool even = true;
    for (int k = 0; k < s->nz && even; k++)
        even = fabs(zc[k] - (lo + (k + 0.5) * dz)) <= 1e-3 * dz;
    if (even) {
        g->n[2] = s->nz;
        g->spacing[2] = dz;
        g->origin[2] = lo;
        return true;
    }
    return grid3_set_levels(g, zc, s->nz, lo, hi);
}

static size_t arrays_out(const struct wrf *w, const struct wrf_desc *d)
{
    size_t n = 0;
    for (int f = 0; f < SPECIES_COUNT; f++)
        n += w->meta.has_species[f];
    if (d->qvapor && w->meta.has_qvapor)
        n++;
    if (!d->no_density)
        n++;
    n += d->temperature;
    bool wind = (d->wind || d->wind_components) && w->meta.has_wind;
    n += wind;
    if (wind && d->wind_components) /* u, v, vorticity and w */
        n += 3 + w->meta.has_w;
    return n;
}

static double step_scratch(const struct wrf *w, const struct wrf_desc *d,
                           const struct selection *s, int outs);

size_t wrf_step_bytes(const struct wrf *w, const struct wrf_desc *d)
{
    struct selection s;
    if (!make_selection(w, d, &s))
        return 0;
    /* In double: the dimensions come from the file, and their product may not fit. */
    double out = (double)arrays_out(w, d) * s.nx * s.ny * s.nz * sizeof(float);
    if (d->level_heights)
        out += (double)s.nx * s.ny * w->meta.nz * sizeof(float);
    double total = out + step_scratch(w, d, &s, 0);
    return total >= (double)SIZE_MAX ? SIZE_MAX : (size_t)total;
}

/* Reads V over the selection's columns shifted by (OX, OY) points (a staggered variable's
 * second face). */
static bool read_var_at(const struct wrf *w, int step, enum wrf_var v, const struct selection *s,
                        int levels, int ox, int oy, float *buf)
{
    const struct wrf_file *f = &w->files[w->steps[step].file];
    size_t start[4] = {(size_t)w->steps[step].index, 0, (size_t)(s->y0 + oy),
                       (size_t)(s->x0 + ox)};
    size_t count[4] = {1, (size_t)levels, (size_t)s->ny, (size_t)s->nx};
    ptrdiff_t stride[4] = {1, 1, s->sy, s->sx};
    int st;
    if (s->sx == 1 && s->sy == 1)
        st = nc_get_vara_float(f->ncid, f->varid[v], start, count, buf);
    else
        st = nc_get_vars_float(f->ncid, f->varid[v], start, count, stride, buf);
    if (st != NC_NOERR) {
        log_error("%s: variable %s, time %d: cannot read: %s", f->path, var_names[v],
                  w->steps[step].index, nc_strerror(st));
        return false;
    }
    return true;
}

static bool read_var(const struct wrf *w, int step, enum wrf_var v, const struct selection *s,
                     int levels, float *buf)
{
    return read_var_at(w, step, v, s, levels, 0, 0, buf);
}

/* A fill value attribute of VAR, if any (converted to float). */
static bool fill_attr(int ncid, int varid, const char *name, float *out)
{
    nc_type type;
    size_t len;
    if (nc_inq_att(ncid, varid, name, &type, &len) != NC_NOERR || len < 1 || type == NC_CHAR ||
        type == NC_STRING)
        return false;
    float vals[8];
    if (len > 8)
        return false;
    return nc_get_att_float(ncid, varid, name, vals) == NC_NOERR && (*out = vals[0], true);
}

/* How one variable's values are checked: a value is bad when outside [BOTTOM, TOP], NaN,
 * NetCDF's default fill, or the variable's fill or missing value (NaN when it has none: a NaN
 * compares unequal to everything, so an absent attribute costs nothing). */
struct var_check {
    float fill, missing, top, bottom;
    bool mass; /* a mass ratio: negatives and values above 1 kg/kg are bad too */
    bool fast; /* a mass ratio whose fill and missing values lie outside [0, 1] */
};

static void var_check_init(const struct wrf *w, int step, enum wrf_var v, struct var_check *c)
{
    const struct wrf_file *f = &w->files[w->steps[step].file];
    float fv = 0.0f, mv = 0.0f;
    bool has_fv = fill_attr(f->ncid, f->varid[v], "_FillValue", &fv);
    bool has_mv = fill_attr(f->ncid, f->varid[v], "missing_value", &mv);
    c->mass = is_mass_ratio(v);
    c->fill = has_fv ? fv : NAN;
    c->missing = has_mv ? mv : NAN;
    c->top = c->mass ? 1.0f : FLT_MAX;
    c->bottom = c->mass ? 0.0f : -FLT_MAX;
    /* NaN fails both comparisons. */
    c->fast = c->mass && !(c->fill >= 0.0f && c->fill <= 1.0f) &&
              !(c->missing >= 0.0f && c->missing <= 1.0f);
}

/* What checking found in some of a variable's values: the counts of struct wrf_var_stats and
 * the range [LO, HI] of the good values (LO > HI: none yet).  Adding up the parts in any order
 * gives the whole's. */
struct check_sum {
    size_t count, nan, inf, fill, negative, absurd;
    double lo, hi;
};

static void check_sum_init(struct check_sum *a)
{
    *a = (struct check_sum){.lo = INFINITY, .hi = -INFINITY};
}

static void check_sum_add(struct check_sum *a, const struct check_sum *b)
{
    a->count += b->count;
    a->nan += b->nan;
    a->inf += b->inf;
    a->fill += b->fill;
    a->negative += b->negative;
    a->absurd += b->absurd;
    a->lo = fmin(a->lo, b->lo);
    a->hi = fmax(a->hi, b->hi);
}

static void check_sum_stats(const struct check_sum *a, struct wrf_var_stats *st)
{
    *st = (struct wrf_var_stats){.read = true, .count = a->count, .nan = a->nan, .inf = a->inf,
                                 .fill = a->fill, .negative = a->negative,
                                 .absurd = a->absurd};
    /* + 0: -0 reads as 0 */
    st->min = a->lo <= a->hi ? a->lo + 0.0 : 0.0;
    st->max = a->lo <= a->hi ? a->hi + 0.0 : 0.0;
}

/* Checks the N values of BUF as C says, replaces bad ones by REPLACEMENT, and adds what it
 * found to SUM. */
static void check_values(const struct var_check *c, float *buf, size_t n, float replacement,
                         struct check_sum *sum)
{
    sum->count += n;
    if (n == 0)
        return;
    /* One branch-free pass first (it vectorises), keeping the range as integers that order as
     * the floats do: when every value is good, that is all. */
    const float fvv = c->fill, mvv = c->missing, top = c->top, bottom = c->bottom;
    int32_t klo = INT32_MAX, khi = INT32_MIN, bad = 0;
    for (size_t i = 0; i < n; i++) {
        float x = buf[i];
        int32_t b;
        memcpy(&b, &x, sizeof(b));
        int32_t key = b ^ ((b >> 31) & 0x7fffffff);
        klo = key < klo ? key : klo;
        khi = key > khi ? key : khi;
        bad |= (int32_t)!(x >= bottom) | (int32_t)!(x <= top) | (int32_t)(x == NC_FILL_FLOAT) |
               (int32_t)(x == fvv) | (int32_t)(x == mvv);
    }
    if (!bad) {
        int32_t blo = klo ^ ((klo >> 31) & 0x7fffffff);
        int32_t bhi = khi ^ ((khi >> 31) & 0x7fffffff);
        float flo, fhi;
        memcpy(&flo, &blo, sizeof(flo));
        memcpy(&fhi, &bhi, sizeof(fhi));
        sum->lo = fmin(sum->lo, flo);
        sum->hi = fmax(sum->hi, fhi);
        return;
    }
    /* Some value is bad: count each kind. */
    double lo = INFINITY, hi = -INFINITY;
    float flo = INFINITY, fhi = -INFINITY; /* the usual good mass ratio */
    for (size_t i = 0; i < n; i++) {
        float x = buf[i];
        if (c->fast && x >= 0.0f && x <= 1.0f) {
            flo = x < flo ? x : flo;
            fhi = x > fhi ? x : fhi;
            continue;
        }
        if (isnan(x)) {
            sum->nan++;
        } else if (isinf(x)) {
            sum->inf++;
        } else if (x == NC_FILL_FLOAT || x == fvv || x == mvv) {
            sum->fill++;
        } else if (c->mass && x < 0.0f) {
            sum->negative++;
        } else if (c->mass && x > 1.0f) {
            sum->absurd++;
        } else {
            if (x < lo)
                lo = x;
            if (x > hi)
                hi = x;
            continue;
        }
        buf[i] = replacement;
    }
    if (flo <= fhi) {
        lo = fmin(lo, flo);
        hi = fmax(hi, fhi);
    }
    sum->lo = fmin(sum->lo, lo);
    sum->hi = fmax(sum->hi, hi);
}

/* sanitize over one share. */
struct check_job {
    const struct var_check *c;
    float *buf;
    float replacement;
    struct check_sum sum[PARALLEL_MAX];
};

static bool check_share(void *ctx, int share, size_t begin, size_t end)
{
    struct check_job *j = ctx;
    check_values(j->c, j->buf + begin, end - begin, j->replacement, &j->sum[share]);
    return true;
}

/* Replaces bad values of a whole variable by REPLACEMENT and counts them (check_values), a
 * share per thread.  Mass ratios also lose negatives and values above 1 kg/kg. */
static void sanitize(const struct wrf *w, int step, enum wrf_var v, float *buf, size_t n,
                     float replacement, struct wrf_var_stats *st)
{
    struct var_check c;
    var_check_init(w, step, v, &c);
    struct check_job j = {.c = &c, .buf = buf, .replacement = replacement};
    for (int t = 0; t < PARALLEL_MAX; t++)
        check_sum_init(&j.sum[t]);
    parallel_for(n, 1 << 20, &j, check_share);
    struct check_sum all;
    check_sum_init(&all);
    for (int t = 0; t < PARALLEL_MAX; t++)
        check_sum_add(&all, &j.sum[t]);
    check_sum_stats(&all, st);
}

/* Logs what sanitize found; false (error) when no value at all was usable. */
static bool report(const struct wrf *w, int step, enum wrf_var v, const struct wrf_var_stats *st)
{
    const char *path = w->files[w->steps[step].file].path;
    size_t unusable = st->nan + st->inf + st->fill;
    if (st->count > 0 && unusable == st->count) {
        log_error("%s: variable %s, time %d (%s): all %zu values are NaN, Inf or fill", path,
                  var_names[v], w->steps[step].index, w->steps[step].date, st->count);
        return false;
    }
    if (wrf_var_stats_bad(st) > 0) {
        char what[160] = "";
        const size_t counts[5] = {st->nan, st->inf, st->fill, st->negative, st->absurd};
        static const char *labels[5] = {"NaN", "Inf", "fill", "negative", "above 1 kg/kg"};
        for (int i = 0; i < 5; i++) {
            if (counts[i])
                snprintf(what + strlen(what), sizeof(what) - strlen(what), "%s%zu %s",
                         what[0] ? ", " : "", counts[i], labels[i]);
        }
        log_warn("%s: variable %s, time %d: %s (of %zu values) %s", path, var_names[v],
                 w->steps[step].index, what, st->count,
                 is_mass_ratio(v) || is_wind(v) ? "set to zero"
                                                : "replaced by the standard atmosphere");
    }
    return true;
}

/* The weight of the upper of two levels at Z0 < ZT < Z1, rounded to a float: the same number
 * whether a column is resampled alone (wrf_resample_column) or through a step's plan. */
static float resample_weight(double zt, double z0, double z1)
{
    return (float)((zt - z0) / (z1 - z0));
}

/* wrf_resample_column onto the N heights ZTS (increasing), TOL its closeness to a level. */
static int resample_at(const double *z, const float *v, int nz, double z_ground, double z_top,
                       const double *zts, int n, double tol, float outside, float *out,
                       int *below)
{
    int k = 0, outside_count = 0, below_count = 0;
    for (int o = 0; o < n; o++) {
        double zt = zts[o];
        if (zt < z_ground - tol || zt > z_top + tol) {
            out[o] = outside;
            outside_count++;
            below_count += zt < z_ground;
            continue;
        }
        while (k + 1 < nz && z[k + 1] <= zt)
            k++;
        if (fabs(zt - z[k]) <= tol) {
            out[o] = v[k];
        } else if (k + 1 < nz && fabs(z[k + 1] - zt) <= tol) {
            out[o] = v[k + 1];
        } else if (zt < z[0]) {
            out[o] = v[0]; /* between the ground and the first mass level */
        } else if (k + 1 >= nz) {
            out[o] = v[nz - 1]; /* between the last mass level and the model top */
        } else {
            double t = resample_weight(zt, z[k], z[k + 1]);
            out[o] = (float)((1.0 - t) * v[k] + t * v[k + 1]);
        }
    }
    if (below)
        *below = below_count;
    return outside_count;
}

int wrf_resample_column(const double *z, const float *v, int nz, double z_ground, double z_top,
                        double z0, double dz, int n, float outside, float *out, int *below)
{
    int outside_count = 0, below_count = 0;
    for (int o = 0; o < n; o++) {
        double zt = z0 + (o + 0.5) * dz;
        int b = 0;
        outside_count += resample_at(z, v, nz, z_ground, z_top, &zt, 1, 1e-4 * fabs(dz),
                                     outside, out + o, &b);
        below_count += b;
    }
    if (below)
        *below = below_count;
    return outside_count;
}

/* Heights of the mass levels of every column from PH + PHB on staggered levels.  Columns are
 * resampled in blocks of BLOCK neighbours so that reading levels and writing output planes
 * touch memory in order. */
#define BLOCK 32

struct columns {
    int nz, nzs;
    size_t cols;
    float *zw;  /* staggered heights, m: zw[k * cols + c] */
};

/* The staggered heights (PH + PHB) / g of columns [begin, end) into ZW (PH there before),
 * the first value out of range (its index) and the first column whose mass levels, half way
 * between two staggered levels, do not increase upward. */
struct heights {
    float *zw;
    const float *phb;
    size_t cols;
    int nz;
    size_t range[PARALLEL_MAX], order[PARALLEL_MAX]; /* SIZE_MAX: none */
};

static bool heights_columns(void *ctx, int share, size_t begin, size_t end)
{
    struct heights *h = ctx;
    size_t range = SIZE_MAX, order = SIZE_MAX;
    for (int k = 0; k <= h->nz; k++) {
        float *zw = h->zw + (size_t)k * h->cols;
        const float *phb = h->phb + (size_t)k * h->cols;
        for (size_t c = begin; c < end; c++) {
            zw[c] = (float)(((double)zw[c] + (double)phb[c]) / WRF_G);
            if ((zw[c] < DATA_HEIGHT_MIN_M || zw[c] > DATA_HEIGHT_MAX_M) && range == SIZE_MAX)
                range = (size_t)k * h->cols + c;
        }
    }
    for (size_t c = begin; c < end && order == SIZE_MAX; c++) {
        double prev = 0.0;
        for (int k = 0; k < h->nz; k++) {
            double zm = 0.5 * ((double)h->zw[(size_t)k * h->cols + c] +
                               (double)h->zw[(size_t)(k + 1) * h->cols + c]);
            if (k > 0 && !(zm > prev)) {
                order = c;
                break;
            }
            prev = zm;
        }
    }
    h->range[share] = range;
    h->order[share] = order;
    return true;
}

/* How every output voxel of a step is resampled from its column's mass levels, worked out
 * once per step from the heights and shared by every variable: wrf_resample_column's rule
 * voxel by voxel, kept as the lower mass level K and the weight T of the level above, in
 * output order (plane by plane), so that applying it to a variable reads the variable's
 * mass-level planes nearly in order and writes its output planes in order. */
#define PLAN_OUTSIDE UINT16_MAX

struct plan {
    size_t cols;
    int nz, no;
    const float *zw;     /* staggered heights, m: zw[k * cols + c] (while the plan is made) */
    const double *zc;    /* the output levels' heights, m (while the plan is made) */
    double tol;          /* a target this close to a level takes its value */
    uint16_t *k;         /* [o * cols + c]: the lower mass level, or PLAN_OUTSIDE */
    float *t;            /* the weight of level k + 1; 0: level k's value as it is */
    size_t below, above; /* outputs below the model's ground, above its top */
    size_t share_below[PARALLEL_MAX], share_above[PARALLEL_MAX];
};

/* Blocks [begin, end) of BLOCK columns of the plan. */
static bool plan_blocks(void *ctx, int share, size_t begin, size_t end)
{
    struct plan *p = ctx;
    int nz = p->nz, no = p->no;
    double *z = malloc((size_t)nz * sizeof(double));
    uint16_t *kb = malloc((size_t)BLOCK * no * sizeof(uint16_t));
    float *tb = malloc((size_t)BLOCK * no * sizeof(float));
    bool ok = z && kb && tb;
    double tol = p->tol;
    size_t first = begin * BLOCK, last = end * BLOCK, below = 0, above = 0;
    if (last > p->cols)
        last = p->cols;
    for (size_t c0 = first; c0 < last && ok; c0 += BLOCK) {
        int nb = (int)(last - c0 < BLOCK ? last - c0 : BLOCK);
        for (int b = 0; b < nb; b++) {
            size_t col = c0 + (size_t)b;
            for (int k = 0; k < nz; k++)
                z[k] = 0.5 * ((double)p->zw[(size_t)k * p->cols + col] +
                              (double)p->zw[(size_t)(k + 1) * p->cols + col]);
            double zg = p->zw[col], ztop = p->zw[(size_t)nz * p->cols + col];
            int k = 0;
            for (int o = 0; o < no; o++) {
                /* wrf_resample_column's cases, in its order. */
                double zt = p->zc[o];
                uint16_t kk;
                float t = 0.0f;
                if (zt < zg - tol || zt > ztop + tol) {
                    kk = PLAN_OUTSIDE;
                    if (zt < zg)
                        below++;
                    else
                        above++;
                } else {
                    while (k + 1 < nz && z[k + 1] <= zt)
                        k++;
                    if (fabs(zt - z[k]) <= tol) {
                        kk = (uint16_t)k;
                    } else if (k + 1 < nz && fabs(z[k + 1] - zt) <= tol) {
                        kk = (uint16_t)(k + 1);
                    } else if (zt < z[0]) {
                        kk = 0;
                    } else if (k + 1 >= nz) {
                        kk = (uint16_t)(nz - 1);
                    } else {
                        kk = (uint16_t)k;
                        t = resample_weight(zt, z[k], z[k + 1]);
                    }
                }
                kb[(size_t)o * BLOCK + b] = kk;
                tb[(size_t)o * BLOCK + b] = t;
            }
        }
        for (int o = 0; o < no; o++) {
            memcpy(p->k + p->cols * (size_t)o + c0, kb + (size_t)o * BLOCK,
                   (size_t)nb * sizeof(uint16_t));
            memcpy(p->t + p->cols * (size_t)o + c0, tb + (size_t)o * BLOCK,
                   (size_t)nb * sizeof(float));
        }
    }
    free(z);
    free(kb);
    free(tb);
    p->share_below[share] = below;
    p->share_above[share] = above;
    return ok;
}

static void plan_finish(struct plan *p)
{
    free(p->k);
    free(p->t);
    memset(p, 0, sizeof(*p));
}

/* One variable through the plan: the mass levels BUF (nz * cols) into the output OUT. */
struct apply {
    const struct plan *p;
    const float *buf;
    float outside;
    const float *fill; /* NULL, or per output level: the value of a voxel that came out NaN
                          (outside, or from a bad input) */
    float *out;
    size_t out_stride; /* between the output's planes */
};

/* Output voxel I = o * cols + c of the mass levels BUF through the plan. */
static inline float apply_one(const struct plan *p, const float *buf, float outside, size_t i,
                              size_t c)
{
    uint16_t k = p->k[i];
    if (k == PLAN_OUTSIDE)
        return outside;
    float v0 = buf[(size_t)k * p->cols + c];
    double t = p->t[i];
    return t == 0.0 ? v0 : (float)((1.0 - t) * v0 + t * buf[(size_t)(k + 1) * p->cols + c]);
}

static bool apply_planes(void *ctx, int share, size_t begin, size_t end)
{
    const struct apply *a = ctx;
    const struct plan *p = a->p;
    size_t cols = p->cols;
    for (size_t o = begin; o < end; o++) {
        float *dst = a->out + a->out_stride * o;
        for (size_t c = 0; c < cols; c++)
            dst[c] = apply_one(p, a->buf, a->outside, cols * o + c, c);
        if (a->fill) {
            for (size_t c = 0; c < cols; c++)
                if (!isfinite(dst[c]))
                    dst[c] = a->fill[o];
        }
    }
    return true;
}

/* Resamples one mass-level variable BUF into OUT (the plan's output grid), a share of the
 * planes per thread. */
static void resample_var(const struct plan *p, const float *buf, float outside,
                         const float *fill, float *out)
{
    struct apply a = {
        .p = p, .buf = buf, .outside = outside, .fill = fill, .out = out, .out_stride = p->cols};
    parallel_for((size_t)p->no, 1, &a, apply_planes);
}

/* Air on the mass levels: P + PB in P and T in THETA become the absolute temperature in
 * TEMPERATURE (when not NULL) and, when DENSITY, the air density in P (NaN where the inputs
 * were bad). */
struct air {
    float *p;
    const float *theta;
    float *temperature;
    bool density;
};

/* The density of air at pressure P (P + PB) and perturbation potential temperature T; NaN
 * where they were bad. */
static inline float air_density(float p, float t)
{
    double rho = optics_wrf_air_density_fast(p, (double)t + WRF_T0);
    return (isfinite(rho) && rho > 0.0) ? (float)rho : NAN;
}

static bool air_range(void *ctx, int share, size_t begin, size_t end)
{
    const struct air *a = ctx;
    for (size_t i = begin; i < end; i++) {
        if (a->temperature) {
            double t = optics_wrf_temperature_fast(a->p[i], (double)a->theta[i] + WRF_T0);
            a->temperature[i] = t > 0.0 ? (float)t : NAN;
        }
        if (a->density)
            a->p[i] = air_density(a->p[i], a->theta[i]);
    }
    return true;
}

/* Reads the staggered V at both faces around the selection's mass points (OX, OY: the shift
 * of the second face) into A and B, sanitizes (bad values become zero), and leaves their mean
 * in A. */
static bool read_faces(const struct wrf *w, int step, enum wrf_var v, const struct selection *s,
                       int levels, int ox, int oy, float *a, float *b, size_t n,
                       struct wrf_var_stats *st)
{
    struct wrf_var_stats st2;
    if (!read_var_at(w, step, v, s, levels, 0, 0, a) ||
        !read_var_at(w, step, v, s, levels, ox, oy, b))
        return false;
    sanitize(w, step, v, a, n, 0.0f, st);
    sanitize(w, step, v, b, n, 0.0f, &st2);
    if (st2.min < st->min)
        st->min = st2.min;
    if (st2.max > st->max)
        st->max = st2.max;
    st->count += st2.count;
    st->nan += st2.nan;
    st->inf += st2.inf;
    st->fill += st2.fill;
    if (!report(w, step, v, st))
        return false;
    for (size_t i = 0; i < n; i++)
        a[i] = 0.5f * (a[i] + b[i]);
    return true;
}

/* Wind speed on the mass levels into SPEED (c->cols * c->nz): U averaged over its two
 * west_east_stag faces, V over its south_north_stag faces, W (when the file has it) over its
 * bottom_top_stag levels, using BUF and BUF2 as scratch.  With COMP (three arrays of
 * c->cols * c->nz, the caller's), the components at the mass points go there too, and with
 * VORT the vertical vorticity on each model level (derived_vorticity_plane, spacing DX, DY,
 * the file's map factors where it has them);
 * COMP[2] stays untouched when the file has no W. */
static bool wind_speed(const struct wrf *w, int step, const struct selection *s,
                       const struct columns *c, float *buf, float *buf2, float *speed,
                       float *const *comp, float *vort, double dx, double dy,
                       struct wrf_stats *stats)
{
    size_t n = c->cols * (size_t)c->nz;
    if (!read_faces(w, step, WRF_U, s, c->nz, 1, 0, buf, buf2, n, &stats->var[WRF_U]))
        return false;
    for (size_t i = 0; i < n; i++)
        speed[i] = buf[i] * buf[i];
    if (comp)
        memcpy(comp[0], buf, n * sizeof(float));
    if (!read_faces(w, step, WRF_V, s, c->nz, 0, 1, buf, buf2, n, &stats->var[WRF_V]))
        return false;
    for (size_t i = 0; i < n; i++)
        speed[i] += buf[i] * buf[i];
    if (comp) {
        memcpy(comp[1], buf, n * sizeof(float));
        /* The map factors of S's columns (BUF's first plane, free now). */
        const float *mf = w->meta.mapfac_m;
        for (int j = 0; vort && mf && j < s->ny; j++)
            for (int i = 0; i < s->nx; i++)
                buf[(size_t)j * s->nx + i] =
                    mf[(size_t)(s->y0 + j * s->sy) * w->meta.nx + s->x0 + i * s->sx];
        for (int k = 0; vort && k < c->nz; k++)
            derived_vorticity_plane(comp[0] + k * c->cols, comp[1] + k * c->cols, mf ? buf : NULL,
                                    s->nx, s->ny, dx, dy, vort + k * c->cols);
    }
    if (w->files[w->steps[step].file].varid[WRF_W] >= 0) {
        float *ws = malloc(c->cols * (size_t)c->nzs * sizeof(float));
        if (!ws) {
            log_error("out of memory reading W");
            return false;
        }
        bool ok = read_var(w, step, WRF_W, s, c->nzs, ws);
        if (ok) {
            sanitize(w, step, WRF_W, ws, c->cols * (size_t)c->nzs, 0.0f, &stats->var[WRF_W]);
            ok = report(w, step, WRF_W, &stats->var[WRF_W]);
        }
        for (size_t i = 0; ok && i < n; i++) {
            float m = 0.5f * (ws[i] + ws[i + c->cols]);
            speed[i] += m * m;
            if (comp)
                comp[2][i] = m;
        }
        free(ws);
        if (!ok)
            return false;
    }
    for (size_t i = 0; i < n; i++)
        speed[i] = sqrtf(speed[i]);
    return true;
}

/* The wind of a step (fields OUT->wind and, with D's components, u, v, w and vorticity)
 * through the step's plan P: its staggered variables and the vorticity's neighbours need
 * whole planes, so it is read whole, after the slabs. */
static bool read_wind(const struct wrf *w, int step, const struct wrf_desc *d,
                      const struct selection *s, const struct plan *p, struct field_volume *out,
                      struct wrf_stats *stats)
{
    const char *path = w->files[w->steps[step].file].path;
    const struct wrf_file *sf = &w->files[w->steps[step].file];
    struct columns c = {.nz = w->meta.nz, .nzs = w->nzs, .cols = (size_t)s->nx * s->ny};
    size_t nout = p->cols * (size_t)p->no, nm = c.cols * (size_t)c.nz;
    float *comp[3] = {NULL, NULL, NULL}, *vort = NULL;
    bool ok = false, has_w = sf->varid[WRF_W] >= 0;
    float *buf = malloc(nm * sizeof(float)), *buf2 = malloc(nm * sizeof(float));
    float *buf3 = malloc(nm * sizeof(float));
    out->wind = malloc(nout * sizeof(float));
    if (!buf || !buf2 || !buf3 || !out->wind) {
        log_error("%s: out of memory for wind speed", path);
        goto done;
    }
    if (d->wind_components) {
        bool cok = true;
        for (int i = 0; i < 4; i++) {
            float **dst = i < 3 ? &comp[i] : &vort;
            *dst = malloc(nm * sizeof(float));
            cok = cok && *dst;
        }
        out->u = malloc(nout * sizeof(float));
        out->v = malloc(nout * sizeof(float));
        out->w = has_w ? malloc(nout * sizeof(float)) : NULL;
        out->vorticity = malloc(nout * sizeof(float));
        if (!cok || !out->u || !out->v || (!out->w && has_w) || !out->vorticity) {
            log_error("%s: out of memory for the wind's components", path);
            goto done;
        }
    }
    /* S's columns are S.sx and S.sy mass columns apart. */
    data_nc_lock_file(path, "reading", false);
    ok = wind_speed(w, step, s, &c, buf, buf2, buf3, d->wind_components ? comp : NULL, vort,
                    w->meta.dx * s->sx, w->meta.dy * s->sy, stats);
    data_nc_unlock();
    if (ok) {
        resample_var(p, buf3, 0.0f, NULL, out->wind);
        if (d->wind_components) {
            resample_var(p, comp[0], 0.0f, NULL, out->u);
            resample_var(p, comp[1], 0.0f, NULL, out->v);
            if (has_w)
                resample_var(p, comp[2], 0.0f, NULL, out->w);
            resample_var(p, vort, 0.0f, NULL, out->vorticity);
        }
    }
done:
    for (int i = 0; i < 3; i++)
        free(comp[i]);
    free(vort);
    free(buf);
    free(buf2);
    free(buf3);
    return ok;
}

/* ---- a step, slab by slab ---------------------------------------------------------------- */

/* A step is read in slabs of whole rows of the selection (about SLAB_COLUMNS columns): every
 * variable of a slab is read (one hyperslab each), checked and resampled before the next slab,
 * so a thread's scratch is a few MiB, allocated once per step and reused while it is in the
 * caches, and the step's heights and plan are never held whole.  Each thread takes a run of
 * slabs; NetCDF reads are serialised by the lock, so one thread reads while another computes.
 * Every value is computed as the passes over whole variables computed it: the same numbers,
 * whatever the slabs. */
#define SLAB_COLUMNS 4096

/* What checking, the heights and the plan found in one slab. */
struct slab_result {
    struct check_sum sum[WRF_VAR_COUNT];
    size_t range; /* the first height out of range, as k * cols + column; SIZE_MAX: none */
    float range_z;
    size_t order; /* the first column whose mass levels do not increase; SIZE_MAX: none */
    size_t below, above;
};

struct step_job {
    const struct wrf *w;
    int step;
    const char *path;
    const struct selection *s;
    const struct grid3 *g;
    int nz, nzs, no, rows;
    size_t cols, slabs;
    struct var_check check[WRF_VAR_COUNT];
    int nmass; /* mass ratios read: MASS, in variable order */
    enum wrf_var mass[SPECIES_COUNT + 1];
    float *mass_out[SPECIES_COUNT + 1]; /* the step's output of each (fields) */
    bool air, density, temperature;     /* P, PB and T read; what is made of them */
    const float *fill_rho, *fill_t;     /* per output level: the standard atmosphere */
    float *rho_out, *t_out, *level_z;   /* the step's outputs (fields; NULL: not made) */
    const struct ext_beta *beta;        /* NULL: fields; else extinction into BETA_OUT, MASS
                                           being BETA's species */
    const double *rho_std;              /* per output level (extinction) */
    const double *zc;                   /* per output level: its height */
    float *beta_out;
    /* Extinction and the histogram of the water vapour (the transfer editor's default field,
     * what derived_field makes of the fields' QVAPOR): one per share of slabs, or NULL. */
    struct transfer_histogram *vapour;
    bool read_vapour;   /* QVAPOR in the file (else the histogram holds the stand-in profile) */
    struct plan *whole; /* NULL, or the step's plan, kept for the wind (read_wind) */
    bool scan;          /* only read and check (wrf_scan_step): no plan, no outputs */
    struct slab_result *res; /* one per slab */
};

static bool slab_read(const struct step_job *j, enum wrf_var v, const struct selection *ss,
                      int levels, float *buf)
{
    data_nc_lock_file(j->path, "reading", false);
    bool ok = read_var(j->w, j->step, v, ss, levels, buf);
    data_nc_unlock();
    return ok;
}

/* One variable of a slab through its plan P (P->cols columns) into OUT, OUT_STRIDE apart
 * between output planes. */
static void slab_apply(const struct plan *p, const float *buf, float outside, const float *fill,
                       float *out, size_t out_stride)
{
    struct apply a = {.p = p, .buf = buf, .outside = outside, .fill = fill, .out = out,
                      .out_stride = out_stride};
    apply_planes(&a, 0, 0, (size_t)p->no);
}

/* The air density of a slab for extinction into RHO, through plan P, from P + PB in PRES and T
 * in THETA (mass levels): extinction needs it only where one of the NMASS resampled mass
 * ratios Q (plane by plane, STRIDE floats apart) adds some, so only the mass levels those
 * voxels are resampled from are worked out, and RHO is 0 elsewhere (where extinction is 0
 * whatever the density).  MARK: scratch of a byte per mass-level and output value. */
static void slab_density(const struct plan *p, const float *q, int nmass, size_t stride,
                         float *pres, const float *theta, const float *fill, uint8_t *mark,
                         float *rho)
{
    size_t sc = p->cols, no = (size_t)p->no, nm = sc * (size_t)p->nz;
    uint8_t *need = mark + nm;
    memset(mark, 0, nm);
    memset(need, 0, sc * no);
    for (int m = 0; m < nmass; m++) { /* species by species: it vectorises */
        const float *qm = q + (size_t)m * stride;
        for (size_t i = 0; i < sc * no; i++) {
            /* ext_beta_run's test, 0 < x <= FLT_MAX, on the bits: one unsigned comparison */
            uint32_t b;
            memcpy(&b, &qm[i], sizeof(b));
            need[i] |= (uint8_t)(b - 1u < 0x7f7fffffu);
        }
    }
    for (size_t i = 0; i < sc * no; i++) {
        uint16_t k = p->k[i];
        if (need[i] && k != PLAN_OUTSIDE) {
            size_t c = i % sc;
            mark[(size_t)k * sc + c] = 1;
            if (p->t[i] != 0.0f)
                mark[(size_t)(k + 1) * sc + c] = 1;
        }
    }
    for (size_t i = 0; i < nm; i++)
        if (mark[i])
            pres[i] = air_density(pres[i], theta[i]);
    for (size_t o = 0; o < no; o++) {
        for (size_t c = 0; c < sc; c++) {
            size_t i = o * sc + c;
            float r = 0.0f;
            if (need[i]) {
                r = apply_one(p, pres, NAN, i, c);
                if (!isfinite(r))
                    r = fill[o];
            }
            rho[i] = r;
        }
    }
}

/* Slabs [begin, end). */
static bool step_slabs(void *ctx, int share, size_t begin, size_t end)
{
    const struct step_job *j = ctx;
    const struct selection *s = j->s;
    size_t scm = (size_t)j->rows * (size_t)s->nx, nz = (size_t)j->nz, nzs = (size_t)j->nzs,
           no = (size_t)j->no;
    bool ext = j->beta != NULL;
    /* Extinction: the slab's resampled mass ratios, then its air density. */
    size_t outs = ext ? (size_t)j->nmass + j->density : 0;
    float *zw = malloc(scm * nzs * sizeof(float)), *phb = malloc(scm * nzs * sizeof(float));
    /* BUF2 holds PHB on the staggered levels first, then mass-level variables. */
    float *buf = malloc(scm * nz * sizeof(float)), *buf2 = phb;
    float *buf3 = j->temperature ? malloc(scm * nz * sizeof(float)) : NULL;
    float *slab_out = outs ? malloc(outs * scm * no * sizeof(float)) : NULL;
    struct plan p = {.nz = j->nz, .no = j->no, .zc = j->zc,
                     .tol = 1e-4 * fabs(grid3_min_dz(j->g))};
    p.k = malloc(scm * no * sizeof(uint16_t));
    p.t = malloc(scm * no * sizeof(float));
    uint8_t *mark = ext && j->density ? malloc(scm * (nz + no)) : NULL;
    float *vapour = j->read_vapour ? malloc(scm * no * sizeof(float)) : NULL;
    bool ok = zw && phb && buf && buf2 && (buf3 || !j->temperature) && (slab_out || !outs) && p.k &&
              p.t && (mark || !(ext && j->density)) && (vapour || !j->read_vapour);
    if (!ok)
        log_error("%s: out of memory reading time step %d", j->path, j->step);
    for (size_t sl = begin; sl < end && ok; sl++) {
        int row0 = (int)sl * j->rows;
        int rows = s->ny - row0 < j->rows ? s->ny - row0 : j->rows;
        size_t sc = (size_t)rows * (size_t)s->nx, c0 = (size_t)row0 * (size_t)s->nx;
        struct selection ss = *s;
        ss.y0 = s->y0 + row0 * s->sy;
        ss.ny = rows;
        struct slab_result *r = &j->res[sl];

        /* Heights: (PH + PHB) / g on staggered levels, checked; then the slab's plan. */
        ok = slab_read(j, WRF_PH, &ss, j->nzs, zw) && slab_read(j, WRF_PHB, &ss, j->nzs, phb);
        if (!ok)
            break;
        check_values(&j->check[WRF_PH], zw, sc * nzs, NAN, &r->sum[WRF_PH]);
        check_values(&j->check[WRF_PHB], phb, sc * nzs, NAN, &r->sum[WRF_PHB]);
        struct heights h = {.zw = zw, .phb = phb, .cols = sc, .nz = j->nz};
        h.range[0] = h.order[0] = SIZE_MAX;
        heights_columns(&h, 0, 0, sc);
        if (h.range[0] != SIZE_MAX) {
            r->range = h.range[0] / sc * j->cols + c0 + h.range[0] % sc;
            r->range_z = zw[h.range[0]];
        }
        if (h.order[0] != SIZE_MAX)
            r->order = c0 + h.order[0];
        if (j->scan) {
            for (int m = 0; m < j->nmass && ok; m++) {
                ok = slab_read(j, j->mass[m], &ss, j->nz, buf);
                if (ok)
                    check_values(&j->check[j->mass[m]], buf, sc * nz, 0.0f, &r->sum[j->mass[m]]);
            }
            for (int v = WRF_P; v <= WRF_T && ok && j->air; v++) {
                ok = slab_read(j, (enum wrf_var)v, &ss, j->nz, buf);
                if (ok)
                    check_values(&j->check[v], buf, sc * nz, NAN, &r->sum[v]);
            }
            continue;
        }
        if (j->level_z) { /* the mass levels' heights, half way between their staggered ones */
            for (size_t k = 0; k < nz; k++)
                for (size_t c = 0; c < sc; c++)
                    j->level_z[k * j->cols + c0 + c] =
                        0.5f * (zw[k * sc + c] + zw[(k + 1) * sc + c]);
        }
        p.cols = sc;
        p.zw = zw;
        p.share_below[0] = p.share_above[0] = 0;
        ok = plan_blocks(&p, 0, 0, (sc + BLOCK - 1) / BLOCK);
        if (!ok) {
            log_error("%s: out of memory resampling time step %d", j->path, j->step);
            break;
        }
        r->below = p.share_below[0];
        r->above = p.share_above[0];
        for (size_t o = 0; j->whole && o < no; o++) {
            memcpy(j->whole->k + o * j->cols + c0, p.k + o * sc, sc * sizeof(uint16_t));
            memcpy(j->whole->t + o * j->cols + c0, p.t + o * sc, sc * sizeof(float));
        }

        for (int m = 0; m < j->nmass && ok; m++) {
            enum wrf_var v = j->mass[m];
            ok = slab_read(j, v, &ss, j->nz, buf);
            if (!ok)
                break;
            check_values(&j->check[v], buf, sc * nz, 0.0f, &r->sum[v]);
            if (ext)
                slab_apply(&p, buf, 0.0f, NULL, slab_out + (size_t)m * scm * no, sc);
            else
                slab_apply(&p, buf, 0.0f, NULL, j->mass_out[m] + c0, j->cols);
        }
        if (!ok)
            break;

        /* Air: P + PB and T, temperature and density in one pass, resampled with the standard
         * atmosphere where they came out NaN. */
        float *rho_slab = ext && j->density ? slab_out + (size_t)j->nmass * scm * no : NULL;
        if (j->air) {
            ok = slab_read(j, WRF_P, &ss, j->nz, buf) && slab_read(j, WRF_PB, &ss, j->nz, buf2);
            if (!ok)
                break;
            check_values(&j->check[WRF_P], buf, sc * nz, NAN, &r->sum[WRF_P]);
            check_values(&j->check[WRF_PB], buf2, sc * nz, NAN, &r->sum[WRF_PB]);
            for (size_t i = 0; i < sc * nz; i++)
                buf[i] += buf2[i];
            ok = slab_read(j, WRF_T, &ss, j->nz, buf2);
            if (!ok)
                break;
            check_values(&j->check[WRF_T], buf2, sc * nz, NAN, &r->sum[WRF_T]);
            if (rho_slab) {
                slab_density(&p, slab_out, j->nmass, scm * no, buf, buf2, j->fill_rho, mark,
                             rho_slab);
            } else {
                struct air a = {.p = buf, .theta = buf2, .temperature = buf3,
                                .density = j->density};
                air_range(&a, 0, 0, sc * nz);
                if (j->temperature)
                    slab_apply(&p, buf3, NAN, j->fill_t, j->t_out + c0, j->cols);
                if (j->density)
                    slab_apply(&p, buf, NAN, j->fill_rho, j->rho_out + c0, j->cols);
            }
        }

        if (ext) {
            for (size_t o = 0; o < no; o++) {
                const float *q[SPECIES_COUNT];
                for (int m = 0; m < j->nmass; m++)
                    q[m] = slab_out + (size_t)m * scm * no + o * sc;
                ext_beta_run(j->beta, q, rho_slab ? rho_slab + o * sc : NULL, j->rho_std[o], sc,
                             j->beta_out + 2 * (o * j->cols + c0));
            }
        }
        if (j->read_vapour) {
            /* Read, checked and resampled as the fields' QVAPOR is, then counted. */
            ok = slab_read(j, WRF_QVAPOR, &ss, j->nz, buf);
            if (!ok)
                break;
            check_values(&j->check[WRF_QVAPOR], buf, sc * nz, 0.0f, &r->sum[WRF_QVAPOR]);
            slab_apply(&p, buf, 0.0f, NULL, vapour, sc);
            for (size_t i = 0; i < sc * no; i++)
                transfer_histogram_add(&j->vapour[share], vapour[i]);
        }
    }
    free(vapour);
    free(zw);
    free(phb);
    free(buf);
    free(buf3);
    free(slab_out);
    free(mark);
    free(p.k);
    free(p.t);
    return ok;
}

/* Rows of columns a slab of S holds. */
static int slab_rows(const struct wrf_desc *d, const struct selection *s)
{
    int rows = d->slab_rows > 0 ? d->slab_rows : SLAB_COLUMNS / s->nx;
    return rows < 1 ? 1 : rows > s->ny ? s->ny : rows;
}

/* The scratch of reading a step of S slab by slab (a thread per CPU, OUTS: extinction's
 * resampled slabs) and, with the wind, of reading it whole. */
static double step_scratch(const struct wrf *w, const struct wrf_desc *d,
                           const struct selection *s, int outs)
{
    double cols = (double)s->nx * s->ny;
    double scm = (double)slab_rows(d, s) * s->nx, slabs = ceil(s->ny / (double)slab_rows(d, s));
    double threads = fmin(parallel_share_count((size_t)slabs, 1), slabs);
    /* Per thread: PH and PHB on staggered levels (PHB's then holds a mass-level variable),
     * a mass-level buffer (two with temperature), the slab's plan (a level index and a weight
     * per output voxel), and for extinction the slab's outputs. */
    double slab = scm * (2.0 * w->nzs + (1.0 + d->temperature) * w->meta.nz) * sizeof(float) +
                  scm * s->nz * (sizeof(uint16_t) + sizeof(float) + outs * sizeof(float));
    if (outs > 0 && !d->no_density) /* which voxels extinction needs the density of */
        slab += scm * (w->meta.nz + s->nz);
    double scratch = threads * slab + slabs * sizeof(struct slab_result);
    bool wind = (d->wind || d->wind_components) && w->meta.has_wind;
    if (wind) {
        /* The step's plan, three mass-level buffers; W on its staggered levels; the
         * components and vorticity on the model levels. */
        scratch += cols * 3.0 * w->meta.nz * sizeof(float) +
                   cols * s->nz * (sizeof(uint16_t) + sizeof(float));
        if (w->meta.has_w)
            scratch += cols * w->nzs * sizeof(float);
        if (d->wind_components)
            scratch += 4.0 * cols * w->meta.nz * sizeof(float);
    }
    return scratch;
}

/* wrf_read_step (BETA NULL: fields into OUT), or wrf_read_step_ext (extinction with BETA's
 * species into EXT; OUT only holds the grid). */
static bool read_step(struct wrf *w, int step, const struct wrf_desc *d, bool scan,
                      const struct ext_beta *beta, struct field_volume *out, struct ext_volume *ext,
                      struct transfer_histogram *vapour, struct wrf_stats *stats)
{
    memset(out, 0, sizeof(*out));
    if (ext)
        memset(ext, 0, sizeof(*ext));
    struct wrf_stats local;
    if (!stats)
        stats = &local;
    memset(stats, 0, sizeof(*stats));
    if (step < 0 || step >= w->step_count) {
        log_error("time step %d out of range: the data has %d (0 to %d)", step, w->step_count,
                  w->step_count - 1);
        return false;
    }
    const char *path = w->files[w->steps[step].file].path;
    const struct wrf_file *sf = &w->files[w->steps[step].file];
    struct selection s;
    if (!make_selection(w, d, &s) || !data_nc_still_whole(path, &sf->layout))
        return false;
    size_t need;
    if (beta) {
        double n =
            (double)s.nx * s.ny * s.nz * 2.0 * sizeof(float) +
            step_scratch(w, d, &s, beta->used + !d->no_density + (vapour && w->meta.has_qvapor));
        need = n >= (double)SIZE_MAX ? SIZE_MAX : (size_t)n;
    } else {
        need = wrf_step_bytes(w, d);
    }
    if ((d->memory_mb > 0 && (double)need > d->memory_mb * 1048576.0) || need == SIZE_MAX) {
        log_error("%s: one time step on a %d x %d x %d grid needs %.0f MiB, above the budget "
                  "data.memory = %.0f MiB: subsample with data.stride or data.crop (or fewer "
                  "data.levels)",
                  path, s.nx, s.ny, s.nz, (double)need / 1048576.0, d->memory_mb);
        return false;
    }
    struct grid3 *g = &out->grid;
    if (!output_grid(w, d, &s, g))
        return false;
    size_t cols = (size_t)s.nx * s.ny, nout = grid3_count(g);
    int no = g->n[2];
    bool ask_wind = d->wind || d->wind_components;
    bool want_wind = !beta && !scan && ask_wind && sf->varid[WRF_U] >= 0 &&
                     sf->varid[WRF_V] >= 0;
    if (!beta && !scan && ask_wind && !want_wind)
        log_warn("%s: no usable U and V (the staggered wind): wind speed unavailable", path);

    struct step_job j = {.w = w, .step = step, .path = path, .s = &s, .g = g, .nz = w->meta.nz,
                         .nzs = w->nzs, .no = no, .rows = slab_rows(d, &s), .cols = cols,
                         .beta = beta, .scan = scan};
    j.slabs = ((size_t)s.ny + (size_t)j.rows - 1) / (size_t)j.rows;
    struct plan whole = {.cols = cols, .nz = j.nz, .no = no}; /* the wind's */
    j.density = !d->no_density;
    j.temperature = !beta && !scan && d->temperature;
    j.air = j.density || j.temperature;
    float *fill = malloc(2 * (size_t)no * sizeof(float));
    double *rho_std = malloc(2 * (size_t)no * sizeof(double));
    j.res = malloc(j.slabs * sizeof(*j.res));
    bool ok = fill && rho_std && j.res;
    if (beta && vapour) {
        j.read_vapour = w->meta.has_qvapor && sf->varid[WRF_QVAPOR] >= 0;
        j.vapour = malloc(PARALLEL_MAX * sizeof(*j.vapour));
        ok = ok && j.vapour;
        for (int t = 0; j.vapour && t < PARALLEL_MAX; t++)
            transfer_histogram_init(&j.vapour[t], vapour->field, vapour->lo, vapour->hi);
    }
    if (beta) {
        for (int u = 0; u < beta->used; u++)
            j.mass[j.nmass++] = (enum wrf_var)beta->species[u];
        ok = ok && ext_volume_init(ext, g);
        j.beta_out = ext->beta;
    } else {
        for (int v = 0; v <= WRF_QVAPOR; v++) {
            if (v < SPECIES_COUNT ? !w->meta.has_species[v] : !(d->qvapor && w->meta.has_qvapor))
                continue;
            j.mass[j.nmass] = (enum wrf_var)v;
            if (scan) {
                j.nmass++;
                continue;
            }
            float *dst = malloc(nout * sizeof(float));
            if (v < SPECIES_COUNT)
                out->q[v] = dst;
            else
                out->qvapor = dst;
            j.mass_out[j.nmass++] = dst;
            ok = ok && dst;
        }
        if (j.density && !scan)
            ok = ok && (j.rho_out = out->rho_air = malloc(nout * sizeof(float)));
        if (j.temperature)
            ok = ok && (j.t_out = out->temperature = malloc(nout * sizeof(float)));
        if (d->level_heights && !scan) {
            ok = ok && (j.level_z = out->level_z = malloc(cols * (size_t)j.nz * sizeof(float)));
            out->level_count = j.nz;
        }
    }
    if (!ok) {
        log_error("%s: out of memory reading time step %d", path, step);
        goto done;
    }
    /* Below the ground, above the top, or where P/PB/T were bad: the standard atmosphere,
     * one value per output level. */
    for (int k = 0; k < no; k++) {
        double z = g->origin[2] + (k + 0.5) * g->spacing[2], std, p;
        fill[k] = (float)optics_std_atmosphere_density(z);
        wrf_std_atmosphere(z, &std, &p);
        fill[no + k] = (float)std;
        rho_std[no + k] = grid3_centre_z(g, k);
        rho_std[k] = optics_std_atmosphere_density(rho_std[no + k]);
    }
    if (want_wind) {
        whole.k = malloc(nout * sizeof(uint16_t));
        whole.t = malloc(nout * sizeof(float));
        if (!whole.k || !whole.t) {
            log_error("%s: out of memory for wind speed", path);
            ok = false;
            goto done;
        }
        j.whole = &whole;
    }
    j.fill_rho = fill;
    j.fill_t = fill + no;
    j.rho_std = rho_std;
    j.zc = rho_std + no;
    for (size_t sl = 0; sl < j.slabs; sl++) {
        for (int v = 0; v < WRF_VAR_COUNT; v++)
            check_sum_init(&j.res[sl].sum[v]);
        j.res[sl].range = j.res[sl].order = SIZE_MAX;
        j.res[sl].below = j.res[sl].above = 0;
    }
    data_nc_lock_file(path, "reading", false);
    for (int v = 0; v < WRF_VAR_COUNT; v++)
        if (sf->varid[v] >= 0)
            var_check_init(w, step, (enum wrf_var)v, &j.check[v]);
    data_nc_unlock();

    ok = parallel_for(j.slabs, 1, &j, step_slabs);
    if (!ok)
        goto done;

    /* What the slabs found, added up in their order and reported as the whole step. */
    ok = false;
    struct check_sum sum[WRF_VAR_COUNT];
    for (int v = 0; v < WRF_VAR_COUNT; v++)
        check_sum_init(&sum[v]);
    size_t bad_range = SIZE_MAX, bad_order = SIZE_MAX;
    float bad_z = 0.0f;
    for (size_t sl = 0; sl < j.slabs; sl++) {
        const struct slab_result *r = &j.res[sl];
        for (int v = 0; v < WRF_VAR_COUNT; v++)
            check_sum_add(&sum[v], &r->sum[v]);
        if (r->range < bad_range) {
            bad_range = r->range;
            bad_z = r->range_z;
        }
        bad_order = r->order < bad_order ? r->order : bad_order;
        stats->below_terrain += r->below;
        stats->above_top += r->above;
    }
    for (int v = WRF_PH; v <= WRF_PHB; v++) {
        check_sum_stats(&sum[v], &stats->var[v]);
        const struct wrf_var_stats *st = &stats->var[v];
        if (st->nan + st->inf + st->fill > 0) {
            log_error("%s: variable %s, time %d: %zu NaN, Inf or fill values: heights "
                      "cannot be placed",
                      path, var_names[v], w->steps[step].index, st->nan + st->inf + st->fill);
            goto done;
        }
    }
    /* A height out of range before a column out of order, each the first in the file's
     * order. */
    if (bad_range != SIZE_MAX) {
        size_t i = bad_range, col = i % cols;
        log_error("%s: variables PH, PHB, time %d: a height of %g m in column (%zu, %zu), "
                  "level %zu: expected %g m to %g km above sea level",
                  path, w->steps[step].index, bad_z, s.x0 + (col % s.nx) * s.sx,
                  s.y0 + (col / s.nx) * s.sy, i / cols, DATA_HEIGHT_MIN_M,
                  DATA_HEIGHT_MAX_M / 1000.0);
        goto done;
    }
    if (bad_order != SIZE_MAX) {
        size_t col = bad_order;
        log_error("%s: variables PH, PHB, time %d: heights do not increase upward in column "
                  "(%zu, %zu)",
                  path, w->steps[step].index, s.x0 + (col % s.nx) * s.sx,
                  s.y0 + (col / s.nx) * s.sy);
        goto done;
    }
    for (int m = 0; m < j.nmass; m++) {
        enum wrf_var v = j.mass[m];
        check_sum_stats(&sum[v], &stats->var[v]);
        if (!report(w, step, v, &stats->var[v]))
            goto done;
    }
    if (j.read_vapour) {
        check_sum_stats(&sum[WRF_QVAPOR], &stats->var[WRF_QVAPOR]);
        if (!report(w, step, WRF_QVAPOR, &stats->var[WRF_QVAPOR]))
            goto done;
    }
    if (j.vapour) {
        /* Shares in order (counts: any order adds up the same); without QVAPOR, the stand-in
         * profile derived_field puts on each level. */
        for (int t = 0; t < PARALLEL_MAX; t++)
            transfer_histogram_merge(vapour, &j.vapour[t]);
        size_t plane = (size_t)g->n[0] * (size_t)g->n[1];
        for (int k = 0; !j.read_vapour && k < no; k++)
            transfer_histogram_add_times(
                vapour, (float)derived_vapour_standard(grid3_centre_z(g, k)), plane);
    }
    if (want_wind && !read_wind(w, step, d, &s, &whole, out, stats))
        goto done;
    for (int v = WRF_P; j.air && v <= WRF_T; v++) {
        check_sum_stats(&sum[v], &stats->var[v]);
        if (!report(w, step, (enum wrf_var)v, &stats->var[v]))
            goto done;
    }
    ok = true;

done:
    plan_finish(&whole);
    free(fill);
    free(rho_std);
    free(j.res);
    free(j.vapour);
    if (!ok) {
        field_volume_finish(out);
        if (ext)
            ext_volume_finish(ext);
    }
    return ok;
}

bool wrf_read_step(struct wrf *w, int step, const struct wrf_desc *d, struct field_volume *out,
                   struct wrf_stats *stats)
{
    return read_step(w, step, d, false, NULL, out, NULL, NULL, stats);
}

bool wrf_scan_step(struct wrf *w, int step, const struct wrf_desc *d, struct wrf_stats *stats)
{
    struct field_volume grid;
    bool ok = read_step(w, step, d, true, NULL, &grid, NULL, NULL, stats);
    field_volume_finish(&grid);
    return ok;
}

bool wrf_read_step_ext(struct wrf *w, int step, const struct wrf_desc *d,
                       const struct optics_params *optics, const struct species_select *sel,
                       struct transfer_histogram *vapour, struct ext_volume *out,
                       struct wrf_stats *stats)
{
    struct ext_beta b;
    ext_beta_init(&b, optics, sel, w->meta.has_species);
    struct field_volume grid;
    bool ok = read_step(w, step, d, false, &b, &grid, out, vapour, stats);
    field_volume_finish(&grid);
    return ok;
}

bool wrf_read_plain(struct wrf *w, int step, const struct wrf_desc *d, double *bytes)
{
    struct selection s;
    if (step < 0 || step >= w->step_count || !make_selection(w, d, &s)) {
        log_error("time step %d out of range: the data has %d (0 to %d)", step, w->step_count,
                  w->step_count - 1);
        return false;
    }
    const struct wrf_file *f = &w->files[w->steps[step].file];
    float *bufs[WRF_VAR_COUNT] = {NULL};
    double total = 0.0;
    bool ok = true;
    data_nc_lock_file(f->path, "reading", false);
    for (int v = 0; v < WRF_VAR_COUNT && ok; v++) {
        bool want = v < SPECIES_COUNT ? w->meta.has_species[v]
                    : v == WRF_QVAPOR ? d->qvapor && w->meta.has_qvapor
                    : is_wind(v)      ? d->wind && f->varid[v] >= 0
                                      : !d->no_density || d->temperature || v == WRF_PH ||
                                       v == WRF_PHB;
        if (!want)
            continue;
        int levels = v == WRF_PH || v == WRF_PHB || v == WRF_W ? w->nzs : w->meta.nz;
        /* The staggered U and V: one more point along their axis, as the reader's two faces
         * cover. */
        struct selection sv = s;
        if (v == WRF_U)
            sv.nx++;
        if (v == WRF_V)
            sv.ny++;
        size_t n = (size_t)sv.nx * sv.ny * (size_t)levels;
        bufs[v] = malloc(n * sizeof(float));
        ok = bufs[v] && read_var(w, step, (enum wrf_var)v, &sv, levels, bufs[v]);
        if (!bufs[v])
            log_error("%s: out of memory reading %s", f->path, var_names[v]);
        total += (double)n * sizeof(float);
    }
    data_nc_unlock();
    for (int v = 0; v < WRF_VAR_COUNT; v++)
        free(bufs[v]);
    if (bytes)
        *bytes = total;
    return ok;
}

/* ---- one point ------------------------------------------------------------------------- */

/* Reads V at NXB x NYB columns SX, SY apart from (X0, Y0) on LEVELS levels into BUF (levels
 * slowest, then rows). */
static bool read_cols(const struct wrf *w, int step, int varid, const char *name, int x0, int y0,
                      int nxb, int nyb, int sx, int sy, int levels, float *buf)
{
    const struct wrf_file *f = &w->files[w->steps[step].file];
    size_t start[4] = {(size_t)w->steps[step].index, 0, (size_t)y0, (size_t)x0};
    size_t count[4] = {1, (size_t)levels, (size_t)nyb, (size_t)nxb};
    ptrdiff_t stride[4] = {1, 1, sy, sx};
    int st = nc_get_vars_float(f->ncid, varid, start, count, stride, buf);
    if (st != NC_NOERR) {
        log_error("%s: variable %s, time %d: cannot read: %s", f->path, name,
                  w->steps[step].index, nc_strerror(st));
        return false;
    }
    return true;
}

/* The lower voxel and the weight of the next along one axis of N voxel centres (edge voxels
 * clamped, as the eye pass samples); a position within 1e-6 voxels of a centre is that
 * centre. */
static void axis_weight(double f, int n, int *i0, int *count, double *t)
{
    if (fabs(f - round(f)) < 1e-6)
        f = round(f);
    if (n < 2 || f <= 0.0) {
        *i0 = 0;
        *count = n < 2 ? 1 : 2;
        *t = 0.0;
        return;
    }
    if (f >= n - 1) {
        *i0 = n - 2;
        *count = 2;
        *t = 1.0;
        return;
    }
    *i0 = (int)floor(f);
    *count = 2;
    *t = f - *i0;
}

/* A 2-D variable NAME (with or without a leading Time) at the block's columns, bilinear with
 * the weights WT; false when the file lacks it or it cannot be read. */
static bool point_2d(const struct wrf *w, int step, const char *name, int x0, int y0, int nxb,
                     int nyb, int sx, int sy, const double wt[4], double *out)
{
    const struct wrf_file *f = &w->files[w->steps[step].file];
    int varid, ndims;
    if (nc_inq_varid(f->ncid, name, &varid) != NC_NOERR ||
        nc_inq_varndims(f->ncid, varid, &ndims) != NC_NOERR || (ndims != 2 && ndims != 3))
        return false;
    size_t start[3] = {(size_t)w->steps[step].index, (size_t)y0, (size_t)x0};
    size_t count[3] = {1, (size_t)nyb, (size_t)nxb};
    ptrdiff_t stride[3] = {1, sy, sx};
    float v[4];
    if (nc_get_vars_float(f->ncid, varid, ndims == 3 ? start : start + 1,
                          ndims == 3 ? count : count + 1, ndims == 3 ? stride : stride + 1,
                          v) != NC_NOERR)
        return false;
    double sum = 0.0;
    for (int c = 0; c < nxb * nyb; c++) {
        if (!isfinite(v[c]))
            return false;
        sum += wt[c] * v[c];
    }
    *out = sum;
    return true;
}

/* What wrf_read_point works with: the block of columns, their heights, the two output levels
 * around the point and the weights. */
struct point_block {
    int x0, y0, nxb, nyb, sx, sy, cols;
    int nz, nzs;
    double wt[4];      /* the columns' bilinear weights */
    float *zw;         /* staggered heights, nzs x cols */
    double *zm;        /* each column's mass level heights, cols x nz */
    double tol;        /* the output grid's closeness to a level */
    int nk;            /* 1 or 2 output levels */
    double tk;         /* weight of the second */
    double zk[2];      /* their heights */
    float *one;        /* scratch: one column on the mass levels */
};

/* The value at the point of BUF (nz x cols on the mass levels), as the field volume holds it:
 * each column resampled to the two output levels (OUTSIDE below the ground and above the top;
 * FILL_STD: such values, and NaN, replaced by the standard atmosphere's temperature (1) or
 * pressure (2)), then bilinear across the columns and linear between the levels. */
static double point_value(const struct point_block *b, const float *buf, float outside,
                          int fill_std)
{
    double sum = 0.0;
    for (int c = 0; c < b->cols; c++) {
        for (int k = 0; k < b->nz; k++)
            b->one[k] = buf[(size_t)k * b->cols + c];
        float out[2];
        resample_at(b->zm + (size_t)c * b->nz, b->one, b->nz, b->zw[c],
                    b->zw[(size_t)b->nz * b->cols + c], b->zk, b->nk, b->tol, outside, out, NULL);
        for (int k = 0; k < b->nk; k++) {
            if (fill_std && !isfinite(out[k])) {
                double t, p;
                wrf_std_atmosphere(b->zk[k], &t, &p);
                out[k] = (float)(fill_std == 1 ? t : p);
            }
            double wk = b->nk == 1 ? 1.0 : k ? b->tk : 1.0 - b->tk;
            sum += b->wt[c] * wk * out[k];
        }
    }
    return sum;
}

enum wrf_point_result wrf_read_point(struct wrf *w, int step, const struct wrf_desc *d,
                                     const double p[3], struct wrf_point *out)
{
    memset(out, 0, sizeof(*out));
    out->temperature_k = NAN;
    if (step < 0 || step >= w->step_count) {
        log_error("time step %d out of range: the data has %d (0 to %d)", step, w->step_count,
                  w->step_count - 1);
        return WRF_POINT_ERROR;
    }
    struct selection s;
    if (!make_selection(w, d, &s))
        return WRF_POINT_ERROR;
    const struct wrf_meta *m = &w->meta;
    /* The grid wrf_read_step makes. */
    struct grid3 og;
    if (!output_grid(w, d, &s, &og))
        return WRF_POINT_ERROR;
    const double *sp = og.spacing, *org = og.origin;
    const int n[3] = {s.nx, s.ny, s.nz};
    double f[3];
    for (int a = 0; a < 3; a++) {
        double rel = a < 2 ? (p[a] - org[a]) / sp[a] : grid3_z_to_voxel(&og, p[a]);
        if (!(rel >= -1e-9 && rel <= n[a] + 1e-9)) {
            if (a < 2)
                return WRF_POINT_OUTSIDE;
            /* Below or above the whole height grid: the column's own ground and top, read
             * below, are what the point is below or above (the grid's bottom is the
             * domain's lowest ground, not this column's). */
            rel = rel < 0.0 ? 0.0 : n[2];
        }
        f[a] = rel - 0.5;
    }
    struct point_block b = {.sx = s.sx, .sy = s.sy, .nz = m->nz, .nzs = w->nzs};
    int ia, ja, ka;
    double tx, ty;
    axis_weight(f[0], s.nx, &ia, &b.nxb, &tx);
    axis_weight(f[1], s.ny, &ja, &b.nyb, &ty);
    axis_weight(f[2], s.nz, &ka, &b.nk, &b.tk);
    b.x0 = s.x0 + ia * s.sx;
    b.y0 = s.y0 + ja * s.sy;
    b.cols = b.nxb * b.nyb;
    for (int r = 0; r < b.nyb; r++)
        for (int q = 0; q < b.nxb; q++)
            b.wt[q + b.nxb * r] = (b.nxb == 1 ? 1.0 : q ? tx : 1.0 - tx) *
                                  (b.nyb == 1 ? 1.0 : r ? ty : 1.0 - ty);
    b.tol = 1e-4 * fabs(grid3_min_dz(&og));
    for (int k = 0; k < b.nk; k++)
        b.zk[k] = grid3_centre_z(&og, ka + k);
    const struct wrf_file *file = &w->files[w->steps[step].file];
    int nz = b.nz, nzs = b.nzs, cols = b.cols;
    /* Scratch: two blocks of (nxb + 1) x (nyb + 1) columns on the staggered levels. */
    size_t block = (size_t)nzs * (size_t)(b.nxb + 1) * (size_t)(b.nyb + 1);
    float *a = malloc(block * sizeof(float)), *bb = malloc(block * sizeof(float));
    float *col = malloc((size_t)nz * (size_t)cols * sizeof(float));
    b.zm = malloc((size_t)nz * (size_t)cols * sizeof(double));
    b.zw = malloc((size_t)nzs * (size_t)cols * sizeof(float));
    b.one = malloc((size_t)nzs * sizeof(float));
    enum wrf_point_result result = WRF_POINT_ERROR;
    if (!a || !bb || !col || !b.zm || !b.zw || !b.one) {
        log_error("out of memory reading a point");
        goto done;
    }
    struct wrf_var_stats st;
#define READ(var, name, ox, oy, nx_, ny_, levels, buf)                                          \
    read_cols(w, step, file->varid[var], name, b.x0 + (ox), b.y0 + (oy), nx_, ny_, b.sx, b.sy, \
              levels, buf)
    data_nc_lock();
    /* Heights: (PH + PHB) / g on staggered levels, rounded to float as wrf_read_step does. */
    if (!READ(WRF_PH, "PH", 0, 0, b.nxb, b.nyb, nzs, a) ||
        !READ(WRF_PHB, "PHB", 0, 0, b.nxb, b.nyb, nzs, bb))
        goto unlock;
    for (size_t i = 0; i < (size_t)nzs * cols; i++) {
        b.zw[i] = (float)(((double)a[i] + (double)bb[i]) / WRF_G);
        if (!isfinite(b.zw[i])) {
            log_error("%s: variables PH, PHB, time %d: a height near the point is not finite",
                      file->path, w->steps[step].index);
            goto unlock;
        }
    }
    for (int c = 0; c < cols; c++)
        for (int k = 0; k < nz; k++)
            b.zm[(size_t)c * nz + k] = 0.5 * ((double)b.zw[(size_t)k * cols + c] +
                                              (double)b.zw[(size_t)(k + 1) * cols + c]);
    for (int c = 0; c < cols; c++) {
        out->ground_m += b.wt[c] * b.zw[c];
        out->top_m += b.wt[c] * b.zw[(size_t)nz * cols + c];
    }
    if (p[2] < out->ground_m) {
        result = WRF_POINT_BELOW;
        goto unlock;
    }
    if (p[2] > out->top_m) {
        result = WRF_POINT_ABOVE;
        goto unlock;
    }
    for (int v = 0; v <= WRF_QVAPOR; v++) {
        if (file->varid[v] < 0)
            continue;
        if (!READ(v, var_names[v], 0, 0, b.nxb, b.nyb, nz, a))
            goto unlock;
        sanitize(w, step, (enum wrf_var)v, a, (size_t)nz * cols, 0.0f, &st);
        double value = point_value(&b, a, 0.0f, 0);
        if (v < SPECIES_COUNT) {
            out->has_species[v] = true;
            out->q[v] = value;
        } else {
            out->has_qvapor = true;
            out->qvapor = value;
        }
    }
    /* Pressure and temperature on the mass levels, as wrf_read_step makes them. */
    if (!READ(WRF_P, "P", 0, 0, b.nxb, b.nyb, nz, a) ||
        !READ(WRF_PB, "PB", 0, 0, b.nxb, b.nyb, nz, bb))
        goto unlock;
    sanitize(w, step, WRF_P, a, (size_t)nz * cols, NAN, &st);
    sanitize(w, step, WRF_PB, bb, (size_t)nz * cols, NAN, &st);
    for (size_t i = 0; i < (size_t)nz * cols; i++)
        a[i] += bb[i];
    out->pressure_pa = point_value(&b, a, NAN, 2);
    if (!READ(WRF_T, "T", 0, 0, b.nxb, b.nyb, nz, bb))
        goto unlock;
    sanitize(w, step, WRF_T, bb, (size_t)nz * cols, NAN, &st);
    for (size_t i = 0; i < (size_t)nz * cols; i++) {
        double t = optics_wrf_temperature_fast(a[i], (double)bb[i] + WRF_T0);
        col[i] = t > 0.0 ? (float)t : NAN;
        bb[i] = (float)((double)bb[i] + WRF_T0);
    }
    out->theta_k = point_value(&b, bb, NAN, 0);
    out->temperature_k = point_value(&b, col, NAN, 1);
    /* The wind: U over its west_east_stag faces, V over south_north_stag, W over its levels. */
    out->has_wind = file->varid[WRF_U] >= 0 && file->varid[WRF_V] >= 0;
    if (out->has_wind) {
        if (!READ(WRF_U, "U", 0, 0, b.nxb, b.nyb, nz, a) ||
            !READ(WRF_U, "U", 1, 0, b.nxb, b.nyb, nz, bb))
            goto unlock;
        sanitize(w, step, WRF_U, a, (size_t)nz * cols, 0.0f, &st);
        sanitize(w, step, WRF_U, bb, (size_t)nz * cols, 0.0f, &st);
        for (size_t i = 0; i < (size_t)nz * cols; i++)
            col[i] = 0.5f * (a[i] + bb[i]);
        double u = point_value(&b, col, 0.0f, 0);
        if (!READ(WRF_V, "V", 0, 0, b.nxb, b.nyb, nz, a) ||
            !READ(WRF_V, "V", 0, 1, b.nxb, b.nyb, nz, bb))
            goto unlock;
        sanitize(w, step, WRF_V, a, (size_t)nz * cols, 0.0f, &st);
        sanitize(w, step, WRF_V, bb, (size_t)nz * cols, 0.0f, &st);
        for (size_t i = 0; i < (size_t)nz * cols; i++)
            col[i] = 0.5f * (a[i] + bb[i]);
        double v = point_value(&b, col, 0.0f, 0);
        double ca, sa;
        if (point_2d(w, step, "COSALPHA", b.x0, b.y0, b.nxb, b.nyb, b.sx, b.sy, b.wt, &ca) &&
            point_2d(w, step, "SINALPHA", b.x0, b.y0, b.nxb, b.nyb, b.sx, b.sy, b.wt, &sa)) {
            /* Grid-relative to earth-relative (the WRF users' forum, "Converting model
             * grid-relative wind to earth-relative wind"). */
            out->u = u * ca - v * sa;
            out->v = v * ca + u * sa;
            out->earth_relative = true;
        } else {
            out->u = u;
            out->v = v;
            out->earth_relative = m->map_proj == 3 || m->map_proj == 6;
        }
        out->has_w = file->varid[WRF_W] >= 0;
        if (out->has_w) {
            if (!READ(WRF_W, "W", 0, 0, b.nxb, b.nyb, nzs, a))
                goto unlock;
            sanitize(w, step, WRF_W, a, (size_t)nzs * cols, 0.0f, &st);
            for (size_t i = 0; i < (size_t)nz * cols; i++)
                col[i] = 0.5f * (a[i] + a[i + cols]);
            out->w = point_value(&b, col, 0.0f, 0);
        }
    }
#undef READ
    result = WRF_POINT_OK;
unlock:
    data_nc_unlock();
done:
    free(a);
    free(bb);
    free(col);
    free(b.zm);
    free(b.zw);
    free(b.one);
    return result;
}

/* ---- what a file is, and the grid without reading --------------------------------------- */

bool wrf_probe(const char *path)
{
    static const char *const dims[] = {"west_east", "south_north", "bottom_top",
                                       "bottom_top_stag"};
    static const char *const vars[] = {"PH", "PHB"};
    int nc, id;
    char why[512];
    data_nc_lock_file(path, "reading", false);
    bool yes = data_nc_open(path, &nc, NULL, why, sizeof(why));
    if (yes) {
        for (size_t i = 0; yes && i < sizeof(dims) / sizeof(dims[0]); i++)
            yes = nc_inq_dimid(nc, dims[i], &id) == NC_NOERR;
        for (size_t i = 0; yes && i < sizeof(vars) / sizeof(vars[0]); i++)
            yes = nc_inq_varid(nc, vars[i], &id) == NC_NOERR;
        nc_close(nc);
    }
    data_nc_unlock();
    return yes;
}

bool wrf_grid(const struct wrf *w, const struct wrf_desc *d, struct grid3 *out)
{
    /* The grid wrf_read_step puts the step on (its "output grid"), from the same selection. */
    struct selection s;
    return make_selection(w, d, &s) && output_grid(w, d, &s, out);
}
