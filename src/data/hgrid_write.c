#include "data/hgrid_write.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/cf.h"
#include "data/geo.h"
#include "data/nclock.h"
#include "data/wrf_write.h"

/* CM1's constants (constants.incl). */
#define RD 287.04
#define CP 1005.7
#define P00 1.0e5

enum { W_Q0 = 0, W_QV = SPECIES_COUNT, W_T, W_P, W_U, W_V, W_W, W_TIME, W_COUNT };

static const char *const cm1_names[W_COUNT] = {"qc", "qr", "qi", "qs", "qg", "qv", "th",
                                               "prs", "u", "v", "w", "time"};
static const char *const cf_names[W_COUNT] = {"cloud", "rain", "ice", "snow", "graupel",
                                              "hus", "ta", "pa", "ua", "va", "wa", "time"};

struct hgrid_writer {
    char *path, *tmp;
    struct grid3 grid;
    struct hgrid_write_desc desc;
    int ncid;
    bool defined, failed;
    bool has[SPECIES_COUNT];
    int var[W_COUNT];
    int steps;
    float *buf; /* (nx + 1) (ny + 1) (nz + 1) */
};

static bool ok_nc(int st, const struct hgrid_writer *w, const char *what)
{
    if (st == NC_NOERR)
        return true;
    log_error("%s: %s: %s", w->path, what, nc_strerror(st));
    return false;
}

static void text(int nc, int var, const char *name, const char *value)
{
    nc_put_att_text(nc, var, name, strlen(value), value);
}

struct hgrid_writer *hgrid_writer_create(const char *path, const struct grid3 *grid,
                                         const struct hgrid_write_desc *d)
{
    struct hgrid_writer *w = calloc(1, sizeof(*w));
    if (!w) {
        log_error("%s: out of memory", path);
        return NULL;
    }
    w->ncid = -1;
    w->grid = *grid;
    w->desc = *d;
    w->path = strdup(path);
    w->buf = malloc((size_t)(grid->n[0] + 1) * (grid->n[1] + 1) * (grid->n[2] + 1) *
                    sizeof(float));
    if (!w->path || !w->buf) {
        log_error("%s: out of memory", path);
        hgrid_writer_destroy(w);
        return NULL;
    }
    if (!data_nc_create_beside(path, NC_CLOBBER | NC_64BIT_OFFSET, &w->tmp, &w->ncid)) {
        hgrid_writer_destroy(w);
        return NULL;
    }
    return w;
}

/* Height of level K's centre (or of its lower face when FACE: half way between the centres
 * on a stretched grid, the box's bottom and top at the ends), m. */
static double level_z(const struct grid3 *g, int k, bool face)
{
    if (!grid3_stretched(g))
        return g->origin[2] + (face ? k : k + 0.5) * g->spacing[2];
    if (!face)
        return grid3_centre_z(g, k);
    if (k <= 0)
        return g->origin[2];
    if (k >= g->n[2])
        return g->origin[2] + g->n[2] * g->spacing[2];
    return 0.5 * (grid3_centre_z(g, k - 1) + grid3_centre_z(g, k));
}

/* Coordinate of point I on axis A (centres, or faces when FACE), in the file's units. */
static double coord(const struct hgrid_writer *w, int a, double i, bool face)
{
    const struct grid3 *g = &w->grid;
    double m = a == 2 ? level_z(g, (int)i, face)
                      : g->origin[a] + (face ? i : i + 0.5) * g->spacing[a];
    bool cf = w->desc.kind == HGRID_CF;
    if (cf && w->desc.latlon && a < 2) {
        double span_deg = g->spacing[a] / GEO_EARTH_RADIUS_M * 180.0 / M_PI;
        if (a == 0)
            span_deg /= cos(w->desc.cen_lat * M_PI / 180.0);
        double c = a == 0 ? w->desc.cen_lon : w->desc.cen_lat;
        return c + ((face ? i : i + 0.5) - 0.5 * g->n[a]) * span_deg;
    }
    double k = (!cf || w->desc.coords_km) ? 1000.0 : 1.0;
    if (cf && a == 2 && w->desc.positive_down)
        m = -m;
    return m / k;
}

