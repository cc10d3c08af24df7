#include "data/wrf_write.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/nclock.h"
#include "data/wrf.h"

#define DATE_LEN 19
#define EARTH_RADIUS 6370000.0 /* WRF's sphere */
#define R_D 287.0
#define C_P 1004.5 /* WRF: cp = 7 r_d / 2 */
#define P0 100000.0
#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

enum {
    V_Q0 = 0,
    V_QVAPOR = SPECIES_COUNT,
    V_P,
    V_PB,
    V_T,
    V_PH,
    V_PHB,
    V_HGT,
    V_LANDMASK,
    V_XLAT,
    V_XLONG,
    V_U,
    V_V,
    V_W,
    V_TIMES,
    V_COUNT
};

struct wrf_writer {
    char *path, *tmp;
    struct grid3 grid;
    struct wrf_write_desc desc;
    char title[128];
    int ncid;
    bool defined, failed;
    bool has[SPECIES_COUNT];
    int var[V_COUNT];
    int steps;
    float *plane;
};

void wrf_std_atmosphere(double z, double *temperature, double *pressure)
{
    /* Layers of the 1976 standard atmosphere up to 47 km, in geopotential height. */
    static const double base_h[4] = {0.0, 11000.0, 20000.0, 32000.0};
    static const double lapse[4] = {-0.0065, 0.0, 0.001, 0.0028};
    static const double base_t[4] = {288.15, 216.65, 216.65, 228.65};
    static const double base_p[4] = {101325.0, 22632.06, 5474.889, 868.0187};
    const double g0 = 9.80665, r = 287.053;
    if (z < 0.0)
        z = 0.0;
    if (z > 47000.0)
        z = 47000.0;
    z = 6356766.0 * z / (6356766.0 + z); /* geometric -> geopotential */
    int l = 3;
    while (l > 0 && z < base_h[l])
        l--;
    double dh = z - base_h[l];
    double t = base_t[l] + lapse[l] * dh;
    double p = lapse[l] == 0.0 ? base_p[l] * exp(-g0 * dh / (r * base_t[l]))
                               : base_p[l] * pow(t / base_t[l], -g0 / (r * lapse[l]));
    *temperature = t;
    *pressure = p;
}

struct wrf_writer *wrf_writer_create(const char *path, const struct grid3 *grid,
                                     const struct wrf_write_desc *d)
{
    for (int a = 0; a < 3; a++) {
        if (grid->n[a] <= 0 || !(grid->spacing[a] > 0)) {
            log_error("%s: cannot write a %d x %d x %d WRF grid", path, grid->n[0], grid->n[1],
                      grid->n[2]);
            return NULL;
        }
    }
    struct wrf_writer *w = calloc(1, sizeof(*w));
    if (!w) {
        log_error("%s: out of memory", path);
        return NULL;
    }
    w->ncid = -1;
    w->grid = *grid;
    if (d)
        w->desc = *d;
    snprintf(w->title, sizeof(w->title), " %s",
             (d && d->title) ? d->title : "OUTPUT FROM ANVIL SYNTH");
    w->desc.title = NULL;
    w->path = strdup(path);
    w->plane = malloc((size_t)grid->n[0] * grid->n[1] * 2 * sizeof(float));
    if (!w->path || !w->plane) {
        log_error("%s: out of memory", path);
        wrf_writer_destroy(w);
        return NULL;
    }
    if (!data_nc_create_beside(path, NC_CLOBBER | NC_64BIT_OFFSET, &w->tmp, &w->ncid)) {
        wrf_writer_destroy(w);
        return NULL;
    }
    data_nc_lock_file(w->path, "writing", true);
    nc_set_fill(w->ncid, NC_NOFILL, NULL);
    data_nc_unlock();
    return w;
}

static void text_att(int nc, int var, const char *name, const char *value)
{
    nc_put_att_text(nc, var, name, strlen(value), value);
}

static bool def_field(struct wrf_writer *w, int slot, const char *name, int ndims, const int *dims,
                      const char *order, const char *description, const char *units,
                      const char *stagger, nc_type type)
{
    int st = nc_def_var(w->ncid, name, type, ndims, dims, &w->var[slot]);
    if (st != NC_NOERR) {
        log_error("%s: variable %s: %s", w->tmp, name, nc_strerror(st));
        return false;
    }
    int v = w->var[slot];
    if (type != NC_CHAR) {
        int ft = 104;
        nc_put_att_int(w->ncid, v, "FieldType", NC_INT, 1, &ft);
        text_att(w->ncid, v, "MemoryOrder", order);
        text_att(w->ncid, v, "description", description);
        text_att(w->ncid, v, "units", units);
        text_att(w->ncid, v, "stagger", stagger);
        if (strcmp(name, "XLAT") && strcmp(name, "XLONG"))
            text_att(w->ncid, v, "coordinates", "XLONG XLAT");
    }
    return true;
}