static bool put_axis(struct hgrid_writer *w, int var, int a, int n, bool face, bool top_down)
{
    double *v = malloc((size_t)n * sizeof(double));
    if (!v)
        return false;
    for (int i = 0; i < n; i++)
        v[i] = coord(w, a, top_down ? n - 1 - i : i, face);
    bool ok = ok_nc(nc_put_var_double(w->ncid, var, v), w, "coordinates");
    free(v);
    return ok;
}

static bool define(struct hgrid_writer *w, const struct field_volume *v)
{
    const struct grid3 *g = &w->grid;
    bool cf = w->desc.kind == HGRID_CF;
    int nc = w->ncid;
    const char *const *names = cf ? cf_names : cm1_names;
    int dt, dz, dy, dx, dzf = -1, dyf = -1, dxf = -1, dnv = -1;
    if (!ok_nc(nc_def_dim(nc, "time", NC_UNLIMITED, &dt), w, "time") ||
        !ok_nc(nc_def_dim(nc, cf ? "z" : "zh", (size_t)g->n[2], &dz), w, "z") ||
        !ok_nc(nc_def_dim(nc, cf ? "y" : "yh", (size_t)g->n[1], &dy), w, "y") ||
        !ok_nc(nc_def_dim(nc, cf ? "x" : "xh", (size_t)g->n[0], &dx), w, "x"))
        return false;
    if (!cf && (!ok_nc(nc_def_dim(nc, "zf", (size_t)g->n[2] + 1, &dzf), w, "zf") ||
                !ok_nc(nc_def_dim(nc, "yf", (size_t)g->n[1] + 1, &dyf), w, "yf") ||
                !ok_nc(nc_def_dim(nc, "xf", (size_t)g->n[0] + 1, &dxf), w, "xf")))
        return false;
    if (cf && !ok_nc(nc_def_dim(nc, "nv", 2, &dnv), w, "nv"))
        return false;
    int ax[3], axf[3] = {-1, -1, -1}, zb = -1;
    int adim[3] = {dx, dy, dz}, fdim[3] = {dxf, dyf, dzf};
    static const char *const cm1_axes[3] = {"xh", "yh", "zh"}, *const cm1_faces[3] = {"xf", "yf",
                                                                                      "zf"};
    static const char *const cf_axes[3] = {"x", "y", "z"}, *const axis_attr[3] = {"X", "Y", "Z"};
    for (int a = 0; a < 3; a++) {
        if (!ok_nc(nc_def_var(nc, cf ? cf_axes[a] : cm1_axes[a], cf ? NC_DOUBLE : NC_FLOAT, 1,
                              &adim[a], &ax[a]),
                   w, "axis"))
            return false;
        if (cf) {
            bool deg = w->desc.latlon && a < 2;
            text(nc, ax[a], "units", deg ? (a ? "degrees_north" : "degrees_east")
                                     : w->desc.coords_km ? "km" : "m");
            text(nc, ax[a], "axis", axis_attr[a]);
            text(nc, ax[a], "standard_name", deg ? (a ? "latitude" : "longitude")
                                             : a == 0 ? "projection_x_coordinate"
                                             : a == 1 ? "projection_y_coordinate"
                                                      : "height");
            if (a == 2) {
                text(nc, ax[a], "positive", w->desc.positive_down ? "down" : "up");
                text(nc, ax[a], "bounds", "z_bnds");
                int bd[2] = {dz, dnv};
                if (!ok_nc(nc_def_var(nc, "z_bnds", NC_DOUBLE, 2, bd, &zb), w, "z_bnds"))
                    return false;
            }
        } else {
            text(nc, ax[a], "units", "km");
            if (!ok_nc(nc_def_var(nc, cm1_faces[a], NC_FLOAT, 1, &fdim[a], &axf[a]), w, "faces"))
                return false;
            text(nc, axf[a], "units", "km");
        }
    }
    if (!ok_nc(nc_def_var(nc, "time", cf ? NC_DOUBLE : NC_FLOAT, 1, &dt, &w->var[W_TIME]), w,
               "time"))
        return false;
    if (cf) {
        const char *s = w->desc.start ? w->desc.start : "2000-01-01_00:00:00";
        char units[64];
        snprintf(units, sizeof(units), "seconds since %.10s %.8s", s, s + 11);
        text(nc, w->var[W_TIME], "units", units);
        text(nc, w->var[W_TIME], "standard_name", "time");
        text(nc, w->var[W_TIME], "axis", "T");
    } else {
        text(nc, w->var[W_TIME], "units", "seconds");
        text(nc, w->var[W_TIME], "long_name", "time since beginning of simulation");
    }
    for (int k = 0; k < W_TIME; k++) {
        w->var[k] = -1;
        if (k < SPECIES_COUNT && (!v->q[k] || (w->desc.omit & (1u << k))))
            continue;
        if (k < SPECIES_COUNT)
            w->has[k] = true;
        int d4[4] = {dt, dz, dy, dx};
        if (!cf && k == W_U)
            d4[3] = dxf;
        if (!cf && k == W_V)
            d4[2] = dyf;
        if (!cf && k == W_W)
            d4[1] = dzf;
        if (!ok_nc(nc_def_var(nc, names[k], NC_FLOAT, 4, d4, &w->var[k]), w, names[k]))
            return false;
        const char *units = k <= W_QV ? (cf ? (w->desc.g_per_kg ? "g kg-1" : "kg kg-1") : "kg/kg")
                            : k == W_T ? "K"
                            : k == W_P ? (cf && w->desc.pressure_hpa ? "hPa" : "Pa")
                                       : (cf ? "m s-1" : "m/s");
        text(nc, w->var[k], "units", units);
        if (cf) {
            static const enum hgrid_var q[W_TIME] = {
                HGRID_CLOUD, HGRID_RAIN, HGRID_ICE, HGRID_SNOW, HGRID_GRAUPEL, HGRID_VAPOR,
                HGRID_TEMPERATURE, HGRID_PRESSURE, HGRID_U, HGRID_V, HGRID_W};
            text(nc, w->var[k], "standard_name", cf_standard_name(q[k]));
        }
    }
    text(nc, NC_GLOBAL, cf ? "Conventions" : "model", cf ? "CF-1.8" : "CM1 (convention)");
    text(nc, NC_GLOBAL, "source", "anvil synth: the procedural storm");
    if (!ok_nc(nc_enddef(nc), w, "define"))
        return false;
    bool top_down = cf && w->desc.top_down;
    bool ok = true;
    for (int a = 0; a < 3 && ok; a++) {
        ok = put_axis(w, ax[a], a, g->n[a], false,
                      (a == 2 && top_down) || (a == 1 && cf && w->desc.north_first));
        if (ok && axf[a] >= 0)
            ok = put_axis(w, axf[a], a, g->n[a] + 1, true, false);
    }
    if (ok && zb >= 0) {
        int n = g->n[2];
        double *b = malloc(2 * (size_t)n * sizeof(double));
        ok = b != NULL;
        for (int i = 0; ok && i < n; i++) {
            int k = top_down ? n - 1 - i : i;
            b[2 * i] = coord(w, 2, k, true);
            b[2 * i + 1] = coord(w, 2, k + 1, true);
        }
        ok = ok && ok_nc(nc_put_var_double(nc, zb, b), w, "z_bnds");
        free(b);
    }
    return ok;
}

/* Fills BUF with quantity K of V on its (possibly staggered) points, in the file's order. */
static void fill(const struct hgrid_writer *w, const struct field_volume *v, int k, size_t n[3])
{
    const struct grid3 *g = &w->grid;
    bool cf = w->desc.kind == HGRID_CF;
    bool top_down = cf && w->desc.top_down;
    n[0] = (size_t)g->n[0] + (!cf && k == W_U);
    n[1] = (size_t)g->n[1] + (!cf && k == W_V);
    n[2] = (size_t)g->n[2] + (!cf && k == W_W);
    for (size_t kk = 0; kk < n[2]; kk++) {
        size_t lev = top_down ? n[2] - 1 - kk : kk;
        for (size_t jw = 0; jw < n[1]; jw++)
            for (size_t i = 0; i < n[0]; i++) {
                size_t j = cf && w->desc.north_first ? n[1] - 1 - jw : jw;
                double x = g->origin[0] + (i + (k == W_U && !cf ? 0.0 : 0.5)) * g->spacing[0];
                double y = g->origin[1] + (j + (k == W_V && !cf ? 0.0 : 0.5)) * g->spacing[1];
                double z = level_z(g, (int)lev, k == W_W && !cf);
                double val = 0.0, t, p;
                if (k < SPECIES_COUNT || k == W_QV) {
                    const float *q = k == W_QV ? v->qvapor : v->q[k];
                    size_t idx = grid3_index(g, (int)i, (int)j, (int)lev);
                    val = q ? q[idx] : 0.01 * exp(-z / 2500.0);
                    if (cf && w->desc.g_per_kg)
                        val *= 1000.0;
                } else if (k == W_T || k == W_P) {
                    wrf_std_atmosphere(z, &t, &p);
                    if (k == W_P)
                        val = cf && w->desc.pressure_hpa ? p / 100.0 : p;
                    else
                        val = cf ? t : t * pow(P00 / p, RD / CP); /* CM1: theta */
                } else {
                    double u, vv, ww;
                    wrf_synth_wind(g, x - g->origin[0], y - g->origin[1], z, &u, &vv, &ww);
                    val = k == W_U ? u : k == W_V ? vv : ww;
                }
                w->buf[i + n[0] * (jw + n[1] * kk)] = (float)val;
            }
    }
}