static void float_att(int nc, const char *name, double value)
{
    float f = (float)value;
    nc_put_att_float(nc, NC_GLOBAL, name, NC_FLOAT, 1, &f);
}

static void int_att(int nc, const char *name, int value)
{
    nc_put_att_int(nc, NC_GLOBAL, name, NC_INT, 1, &value);
}

static const char *species_description[SPECIES_COUNT] = {
    "Cloud water mixing ratio", "Rain water mixing ratio", "Ice mixing ratio", "Snow mixing ratio",
    "Graupel mixing ratio"};

static bool define(struct wrf_writer *w, const struct field_volume *v, const char *date)
{
    const struct grid3 *g = &w->grid;
    int nc = w->ncid, dt, ds, dx, dy, dz, dzs, dxs, dys;
    int st = nc_def_dim(nc, "Time", NC_UNLIMITED, &dt);
    if (st == NC_NOERR)
        st = nc_def_dim(nc, "DateStrLen", DATE_LEN, &ds);
    if (st == NC_NOERR)
        st = nc_def_dim(nc, "west_east", (size_t)g->n[0], &dx);
    if (st == NC_NOERR)
        st = nc_def_dim(nc, "south_north", (size_t)g->n[1], &dy);
    if (st == NC_NOERR)
        st = nc_def_dim(nc, "bottom_top", (size_t)g->n[2], &dz);
    if (st == NC_NOERR)
        st = nc_def_dim(nc, "bottom_top_stag", (size_t)g->n[2] + 1, &dzs);
    if (st == NC_NOERR)
        st = nc_def_dim(nc, "west_east_stag", (size_t)g->n[0] + 1, &dxs);
    if (st == NC_NOERR)
        st = nc_def_dim(nc, "south_north_stag", (size_t)g->n[1] + 1, &dys);
    if (st != NC_NOERR) {
        log_error("%s: dimensions: %s", w->tmp, nc_strerror(st));
        return false;
    }
    int d3[4] = {dt, dz, dy, dx}, d3s[4] = {dt, dzs, dy, dx}, d2[3] = {dt, dy, dx};
    int d3u[4] = {dt, dz, dy, dxs}, d3v[4] = {dt, dz, dys, dx};
    int dtimes[2] = {dt, ds};
    bool ice = false;
    for (int f = 0; f < SPECIES_COUNT; f++) {
        w->has[f] = v->q[f] != NULL;
        ice = ice || (w->has[f] && species_is_ice((enum species)f));
    }
    bool ok = def_field(w, V_TIMES, "Times", 2, dtimes, "", "", "", "", NC_CHAR) &&
              def_field(w, V_XLAT, "XLAT", 3, d2, "XY ", "LATITUDE, SOUTH IS NEGATIVE",
                        "degree_north", "", NC_FLOAT) &&
              def_field(w, V_XLONG, "XLONG", 3, d2, "XY ", "LONGITUDE, WEST IS NEGATIVE",
                        "degree_east", "", NC_FLOAT) &&
              def_field(w, V_HGT, "HGT", 3, d2, "XY ", "Terrain Height", "m", "", NC_FLOAT) &&
              def_field(w, V_LANDMASK, "LANDMASK", 3, d2, "XY ",
                        "LAND MASK (1 FOR LAND, 0 FOR "
                        "WATER)",
                        "", "", NC_FLOAT) &&
              def_field(w, V_PH, "PH", 4, d3s, "XYZ", "perturbation geopotential", "m2 s-2", "Z",
                        NC_FLOAT) &&
              def_field(w, V_PHB, "PHB", 4, d3s, "XYZ", "base-state geopotential", "m2 s-2", "Z",
                        NC_FLOAT) &&
              def_field(w, V_T, "T", 4, d3, "XYZ", "perturbation potential temperature (theta-t0)",
                        "K", "", NC_FLOAT) &&
              def_field(w, V_P, "P", 4, d3, "XYZ", "perturbation pressure", "Pa", "", NC_FLOAT) &&
              def_field(w, V_PB, "PB", 4, d3, "XYZ", "BASE STATE PRESSURE", "Pa", "", NC_FLOAT) &&
              def_field(w, V_QVAPOR, "QVAPOR", 4, d3, "XYZ", "Water vapor mixing ratio", "kg kg-1",
                        "", NC_FLOAT) &&
              def_field(w, V_U, "U", 4, d3u, "XYZ", "x-wind component", "m s-1", "X",
                        NC_FLOAT) &&
              def_field(w, V_V, "V", 4, d3v, "XYZ", "y-wind component", "m s-1", "Y",
                        NC_FLOAT) &&
              def_field(w, V_W, "W", 4, d3s, "XYZ", "z-wind component", "m s-1", "Z", NC_FLOAT);
    for (int f = 0; f < SPECIES_COUNT && ok; f++) {
        if (w->has[f])
            ok = def_field(w, V_Q0 + f, species_wrf_name((enum species)f), 4, d3, "XYZ",
                           species_description[f], "kg kg-1", "", NC_FLOAT);
    }
    if (!ok)
        return false;

    int mp = w->desc.mp_physics ? w->desc.mp_physics : (ice ? 8 : 3);
    text_att(nc, NC_GLOBAL, "TITLE", w->title);
    text_att(nc, NC_GLOBAL, "START_DATE", date);
    text_att(nc, NC_GLOBAL, "SIMULATION_START_DATE", date);
    int_att(nc, "WEST-EAST_GRID_DIMENSION", g->n[0] + 1);
    int_att(nc, "SOUTH-NORTH_GRID_DIMENSION", g->n[1] + 1);
    int_att(nc, "BOTTOM-TOP_GRID_DIMENSION", g->n[2] + 1);
    float_att(nc, "DX", g->spacing[0]);
    float_att(nc, "DY", g->spacing[1]);
    int_att(nc, "MP_PHYSICS", mp);
    float_att(nc, "CEN_LAT", w->desc.cen_lat);
    float_att(nc, "CEN_LON", w->desc.cen_lon);
    float_att(nc, "TRUELAT1", w->desc.cen_lat);
    float_att(nc, "TRUELAT2", w->desc.cen_lat);
    float_att(nc, "MOAD_CEN_LAT", w->desc.cen_lat);
    float_att(nc, "STAND_LON", w->desc.cen_lon);
    int_att(nc, "MAP_PROJ", 3);
    if (w->desc.grid_id > 0) {
        int_att(nc, "GRID_ID", w->desc.grid_id);
        if (!w->desc.latlon_only) {
            int_att(nc, "PARENT_ID", w->desc.parent_id);
            int_att(nc, "I_PARENT_START", w->desc.i_parent_start);
            int_att(nc, "J_PARENT_START", w->desc.j_parent_start);
            int_att(nc, "PARENT_GRID_RATIO", w->desc.parent_grid_ratio);
        }
    }
    text_att(nc, NC_GLOBAL, "MAP_PROJ_CHAR", "Mercator");
    st = nc_enddef(nc);
    if (st != NC_NOERR) {
        log_error("%s: %s", w->tmp, nc_strerror(st));
        return false;
    }
    return true;
}

static bool put(struct wrf_writer *w, int slot, const size_t *start, const size_t *count,
                const float *data)
{
    int st = nc_put_vara_float(w->ncid, w->var[slot], start, count, data);
    if (st != NC_NOERR) {
        char name[NC_MAX_NAME + 1] = "?";
        nc_inq_varname(w->ncid, w->var[slot], name);
        log_error("%s: variable %s: %s", w->tmp, name, nc_strerror(st));
        return false;
    }
    return true;
}

/* The 2-D fields: Mercator latitude/longitude of the mass points, flat terrain at the
 * volume's bottom, all water. */
static bool write_2d(struct wrf_writer *w, size_t t)
{
    const struct grid3 *g = &w->grid;
    size_t plane = (size_t)g->n[0] * g->n[1];
    size_t s[3] = {t, 0, 0}, c[3] = {1, (size_t)g->n[1], (size_t)g->n[0]};
    double k = cos(w->desc.cen_lat * DEG) * EARTH_RADIUS;
    double y0 = k * log(tan(0.25 * PI + 0.5 * w->desc.cen_lat * DEG));
    float *lat = w->plane, *lon = w->plane + plane;
    /* The grid's west and south edge from the map centre. */
    bool placed = w->desc.grid_id > 0;
    for (int j = 0; j < g->n[1]; j++) {
        double y = y0 + (placed ? w->desc.map_corner_m[1] + (j + 0.5) * g->spacing[1]
                                : (j + 0.5 - 0.5 * g->n[1]) * g->spacing[1]);
        double phi = 2.0 * atan(exp(y / k)) - 0.5 * PI;
        for (int i = 0; i < g->n[0]; i++) {
            double x = placed ? w->desc.map_corner_m[0] + (i + 0.5) * g->spacing[0]
                              : (i + 0.5 - 0.5 * g->n[0]) * g->spacing[0];
            lat[(size_t)j * g->n[0] + i] = (float)(phi / DEG);
            lon[(size_t)j * g->n[0] + i] = (float)(w->desc.cen_lon + x / k / DEG);
        }
    }
    if (!put(w, V_XLAT, s, c, lat) || !put(w, V_XLONG, s, c, lon))
        return false;
    for (size_t i = 0; i < plane; i++) {
        lat[i] = (float)g->origin[2];
        lon[i] = 0.0f;
    }
    return put(w, V_HGT, s, c, lat) && put(w, V_LANDMASK, s, c, lon);
}