bool hgrid_writer_add(struct hgrid_writer *w, const struct field_volume *v, double seconds)
{
    if (w->failed)
        return false;
    for (int a = 0; a < 3; a++)
        if (v->grid.n[a] != w->grid.n[a]) {
            log_error("%s: a step of another grid", w->path);
            w->failed = true;
            return false;
        }
    data_nc_lock_file(w->path, "writing", true);
    bool ok = true;
    if (!w->defined) {
        ok = define(w, v);
        w->defined = true;
    }
    size_t t = (size_t)w->steps;
    if (ok)
        ok = ok_nc(nc_put_var1_double(w->ncid, w->var[W_TIME], &t, &seconds), w, "time");
    for (int k = 0; k < W_TIME && ok; k++) {
        if (w->var[k] < 0)
            continue;
        if (k < SPECIES_COUNT && !v->q[k]) {
            log_error("%s: step %d lacks %s, which the first step had", w->path, w->steps,
                      species_name((enum species)k));
            ok = false;
            break;
        }
        size_t n[3];
        fill(w, v, k, n);
        size_t s4[4] = {t, 0, 0, 0}, c4[4] = {1, n[2], n[1], n[0]};
        ok = ok_nc(nc_put_vara_float(w->ncid, w->var[k], s4, c4, w->buf), w, "data");
    }
    data_nc_unlock();
    if (ok)
        w->steps++;
    else
        w->failed = true;
    return ok;
}

bool hgrid_writer_finish(struct hgrid_writer *w)
{
    if (!w)
        return false;
    bool ok = data_nc_finish_beside(w->path, &w->tmp, &w->ncid, !w->failed, w->steps);
    hgrid_writer_destroy(w);
    return ok;
}

void hgrid_writer_destroy(struct hgrid_writer *w)
{
    if (!w)
        return;
    data_nc_abandon(&w->tmp, &w->ncid);
    free(w->path);
    free(w->buf);
    free(w);
}