/* Staggered level K: the cell faces; on a stretched grid each centre half way between its two
 * faces, from the box's bottom up (wrf_write.h). */
static double face_z(const struct grid3 *g, int k)
{
    if (!grid3_stretched(g))
        return g->origin[2] + k * g->spacing[2];
    double f = g->origin[2];
    for (int i = 0; i < k; i++)
        f = 2.0 * g->z_centre[i] - f;
    return f;
}

void wrf_synth_wind(const struct grid3 *g, double x, double y, double z, double *u, double *v,
                    double *wz)
{
    double lx = g->n[0] * g->spacing[0], ly = g->n[1] * g->spacing[1];
    double top = g->origin[2] + g->n[2] * g->spacing[2];
    double ex = x - 0.5 * lx, ey = y - 0.5 * ly, r = hypot(ex, ey);
    double rmax = 0.15 * fmin(lx, ly);
    double decay = fmax(0.0, 1.0 - z / 15000.0);
    double vt = 30.0 * decay * (r < rmax ? r / rmax : rmax / r);
    *u = 5.0 - (r > 0.0 ? vt * ey / r : 0.0);
    *v = r > 0.0 ? vt * ex / r : 0.0;
    double h = top > g->origin[2] ? (z - g->origin[2]) / (top - g->origin[2]) : 0.0;
    *wz = 2.0 * exp(-(r / rmax) * (r / rmax)) * sin(PI * fmin(fmax(h, 0.0), 1.0));
}

/* U, V, W of wrf_synth_wind on their staggered points. */
static bool write_wind(struct wrf_writer *w, size_t t)
{
    const struct grid3 *g = &w->grid;
    int nx = g->n[0], ny = g->n[1];
    float *a = malloc((size_t)(nx + 1) * (size_t)(ny + 1) * sizeof(float));
    if (!a) {
        log_error("%s: out of memory", w->tmp);
        return false;
    }
    bool ok = true;
    for (int k = 0; k <= g->n[2] && ok; k++) {
        double zm = grid3_centre_z(g, k < g->n[2] ? k : g->n[2] - 1), zw = face_z(g, k);
        double u, v, wz;
        size_t s1[4] = {t, (size_t)k, 0, 0};
        if (k < g->n[2]) {
            for (int j = 0; j < ny; j++)
                for (int i = 0; i <= nx; i++) {
                    wrf_synth_wind(g, i * g->spacing[0], (j + 0.5) * g->spacing[1], zm, &u, &v,
                                   &wz);
                    a[(size_t)j * (nx + 1) + i] = (float)u;
                }
            ok = put(w, V_U, s1, (size_t[4]){1, 1, (size_t)ny, (size_t)nx + 1}, a);
            for (int j = 0; j <= ny && ok; j++)
                for (int i = 0; i < nx; i++) {
                    wrf_synth_wind(g, (i + 0.5) * g->spacing[0], j * g->spacing[1], zm, &u, &v,
                                   &wz);
                    a[(size_t)j * nx + i] = (float)v;
                }
            ok = ok && put(w, V_V, s1, (size_t[4]){1, 1, (size_t)ny + 1, (size_t)nx}, a);
        }
        for (int j = 0; j < ny && ok; j++)
            for (int i = 0; i < nx; i++) {
                wrf_synth_wind(g, (i + 0.5) * g->spacing[0], (j + 0.5) * g->spacing[1], zw, &u,
                               &v, &wz);
                a[(size_t)j * nx + i] = (float)wz;
            }
        ok = ok && put(w, V_W, s1, (size_t[4]){1, 1, (size_t)ny, (size_t)nx}, a);
    }
    free(a);
    return ok;
}

static bool write_3d(struct wrf_writer *w, const struct field_volume *v, size_t t)
{
    const struct grid3 *g = &w->grid;
    size_t plane = (size_t)g->n[0] * g->n[1];
    size_t s[4] = {t, 0, 0, 0}, c[4] = {1, (size_t)g->n[2], (size_t)g->n[1], (size_t)g->n[0]};
    for (int f = 0; f < SPECIES_COUNT; f++) {
        if (w->has[f] && !put(w, V_Q0 + f, s, c, v->q[f]))
            return false;
    }
    if (v->qvapor && !put(w, V_QVAPOR, s, c, v->qvapor))
        return false;
    float *a = w->plane, *b = w->plane + plane;
    size_t c1[4] = {1, 1, (size_t)g->n[1], (size_t)g->n[0]};
    for (int k = 0; k <= g->n[2]; k++) {
        size_t s1[4] = {t, (size_t)k, 0, 0};
        /* Staggered: cell faces. */
        double zw = face_z(g, k);
        for (size_t i = 0; i < plane; i++) {
            a[i] = 0.0f;
            b[i] = (float)(WRF_G * zw);
        }
        if (!put(w, V_PH, s1, c1, a) || !put(w, V_PHB, s1, c1, b))
            return false;
        if (k == g->n[2])
            break;
        /* Mass levels: cell centres. */
        double z = grid3_centre_z(g, k);
        double temp, p;
        wrf_std_atmosphere(z, &temp, &p);
        for (size_t i = 0; i < plane; i++) {
            a[i] = 0.0f;
            b[i] = (float)p;
        }
        if (!put(w, V_P, s1, c1, a) || !put(w, V_PB, s1, c1, b))
            return false;
        double pf = (double)(float)p; /* what the reader will see */
        double exner = pow(pf / P0, R_D / C_P);
        const float *rho = v->rho_air ? v->rho_air + plane * (size_t)k : NULL;
        for (size_t i = 0; i < plane; i++) {
            double tabs = temp;
            if (rho && rho[i] > 0.0f && isfinite(rho[i]))
                tabs = pf / (R_D * rho[i]);
            a[i] = (float)(tabs / exner - WRF_T0);
        }
        if (!put(w, V_T, s1, c1, a))
            return false;
        if (!v->qvapor) {
            for (size_t i = 0; i < plane; i++)
                a[i] = (float)(0.01 * exp(-z / 2500.0));
            if (!put(w, V_QVAPOR, s1, c1, a))
                return false;
        }
    }
    return true;
}

bool wrf_writer_add(struct wrf_writer *w, const struct field_volume *v, const char *date)
{
    if (w->failed)
        return false;
    const struct grid3 *g = &w->grid;
    for (int a = 0; a < 3; a++) {
        if (v->grid.n[a] != g->n[a]) {
            log_error("%s: step %d has a %d x %d x %d grid, the file %d x %d x %d", w->path,
                      w->steps, v->grid.n[0], v->grid.n[1], v->grid.n[2], g->n[0], g->n[1],
                      g->n[2]);
            w->failed = true;
            return false;
        }
    }
    if (w->defined) {
        for (int f = 0; f < SPECIES_COUNT; f++) {
            if ((v->q[f] != NULL) != w->has[f]) {
                log_error("%s: step %d: species %s %s, unlike the first step", w->path, w->steps,
                          species_name((enum species)f), v->q[f] ? "present" : "missing");
                w->failed = true;
                return false;
            }
        }
    }
    char padded[DATE_LEN + 1];
    memset(padded, ' ', DATE_LEN);
    padded[DATE_LEN] = '\0';
    if (date)
        memcpy(padded, date, strnlen(date, DATE_LEN));
    data_nc_lock_file(w->path, "writing", true);
    bool ok = true;
    if (!w->defined) {
        ok = define(w, v, padded);
        w->defined = true;
    }
    size_t t = (size_t)w->steps;
    if (ok) {
        size_t s[2] = {t, 0}, c[2] = {1, DATE_LEN};
        int st = nc_put_vara_text(w->ncid, w->var[V_TIMES], s, c, padded);
        if (st != NC_NOERR) {
            log_error("%s: variable Times: %s", w->tmp, nc_strerror(st));
            ok = false;
        }
    }
    ok = ok && write_2d(w, t) && write_3d(w, v, t) && write_wind(w, t);
    data_nc_unlock();
    if (ok)
        w->steps++;
    else
        w->failed = true;
    return ok;
}

bool wrf_writer_finish(struct wrf_writer *w)
{
    if (!w)
        return false;
    bool ok = data_nc_finish_beside(w->path, &w->tmp, &w->ncid, !w->failed, w->steps);
    wrf_writer_destroy(w);
    return ok;
}

void wrf_writer_destroy(struct wrf_writer *w)
{
    if (!w)
        return;
    data_nc_abandon(&w->tmp, &w->ncid);
    free(w->path);
    free(w->plane);
    free(w);
}
