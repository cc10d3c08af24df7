#include "data/hgrid.h"

#include <ctype.h>
#include <glob.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/extfile.h"
#include "data/geo.h"
#include "data/nclock.h"
#include "data/ncopen.h"
#include "data/wrf_write.h"

#define MAX_STEPS 100000
#define MAX_POINTS (1 << 20) /* per axis */

/* Dry air and the reference pressure of potential temperature, as CM1 defines them
 * (constants.incl: rd = 287.04, cp = 1005.7, p00 = 1.0e5). */
#define HG_RD 287.04
#define HG_CP 1005.7
#define HG_P00 1.0e5

static const char *labels[HGRID_VAR_COUNT] = {
    "cloud", "rain", "ice", "snow", "graupel", "vapour", "temperature", "theta",
    "pressure", "density", "u", "v", "w",
};

const char *hgrid_var_label(enum hgrid_var v)
{
    return (v >= 0 && v < HGRID_VAR_COUNT) ? labels[v] : "?";
}

struct hg_file {
    char *path;
    int ncid;
    struct data_nc_layout layout;
    int ntimes;
    struct hgrid_layout lay;
    double *time; /* ntimes seconds since the origin */
    bool dated;
    double epoch; /* the origin, seconds since 1970 (dated) */
};

struct hg_step {
    int file, index;
    double seconds; /* since the first file's origin when undated, else since 1970 */
    char date[32];
};

struct hgrid {
    struct hg_file *files;
    int file_count;
    struct hg_step *steps;
    int step_count;
    struct hgrid_meta meta;
};

/* ---- units ------------------------------------------------------------------------------ */

/* UNITS without surrounding blanks and with "**" and "^" dropped ("m s**-1" -> "m s-1"). */
static void normalise(const char *units, char *out, size_t size)
{
    size_t n = 0;
    const char *s = units ? units : "";
    while (*s && isspace((unsigned char)*s))
        s++;
    for (; *s && n + 1 < size; s++) {
        if (*s == '*' || *s == '^')
            continue;
        out[n++] = *s;
    }
    while (n > 0 && isspace((unsigned char)out[n - 1]))
        n--;
    out[n] = '\0';
}

static bool one_of(const char *u, const char *const *list)
{
    for (; *list; list++)
        if (!strcmp(u, *list))
            return true;
    return false;
}

bool hgrid_parse_length(const char *units, double *scale)
{
    char u[64];
    normalise(units, u, sizeof(u));
    static const char *const m[] = {"m", "meter", "meters", "metre", "metres", NULL};
    static const char *const km[] = {"km", "kilometer", "kilometers", "kilometre", "kilometres",
                                     NULL};
    if (one_of(u, m))
        *scale = 1.0;
    else if (one_of(u, km))
        *scale = 1000.0;
    else
        return false;
    return true;
}

bool hgrid_parse_units(enum hgrid_var v, const char *units, double *scale, double *offset)
{
    char u[64];
    normalise(units, u, sizeof(u));
    *scale = 1.0;
    *offset = 0.0;
    switch (v) {
    case HGRID_CLOUD:
    case HGRID_RAIN:
    case HGRID_ICE:
    case HGRID_SNOW:
    case HGRID_GRAUPEL:
    case HGRID_VAPOR: {
        static const char *const kg[] = {"", "1", "kg kg-1", "kg/kg", "kg kg-1 ", "kg.kg-1", NULL};
        static const char *const g[] = {"g kg-1", "g/kg", "g.kg-1", NULL};
        if (one_of(u, kg))
            return true;
        if (one_of(u, g)) {
            *scale = 1e-3;
            return true;
        }
        return false;
    }
    case HGRID_TEMPERATURE:
    case HGRID_THETA: {
        static const char *const k[] = {"K", "kelvin", "Kelvin", "degK", NULL};
        static const char *const c[] = {"degC", "degree_Celsius", "degrees_Celsius", "Celsius",
                                        "celsius", "C", "deg_C", NULL};
        if (one_of(u, k))
            return true;
        if (one_of(u, c)) {
            *offset = 273.15;
            return true;
        }
        return false;
    }
    case HGRID_PRESSURE: {
        static const char *const pa[] = {"Pa", "pascal", "Pascal", NULL};
        static const char *const hpa[] = {"hPa", "mbar", "mb", "millibar", NULL};
        if (one_of(u, pa))
            return true;
        if (one_of(u, hpa)) {
            *scale = 100.0;
            return true;
        }
        if (!strcmp(u, "kPa")) {
            *scale = 1000.0;
            return true;
        }
        return false;
    }
    case HGRID_DENSITY: {
        static const char *const d[] = {"kg m-3", "kg/m3", "kg/m^3", "kg.m-3", NULL};
        return one_of(u, d);
    }
    case HGRID_U:
    case HGRID_V:
    case HGRID_W: {
        static const char *const w[] = {"m s-1", "m/s", "m.s-1", NULL};
        return one_of(u, w);
    }
    case HGRID_VAR_COUNT:
        break;
    }
    return false;
}

/* ---- dates ------------------------------------------------------------------------------ */

void hgrid_format_date(double seconds, char out[32])
{
    long long t = (long long)llround(seconds);
    long long days = t / 86400, rem = t % 86400;
    if (rem < 0) {
        rem += 86400;
        days--;
    }
    /* civil_from_days (the inverse of extfile's days_from_civil) */
    long long z = days + 719468;
    long long era = (z >= 0 ? z : z - 146096) / 146097;
    long long doe = z - era * 146097;
    long long yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    long long y = yoe + era * 400;
    long long doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    long long mp = (5 * doy + 2) / 153;
    long long d = doy - (153 * mp + 2) / 5 + 1;
    long long m = mp + (mp < 10 ? 3 : -9);
    y += m <= 2;
    snprintf(out, 32, "%04d-%02d-%02d_%02d:%02d:%02d", (int)(y % 10000), (int)m % 100,
             (int)d % 100, (int)(rem / 3600) % 100, (int)(rem / 60 % 60), (int)(rem % 60));
}

/* "UNIT since DATE" or "UNIT": the seconds a unit is and the origin (dated). */
static bool time_units(const char *units, double *unit_s, bool *dated, double *epoch)
{
    char u[128];
    normalise(units, u, sizeof(u));
    char word[32] = "";
    int used = 0;
    if (sscanf(u, "%31s%n", word, &used) != 1)
        return false;
    static const struct {
        const char *name;
        double s;
    } unit[] = {{"s", 1}, {"sec", 1}, {"secs", 1}, {"second", 1}, {"seconds", 1},
                {"min", 60}, {"mins", 60}, {"minute", 60}, {"minutes", 60},
                {"h", 3600}, {"hr", 3600}, {"hour", 3600}, {"hours", 3600},
                {"d", 86400}, {"day", 86400}, {"days", 86400}};
    *unit_s = 0.0;
    for (size_t i = 0; i < sizeof(unit) / sizeof(unit[0]); i++)
        if (!strcmp(word, unit[i].name))
            *unit_s = unit[i].s;
    if (*unit_s == 0.0)
        return false;
    *dated = false;
    *epoch = 0.0;
    const char *rest = u + used;
    while (*rest == ' ')
        rest++;
    if (!*rest)
        return true;
    if (strncmp(rest, "since", 5) != 0)
        return false;
    rest += 5;
    while (*rest == ' ')
        rest++;
    /* "2000-01-01 00:00:00", "2000-01-01T00:00:00Z", "2000-01-01" */
    char date[32];
    int y, mo, d, h = 0, mi = 0, s = 0;
    int got = sscanf(rest, "%d-%d-%d%*[ T]%d:%d:%d", &y, &mo, &d, &h, &mi, &s);
    if (got < 3)
        return false;
    snprintf(date, sizeof(date), "%04d-%02d-%02d_%02d:%02d:%02d", y, mo, d, h, mi, s);
    if (!extfile_parse_date(date, epoch))
        return false;
    *dated = true;
    return true;
}

/* ---- opening ---------------------------------------------------------------------------- */

static bool get_text_att(int ncid, int varid, const char *name, char *buf, size_t size)
{
    size_t len;
    nc_type t;
    buf[0] = '\0';
    if (nc_inq_att(ncid, varid, name, &t, &len) != NC_NOERR || t != NC_CHAR || len >= size)
        return false;
    if (nc_get_att_text(ncid, varid, name, buf) != NC_NOERR)
        return false;
    buf[len] = '\0';
    return true;
}

bool hgrid_take_field(int ncid, const char *path, int varid, enum hgrid_var v, int stagger,
                      bool units_optional, struct hgrid_layout *l)
{
    struct hgrid_field *f = &l->field[v];
    char name[NC_MAX_NAME + 1] = "?";
    nc_inq_varname(ncid, varid, name);
    nc_type type;
    int nd, dims[NC_MAX_VAR_DIMS];
    nc_inq_var(ncid, varid, NULL, &type, &nd, dims, NULL);
    int want[3] = {l->axis_dim[2], l->axis_dim[1], l->axis_dim[0]}; /* z, y, x */
    if (stagger >= 0)
        want[2 - stagger] = l->stag_dim[stagger];
    bool shape = (nd == 3 || (nd == 4 && l->time_dim >= 0 && dims[0] == l->time_dim)) &&
                 want[0] >= 0 && want[1] >= 0 && want[2] >= 0;
    for (int i = 0; shape && i < 3; i++)
        shape = dims[nd - 3 + i] == want[i];
    if ((type != NC_FLOAT && type != NC_DOUBLE) || !shape) {
        char dn[3][NC_MAX_NAME + 1] = {"?", "?", "?"};
        for (int i = 0; i < 3; i++)
            if (want[i] >= 0)
                nc_inq_dimname(ncid, want[i], dn[i]);
        log_error("%s: variable %s (%s): expected float or double %s(time, %s, %s, %s)", path,
                  name, hgrid_var_label(v), name, dn[0], dn[1], dn[2]);
        return false;
    }
    char units[64];
    bool have_units = get_text_att(ncid, varid, "units", units, sizeof(units));
    f->scale = 1.0;
    f->offset = 0.0;
    if (have_units || !units_optional) {
        if (!have_units) {
            log_error("%s: variable %s (%s): no units attribute", path, name, hgrid_var_label(v));
            return false;
        }
        if (!hgrid_parse_units(v, units, &f->scale, &f->offset)) {
            log_error("%s: variable %s: units \"%s\" are not a unit of %s", path, name, units,
                      hgrid_var_label(v));
            return false;
        }
    }
    f->varid = varid;
    f->stagger = stagger;
    snprintf(f->name, sizeof(f->name), "%s", name);
    return true;
}

/* Reads the 1-D variable VARID of N values (doubles). */
static bool read_1d(int ncid, int varid, size_t n, double *out)
{
    int nd;
    if (nc_inq_varndims(ncid, varid, &nd) != NC_NOERR || nd != 1)
        return false;
    size_t start = 0;
    if (nc_get_vara_double(ncid, varid, &start, &n, out) != NC_NOERR)
        return false;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(out[i]) || fabs(out[i]) > 1e12)
            return false;
    return true;
}

static double *alloc_doubles(size_t n)
{
    return malloc((n ? n : 1) * sizeof(double));
}

/* Regular spacing of N values (N >= 2 strictly increasing, steps equal to 1e-4): *D; false
 * otherwise. */
static bool regular(const double *v, size_t n, double *d)
{
    if (n < 2) {
        *d = NAN;
        return true;
    }
    *d = (v[n - 1] - v[0]) / (double)(n - 1);
    if (!(*d > 0))
        return false;
    for (size_t i = 1; i < n; i++)
        if (fabs(v[i] - v[i - 1] - *d) > 1e-4 * *d)
            return false;
    return true;
}

/* The horizontal axis A of file F into the meta (first file) or checked against it. */
static bool horizontal_axis(struct hgrid *h, struct hg_file *f, int a, bool first)
{
    struct hgrid_layout *l = &f->lay;
    struct hgrid_meta *m = &h->meta;
    size_t n;
    nc_inq_dimlen(f->ncid, l->axis_dim[a], &n);
    char name[NC_MAX_NAME + 1] = "?";
    nc_inq_varname(f->ncid, l->axis_var[a], name);
    if (n < 1 || n > MAX_POINTS) {
        log_error("%s: coordinate %s: %zu points", f->path, name, n);
        return false;
    }
    double *v = alloc_doubles(n);
    if (!v) {
        log_error("%s: out of memory", f->path);
        return false;
    }
    bool ok = read_1d(f->ncid, l->axis_var[a], n, v);
    char units[64];
    get_text_att(f->ncid, l->axis_var[a], "units", units, sizeof(units));
    double scale = 1.0, d = NAN;
    bool flip = ok && n > 1 && v[n - 1] < v[0]; /* latitudes from the north, say */
    for (size_t i = 0; flip && i < n / 2; i++) {
        double t = v[i];
        v[i] = v[n - 1 - i];
        v[n - 1 - i] = t;
    }
    if (!ok) {
        log_error("%s: coordinate %s: unreadable or not finite", f->path, name);
    } else if (!l->latlon && !hgrid_parse_length(units, &scale)) {
        log_error("%s: coordinate %s: units \"%s\": expected a length (m or km)", f->path, name,
                  units);
        ok = false;
    } else if (!regular(v, n, &d)) {
        log_error("%s: coordinate %s: not evenly spaced (%g, %g, ...): expected a regular grid",
                  f->path, name, v[0], n > 1 ? v[1] : v[0]);
        ok = false;
    } else if (n < 2) {
        log_error("%s: coordinate %s: one point (at least two are needed for a spacing)",
                  f->path, name);
        ok = false;
    }
    if (!ok) {
        free(v);
        return false;
    }
    double metres;
    if (l->latlon) {
        if (a == 1 && (fabs(v[0]) > 89.0 || fabs(v[n - 1]) > 89.0)) {
            log_error("%s: latitude %s from %g to %g degrees: expected within 89 degrees of the "
                      "equator",
                      f->path, name, v[0], v[n - 1]);
            free(v);
            return false;
        }
        metres = d * M_PI / 180.0 * GEO_EARTH_RADIUS_M;
    } else {
        metres = d * scale;
    }
    if (first) {
        m->flip[a] = flip;
        if (a == 0) {
            m->nx = (int)n;
            m->x0 = v[0] * scale;
            m->lon0 = v[0];
            m->dlon = d;
            m->dx = metres;
            snprintf(m->x_units, sizeof(m->x_units), "%s", units);
        } else {
            m->ny = (int)n;
            m->y0 = v[0] * scale;
            m->lat0 = v[0];
            m->dlat = d;
            m->dy = metres;
        }
        snprintf(m->axis_names[a], sizeof(m->axis_names[a]), "%s", name);
    } else if ((a == 0 ? m->nx : m->ny) != (int)n || m->flip[a] != flip ||
               fabs((a == 0 ? m->dx : m->dy) - metres) > 1e-6 * metres) {
        log_error("%s: coordinate %s: %zu points %g m apart, but %s has %d points %g m apart",
                  f->path, name, n, metres, h->files[0].path, a == 0 ? m->nx : m->ny,
                  a == 0 ? m->dx : m->dy);
        free(v);
        return false;
    }
    free(v);
    return true;
}

/* The vertical axis of file F: heights (increasing after the sign), faces. */
static bool vertical_axis(struct hgrid *h, struct hg_file *f, bool first)
{
    struct hgrid_layout *l = &f->lay;
    struct hgrid_meta *m = &h->meta;
    size_t n;
    nc_inq_dimlen(f->ncid, l->axis_dim[2], &n);
    char name[NC_MAX_NAME + 1] = "?";
    nc_inq_varname(f->ncid, l->axis_var[2], name);
    if (n < 1 || n > MAX_POINTS) {
        log_error("%s: vertical coordinate %s: %zu levels", f->path, name, n);
        return false;
    }
    double *z = alloc_doubles(n), *faces = alloc_doubles(n + 1);
    bool ok = z && faces;
    if (!ok)
        log_error("%s: out of memory", f->path);
    char units[64];
    get_text_att(f->ncid, l->axis_var[2], "units", units, sizeof(units));
    double scale = 1.0;
    if (ok && !read_1d(f->ncid, l->axis_var[2], n, z)) {
        log_error("%s: vertical coordinate %s: unreadable or not finite", f->path, name);
        ok = false;
    }
    if (ok && !hgrid_parse_length(units, &scale)) {
        log_error("%s: vertical coordinate %s: units \"%s\": expected a height (m or km)",
                  f->path, name, units);
        ok = false;
    }
    bool reversed = false;
    if (ok) {
        for (size_t k = 0; k < n; k++)
            z[k] *= scale * l->z_sign;
        reversed = n > 1 && z[1] < z[0];
        if (reversed)
            for (size_t k = 0; k < n / 2; k++) {
                double t = z[k];
                z[k] = z[n - 1 - k];
                z[n - 1 - k] = t;
            }
        for (size_t k = 1; k < n && ok; k++)
            if (!(z[k] > z[k - 1])) {
                log_error("%s: vertical coordinate %s: heights not monotone (level %zu at %g m, "
                          "level %zu at %g m): expected them all increasing or all decreasing",
                          f->path, name, reversed ? n - k : k - 1, z[k - 1],
                          reversed ? n - 1 - k : k, z[k]);
                ok = false;
            }
    }
    /* The faces: CM1's zf, CF bounds, else half way between the levels. */
    bool have_faces = false;
    if (ok && l->face_var[2] >= 0) {
        double *zf = alloc_doubles(n + 1);
        if (zf && read_1d(f->ncid, l->face_var[2], n + 1, zf)) {
            for (size_t k = 0; k <= n; k++)
                faces[k] = zf[reversed ? n - k : k] * scale * l->z_sign;
            have_faces = true;
        }
        free(zf);
    } else if (ok && l->bounds_var[2] >= 0) {
        double *b = alloc_doubles(2 * n);
        size_t s[2] = {0, 0}, c[2] = {n, 2};
        if (b && nc_get_vara_double(f->ncid, l->bounds_var[2], s, c, b) == NC_NOERR) {
            for (size_t k = 0; k < n; k++) {
                size_t src = reversed ? n - 1 - k : k;
                double lo = fmin(b[2 * src], b[2 * src + 1]) * scale * l->z_sign;
                double hi = fmax(b[2 * src], b[2 * src + 1]) * scale * l->z_sign;
                if (l->z_sign < 0) {
                    double t = lo;
                    lo = hi;
                    hi = t;
                }
                faces[k] = lo;
                faces[k + 1] = hi;
            }
            have_faces = true;
        }
        free(b);
    }
    if (ok && have_faces) {
        for (size_t k = 0; k < n && ok; k++)
            if (!(faces[k] <= z[k] && z[k] <= faces[k + 1] && faces[k] < faces[k + 1])) {
                log_error("%s: the cell faces of %s do not enclose level %zu (%g m)", f->path,
                          name, k, z[k]);
                ok = false;
            }
    }
    if (ok && !have_faces) {
        if (n == 1) {
            log_error("%s: vertical coordinate %s: one level and no bounds: its thickness is "
                      "unknown",
                      f->path, name);
            ok = false;
        } else {
            faces[0] = z[0] - 0.5 * (z[1] - z[0]);
            faces[n] = z[n - 1] + 0.5 * (z[n - 1] - z[n - 2]);
            for (size_t k = 1; k < n; k++)
                faces[k] = 0.5 * (z[k - 1] + z[k]);
        }
    }
    if (ok && (faces[0] < DATA_HEIGHT_MIN_M || faces[n] > DATA_HEIGHT_MAX_M)) {
        log_error("%s: vertical coordinate %s: heights from %g m to %g m: expected %g m to %g km "
                  "above sea level",
                  f->path, name, faces[0], faces[n], DATA_HEIGHT_MIN_M,
                  DATA_HEIGHT_MAX_M / 1000.0);
        ok = false;
    }
    if (ok) {
        double dz = (faces[n] - faces[0]) / (double)n;
        if (dz < DATA_SPACING_MIN_M) {
            log_error("%s: vertical coordinate %s: levels %g m apart: expected at least %g m",
                      f->path, name, dz, DATA_SPACING_MIN_M);
            ok = false;
        }
    }
    if (ok && first) {
        m->nz = (int)n;
        m->z = z;
        z = NULL;
        m->bottom_m = faces[0];
        m->top_m = faces[n];
        m->reversed = reversed;
        double d = (faces[n] - faces[0]) / (double)n;
        m->stretched = false;
        for (size_t k = 0; k < n; k++)
            if (fabs(m->z[k] - (faces[0] + (k + 0.5) * d)) > 1e-4 * d)
                m->stretched = true;
        snprintf(m->axis_names[2], sizeof(m->axis_names[2]), "%s", name);
        snprintf(m->z_units, sizeof(m->z_units), "%s", units);
    } else if (ok) {
        bool same = m->nz == (int)n && m->reversed == reversed;
        for (size_t k = 0; same && k < n; k++)
            same = fabs(m->z[k] - z[k]) <= 1e-3;
        if (!same) {
            log_error("%s: vertical coordinate %s differs from %s's", f->path, name,
                      h->files[0].path);
            ok = false;
        }
    }
    free(z);
    free(faces);
    return ok;
}

static bool read_times(struct hg_file *f)
{
    struct hgrid_layout *l = &f->lay;
    size_t nt = 1;
    if (l->time_dim >= 0)
        nc_inq_dimlen(f->ncid, l->time_dim, &nt);
    if (nt == 0 || nt > MAX_STEPS) {
        log_error("%s: %zu time steps", f->path, nt);
        return false;
    }
    f->ntimes = (int)nt;
    f->time = alloc_doubles(nt);
    if (!f->time) {
        log_error("%s: out of memory", f->path);
        return false;
    }
    for (size_t t = 0; t < nt; t++)
        f->time[t] = (double)t;
    if (l->time_var < 0)
        return true;
    char units[128], name[NC_MAX_NAME + 1] = "time";
    nc_inq_varname(f->ncid, l->time_var, name);
    get_text_att(f->ncid, l->time_var, "units", units, sizeof(units));
    double unit_s;
    if (!time_units(units, &unit_s, &f->dated, &f->epoch)) {
        log_error("%s: variable %s: units \"%s\": expected seconds, minutes, hours or days "
                  "(optionally \"since YYYY-MM-DD hh:mm:ss\")",
                  f->path, name, units);
        return false;
    }
    if (!read_1d(f->ncid, l->time_var, nt, f->time)) {
        log_error("%s: variable %s: unreadable or not finite", f->path, name);
        return false;
    }
    for (size_t t = 0; t < nt; t++)
        f->time[t] *= unit_s;
    return true;
}

static bool has_glob_chars(const char *s)
{
    return strpbrk(s, "*?[") != NULL;
}

static bool add_path(struct hgrid *h, const char *path)
{
    struct hg_file *files = realloc(h->files, (size_t)(h->file_count + 1) * sizeof(*files));
    if (!files)
        return false;
    h->files = files;
    struct hg_file *f = &files[h->file_count];
    memset(f, 0, sizeof(*f));
    f->ncid = -1;
    f->path = strdup(path);
    if (!f->path)
        return false;
    h->file_count++;
    return true;
}

static int compare_steps(const void *a, const void *b)
{
    const struct hg_step *x = a, *y = b;
    if (x->seconds != y->seconds)
        return x->seconds < y->seconds ? -1 : 1;
    return x->file != y->file ? x->file - y->file : x->index - y->index;
}

static bool open_file(struct hgrid *h, int i, hgrid_identify_fn identify)
{
    struct hg_file *f = &h->files[i];
    char why[512];
    if (!data_nc_open(f->path, &f->ncid, &f->layout, why, sizeof(why))) {
        log_error("%s: %s", f->path, why);
        return false;
    }
    struct hgrid_layout *l = &f->lay;
    memset(l, 0, sizeof(*l));
    for (int v = 0; v < HGRID_VAR_COUNT; v++)
        l->field[v].varid = -1;
    for (int a = 0; a < 3; a++)
        l->axis_var[a] = l->axis_dim[a] = l->stag_dim[a] = l->face_var[a] = l->bounds_var[a] =
            -1;
    l->time_var = l->time_dim = -1;
    l->z_sign = 1.0;
    if (!identify(f->ncid, f->path, l))
        return false;
    bool first = i == 0;
    if (first)
        h->meta.latlon = l->latlon;
    else if (h->meta.latlon != l->latlon) {
        log_error("%s: horizontal coordinates in %s, but %s's are in %s", f->path,
                  l->latlon ? "degrees" : "metres", h->files[0].path,
                  h->meta.latlon ? "degrees" : "metres");
        return false;
    }
    if (!horizontal_axis(h, f, 0, first) || !horizontal_axis(h, f, 1, first) ||
        !vertical_axis(h, f, first) || !read_times(f))
        return false;
    if (l->latlon && first) {
        double lat_mid = h->meta.lat0 + 0.5 * (h->meta.ny - 1) * h->meta.dlat;
        h->meta.dx *= cos(lat_mid * M_PI / 180.0);
        h->meta.x0 = h->meta.y0 = 0.0;
    }
    double sp[2] = {h->meta.dx, h->meta.dy};
    for (int a = 0; a < 2; a++)
        if (!(sp[a] >= DATA_SPACING_MIN_M && sp[a] <= DATA_SPACING_MAX_M)) {
            log_error("%s: coordinate %s: points %g m apart: expected %g m to %g km", f->path,
                      h->meta.axis_names[a], sp[a], DATA_SPACING_MIN_M,
                      DATA_SPACING_MAX_M / 1000.0);
            return false;
        }
    for (int v = 0; v < HGRID_VAR_COUNT; v++) {
        bool has = l->field[v].varid >= 0;
        if (first) {
            h->meta.field[v] = l->field[v];
        } else if (has != (h->meta.field[v].varid >= 0)) {
            log_error("%s: %s %s, but %s %s it: every file of a series must hold the same "
                      "variables",
                      f->path, has ? "holds" : "lacks", hgrid_var_label((enum hgrid_var)v),
                      h->files[0].path, has ? "lacks" : "holds");
            return false;
        }
    }
    return true;
}

struct hgrid *hgrid_open(enum hgrid_kind kind, hgrid_identify_fn identify,
                         const char *const *paths, int count, double memory_mb)
{
    struct hgrid *h = calloc(1, sizeof(*h));
    if (!h) {
        log_error("out of memory");
        return NULL;
    }
    h->meta.kind = kind;
    for (int i = 0; i < count; i++) {
        if (has_glob_chars(paths[i])) {
            glob_t g;
            int st = glob(paths[i], 0, NULL, &g);
            if (st != 0) {
                log_error("%s: no file matches", paths[i]);
                if (st != GLOB_NOMATCH)
                    globfree(&g);
                goto error;
            }
            for (size_t j = 0; j < g.gl_pathc; j++)
                if (!add_path(h, g.gl_pathv[j])) {
                    globfree(&g);
                    goto error_oom;
                }
            globfree(&g);
        } else if (!add_path(h, paths[i])) {
            goto error_oom;
        }
    }
    if (h->file_count == 0) {
        log_error("no data files given (data.files)");
        goto error;
    }
    data_nc_lock();
    bool ok = true;
    for (int i = 0; i < h->file_count && ok; i++) {
        data_nc_lock_file(h->files[i].path, "reading", false);
        ok = open_file(h, i, identify);
        data_nc_unlock();
    }
    data_nc_unlock();
    if (!ok)
        goto error;
    /* What opening holds: the coordinates and the steps; judged before anything large. */
    double open_bytes = (double)h->meta.nz * 8.0 + 32.0 * h->file_count;
    for (int i = 0; i < h->file_count; i++)
        open_bytes += (double)h->files[i].ntimes * (sizeof(struct hg_step) + 8.0);
    if (memory_mb > 0 && open_bytes > memory_mb * 1048576.0) {
        log_error("%s: the time steps need %.0f MiB, above data.memory = %.0f MiB",
                  h->files[0].path, open_bytes / 1048576.0, memory_mb);
        goto error;
    }
    int total = 0;
    for (int i = 0; i < h->file_count; i++)
        total += h->files[i].ntimes;
    if (total > MAX_STEPS) {
        log_error("%s: %d time steps in all: at most %d", h->files[0].path, total, MAX_STEPS);
        goto error;
    }
    h->steps = calloc((size_t)total, sizeof(*h->steps));
    if (!h->steps)
        goto error_oom;
    bool dated = h->files[0].dated;
    for (int i = 0; i < h->file_count; i++) {
        struct hg_file *f = &h->files[i];
        if (f->dated != dated) {
            log_error("%s: times %s a date, but %s's %s: every file of a series must count time "
                      "the same way",
                      f->path, f->dated ? "since" : "without", h->files[0].path,
                      dated ? "have one" : "do not");
            goto error;
        }
        for (int t = 0; t < f->ntimes; t++) {
            struct hg_step *s = &h->steps[h->step_count++];
            s->file = i;
            s->index = t;
            s->seconds = f->time[t] + (dated ? f->epoch - h->files[0].epoch : 0.0);
        }
    }
    qsort(h->steps, (size_t)h->step_count, sizeof(*h->steps), compare_steps);
    for (int s = 0; s < h->step_count; s++) {
        struct hg_step *st = &h->steps[s];
        if (s > 0 && st->seconds == h->steps[s - 1].seconds &&
            (h->files[0].lay.time_var >= 0 || st->file != h->steps[s - 1].file)) {
            log_error("%s and %s both hold time %g s", h->files[h->steps[s - 1].file].path,
                      h->files[st->file].path, st->seconds);
            goto error;
        }
        if (dated)
            hgrid_format_date(st->seconds + h->files[0].epoch, st->date);
    }
    double first = h->step_count > 0 && dated ? h->steps[0].seconds : 0.0;
    for (int s = 0; s < h->step_count; s++)
        h->steps[s].seconds -= first; /* dated series count from their first step */
    return h;

error_oom:
    log_error("out of memory");
error:
    hgrid_close(h);
    return NULL;
}

void hgrid_close(struct hgrid *h)
{
    if (!h)
        return;
    data_nc_lock();
    for (int i = 0; i < h->file_count; i++) {
        if (h->files[i].ncid >= 0)
            nc_close(h->files[i].ncid);
        free(h->files[i].path);
        free(h->files[i].time);
    }
    data_nc_unlock();
    free(h->files);
    free(h->steps);
    free(h->meta.z);
    free(h);
}

const struct hgrid_meta *hgrid_get_meta(const struct hgrid *h)
{
    return &h->meta;
}

int hgrid_step_count(const struct hgrid *h)
{
    return h->step_count;
}

const char *hgrid_step_date(const struct hgrid *h, int step)
{
    return (step >= 0 && step < h->step_count) ? h->steps[step].date : "";
}

double hgrid_step_seconds(const struct hgrid *h, int step)
{
    return (step >= 0 && step < h->step_count) ? h->steps[step].seconds : 0.0;
}

const char *hgrid_step_path(const struct hgrid *h, int step)
{
    return (step >= 0 && step < h->step_count) ? h->files[h->steps[step].file].path : "";
}

bool hgrid_latlon(const struct hgrid *h, float **lat, float **lon)
{
    const struct hgrid_meta *m = &h->meta;
    *lat = *lon = NULL;
    if (!m->latlon)
        return false;
    size_t n = (size_t)m->nx * m->ny;
    *lat = malloc(n * sizeof(float));
    *lon = malloc(n * sizeof(float));
    if (!*lat || !*lon) {
        free(*lat);
        free(*lon);
        *lat = *lon = NULL;
        return false;
    }
    for (int j = 0; j < m->ny; j++)
        for (int i = 0; i < m->nx; i++) {
            (*lat)[i + (size_t)m->nx * j] = (float)(m->lat0 + j * m->dlat);
            (*lon)[i + (size_t)m->nx * j] = (float)(m->lon0 + i * m->dlon);
        }
    return true;
}

/* ---- reading ---------------------------------------------------------------------------- */

static bool has(const struct hgrid_meta *m, enum hgrid_var v)
{
    return m->field[v].varid >= 0;
}

static bool want_density(const struct hgrid_meta *m, const struct hgrid_desc *d)
{
    return !d->no_density &&
           (has(m, HGRID_DENSITY) ||
            (has(m, HGRID_PRESSURE) && (has(m, HGRID_TEMPERATURE) || has(m, HGRID_THETA))));
}

static bool want_temperature(const struct hgrid_meta *m, const struct hgrid_desc *d)
{
    return d->temperature &&
           (has(m, HGRID_TEMPERATURE) || (has(m, HGRID_THETA) && has(m, HGRID_PRESSURE)));
}

static bool want_wind(const struct hgrid_meta *m, const struct hgrid_desc *d)
{
    return d->wind && has(m, HGRID_U) && has(m, HGRID_V);
}

size_t hgrid_step_bytes(const struct hgrid *h, const struct hgrid_desc *d)
{
    const struct hgrid_meta *m = &h->meta;
    double plane = (double)m->nx * m->ny, cells = plane * m->nz;
    int outputs = 0;
    for (int f = 0; f < SPECIES_COUNT; f++)
        outputs += has(m, (enum hgrid_var)f);
    outputs += want_density(m, d) + (d->qvapor && has(m, HGRID_VAPOR)) +
               want_temperature(m, d) + want_wind(m, d);
    if (want_wind(m, d) && d->wind_components)
        outputs += 2 + has(m, HGRID_W);
    /* Scratch: the raw read (staggered: one more point each way), two mass-level arrays and a
     * third for wind, and one column each way. */
    double raw = (double)(m->nx + 1) * (m->ny + 1) * (m->nz + 1);
    double bytes = 4.0 * (outputs * cells + raw + 3.0 * cells) + 16.0 * m->nz;
    return bytes > 0x1p62 ? SIZE_MAX : (size_t)bytes;
}

struct reader {
    struct hgrid *h;
    struct hg_file *f;
    int index; /* time index in the file */
    struct hgrid_stats *stats;
    float *raw;
    double *col_z;
    float *col_v;
    bool native; /* the output grid is the file's own levels */
};

/* Reads quantity V of the step into RAW (its own, possibly staggered, shape), in SI, with bad
 * values replaced by BAD (NAN: keep them marked as NAN for the caller). */
static bool read_raw(struct reader *r, enum hgrid_var v, size_t counts[3])
{
    const struct hgrid_meta *m = &r->h->meta;
    const struct hgrid_field *fd = &r->f->lay.field[v];
    int ncid = r->f->ncid, nd, dims[NC_MAX_VAR_DIMS];
    nc_inq_varndims(ncid, fd->varid, &nd);
    nc_inq_vardimid(ncid, fd->varid, dims);
    size_t start[4] = {0}, count[4] = {0};
    int d0 = 0;
    if (nd == 4) {
        start[0] = (size_t)r->index;
        count[0] = 1;
        d0 = 1;
    }
    counts[0] = (size_t)m->nx + (fd->stagger == 0);
    counts[1] = (size_t)m->ny + (fd->stagger == 1);
    counts[2] = (size_t)m->nz + (fd->stagger == 2);
    count[d0] = counts[2];
    count[d0 + 1] = counts[1];
    count[d0 + 2] = counts[0];
    int st = nc_get_vara_float(ncid, fd->varid, start, count, r->raw);
    if (st != NC_NOERR) {
        log_error("%s: variable %s, time %d: %s", r->f->path, fd->name, r->index,
                  nc_strerror(st));
        return false;
    }
    float fill = NC_FILL_FLOAT, missing = NC_FILL_FLOAT;
    bool has_fill = nc_get_att_float(ncid, fd->varid, "_FillValue", &fill) == NC_NOERR;
    bool has_missing = nc_get_att_float(ncid, fd->varid, "missing_value", &missing) == NC_NOERR;
    struct wrf_var_stats *s = &r->stats->var[v];
    memset(s, 0, sizeof(*s));
    s->read = true;
    size_t n = counts[0] * counts[1] * counts[2];
    s->count = n;
    bool mass = v <= HGRID_VAPOR;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        float x = r->raw[i];
        if (isnan(x)) {
            s->nan++;
        } else if (isinf(x)) {
            s->inf++;
        } else if (x == NC_FILL_FLOAT || (has_fill && x == fill) ||
                   (has_missing && x == missing)) {
            s->fill++;
        } else {
            double y = x * fd->scale + fd->offset;
            if (mass && y < 0.0)
                s->negative++;
            else if (mass && y > 1.0)
                s->absurd++;
            else {
                r->raw[i] = (float)y;
                lo = fmin(lo, y);
                hi = fmax(hi, y);
                continue;
            }
        }
        r->raw[i] = NAN; /* bad: the caller replaces it */
    }
    s->min = isfinite(lo) ? lo : 0.0;
    s->max = isfinite(hi) ? hi : 0.0;
    size_t bad = wrf_var_stats_bad(s);
    if (bad == n && n > 0) {
        log_error("%s: variable %s, time %d: all %zu values are NaN, Inf or fill: the file is "
                  "broken, not the sky clear",
                  r->f->path, fd->name, r->index, n);
        return false;
    }
    if (bad)
        log_warn("%s: variable %s, time %d: %zu NaN, %zu Inf, %zu fill, %zu negative, %zu "
                 "above 1 replaced",
                 r->f->path, fd->name, r->index, s->nan, s->inf, s->fill, s->negative,
                 s->absurd);
    return true;
}

/* RAW (mass-point shape, or staggered along STAGGER) onto the mass points, in increasing
 * height order, into ML (nx ny nz): staggered values are averaged over the two points around
 * each mass point; a bad value (NAN) counts as BAD. */
static void to_mass_levels(const struct hgrid_meta *m, const float *raw, int stagger, float bad,
                           float *ml)
{
    size_t nx = (size_t)m->nx, ny = (size_t)m->ny, nz = (size_t)m->nz;
    size_t rx = nx + (stagger == 0), ry = ny + (stagger == 1);
    for (size_t k = 0; k < nz; k++) {
        size_t kk = m->reversed ? nz - 1 - k : k;
        for (size_t j = 0; j < ny; j++)
            for (size_t i = 0; i < nx; i++) {
                size_t ii = m->flip[0] ? nx - 1 - i : i, jj = m->flip[1] ? ny - 1 - j : j;
                size_t a = ii + rx * (jj + ry * kk), b = a;
                if (stagger == 0)
                    b = a + 1; /* faces ii and ii + 1 in the file's order */
                else if (stagger == 1)
                    b = a + rx;
                else if (stagger == 2)
                    b = a + rx * ry;
                float x = raw[a], y = raw[b];
                x = isnan(x) ? bad : x;
                y = isnan(y) ? bad : y;
                ml[i + nx * (j + ny * k)] = stagger < 0 ? x : 0.5f * (x + y);
            }
    }
}

/* Each column of ML (mass levels) onto the output grid OUT (nz even levels); on the file's
 * own levels a copy (the values as the file holds them). */
static void resample(struct reader *r, const float *ml, float *out)
{
    const struct hgrid_meta *m = &r->h->meta;
    size_t plane = (size_t)m->nx * m->ny;
    if (r->native) {
        memcpy(out, ml, plane * (size_t)m->nz * sizeof(float));
        return;
    }
    double dz = (m->top_m - m->bottom_m) / m->nz;
    for (int k = 0; k < m->nz; k++)
        r->col_z[k] = m->z[k];
    for (size_t c = 0; c < plane; c++) {
        for (int k = 0; k < m->nz; k++)
            r->col_v[k] = ml[c + plane * (size_t)k];
        float *o = r->col_v + m->nz;
        wrf_resample_column(r->col_z, r->col_v, m->nz, m->bottom_m, m->top_m, m->bottom_m, dz,
                            m->nz, 0.0f, o, NULL);
        for (int k = 0; k < m->nz; k++)
            out[c + plane * (size_t)k] = o[k];
    }
}

bool hgrid_native(const struct hgrid *h, bool native_levels)
{
    const struct hgrid_meta *m = &h->meta;
    /* A stretched grid's centres lie strictly inside its box: a level on the lowest or
     * highest face (CF bounds may say so) takes the even levels. */
    return native_levels && m->stretched && m->nz <= GRID3_LEVELS_MAX &&
           m->z[0] > m->bottom_m && m->z[m->nz - 1] < m->top_m;
}

void hgrid_grid(const struct hgrid *h, bool native_levels, struct grid3 *out)
{
    const struct hgrid_meta *m = &h->meta;
    memset(out, 0, sizeof(*out));
    out->n[0] = m->nx;
    out->n[1] = m->ny;
    out->n[2] = m->nz;
    out->spacing[0] = m->dx;
    out->spacing[1] = m->dy;
    out->spacing[2] = (m->top_m - m->bottom_m) / m->nz;
    out->origin[2] = m->bottom_m;
    /* The faces enclose the levels (checked at open) and hgrid_native keeps them off the
     * box's faces, so the levels fit. */
    if (hgrid_native(h, native_levels))
        grid3_set_levels(out, m->z, m->nz, m->bottom_m, m->top_m);
}

bool hgrid_read_step(struct hgrid *h, int step, const struct hgrid_desc *d,
                     struct field_volume *out, struct hgrid_stats *stats)
{
    memset(out, 0, sizeof(*out));
    struct hgrid_stats local;
    if (!stats)
        stats = &local;
    memset(stats, 0, sizeof(*stats));
    const struct hgrid_meta *m = &h->meta;
    if (step < 0 || step >= h->step_count) {
        log_error("%s: time step %d out of range (0 to %d)", h->files[0].path, step,
                  h->step_count - 1);
        return false;
    }
    size_t bytes = hgrid_step_bytes(h, d);
    if (d->memory_mb > 0 && (double)bytes > d->memory_mb * 1048576.0) {
        log_error("%s: one time step of %d x %d x %d points needs %.3g MiB, above the budget "
                  "data.memory = %.3g MiB: use a smaller grid or raise data.memory",
                  h->files[0].path, m->nx, m->ny, m->nz, (double)bytes / 1048576.0,
                  d->memory_mb);
        return false;
    }
    struct reader r = {.h = h, .f = &h->files[h->steps[step].file],
                       .index = h->steps[step].index, .stats = stats};
    if (!data_nc_still_whole(r.f->path, &r.f->layout))
        return false;
    hgrid_grid(h, d->native_levels, &out->grid);
    r.native = grid3_stretched(&out->grid);
    size_t cells = grid3_count(&out->grid);
    size_t raw_n = (size_t)(m->nx + 1) * (m->ny + 1) * (m->nz + 1);
    r.raw = malloc(raw_n * sizeof(float));
    r.col_z = malloc((size_t)m->nz * sizeof(double));
    r.col_v = malloc(2 * (size_t)m->nz * sizeof(float));
    float *ml[3] = {malloc(cells * sizeof(float)), malloc(cells * sizeof(float)), NULL};
    bool ok = r.raw && r.col_z && r.col_v && ml[0] && ml[1];
    if (!ok)
        log_error("%s: out of memory for a step of %zu points", r.f->path, cells);
    size_t counts[3];
    data_nc_lock_file(r.f->path, "reading", false);
    /* The species and vapour. */
    for (int v = 0; v <= HGRID_VAPOR && ok; v++) {
        if (!has(m, (enum hgrid_var)v) || (v == HGRID_VAPOR && !d->qvapor))
            continue;
        float **dst = v == HGRID_VAPOR ? &out->qvapor : &out->q[v];
        *dst = malloc(cells * sizeof(float));
        ok = *dst && read_raw(&r, (enum hgrid_var)v, counts);
        if (ok) {
            to_mass_levels(m, r.raw, r.f->lay.field[v].stagger, 0.0f, ml[0]);
            resample(&r, ml[0], *dst);
        }
    }
    /* Temperature (ml[0]) and pressure (ml[1]) on the mass levels; bad values become the
     * standard atmosphere at the level. */
    bool t_on = ok && (want_temperature(m, d) || want_density(m, d) || d->pressure);
    bool have_t = false, have_p = false;
    if (t_on && has(m, HGRID_PRESSURE)) {
        ok = read_raw(&r, HGRID_PRESSURE, counts);
        if (ok) {
            to_mass_levels(m, r.raw, r.f->lay.field[HGRID_PRESSURE].stagger, NAN, ml[1]);
            size_t plane = (size_t)m->nx * m->ny;
            for (size_t i = 0; i < cells; i++)
                if (isnan(ml[1][i])) {
                    double tt, pp;
                    wrf_std_atmosphere(m->z[i / plane], &tt, &pp);
                    ml[1][i] = (float)pp;
                }
            have_p = true;
        }
    }
    if (ok && t_on && (has(m, HGRID_TEMPERATURE) || (has(m, HGRID_THETA) && have_p))) {
        enum hgrid_var tv = has(m, HGRID_TEMPERATURE) ? HGRID_TEMPERATURE : HGRID_THETA;
        ok = read_raw(&r, tv, counts);
        if (ok) {
            to_mass_levels(m, r.raw, r.f->lay.field[tv].stagger, NAN, ml[0]);
            size_t plane = (size_t)m->nx * m->ny;
            for (size_t i = 0; i < cells; i++) {
                double tt, pp;
                if (isnan(ml[0][i])) {
                    wrf_std_atmosphere(m->z[i / plane], &tt, &pp);
                    ml[0][i] = (float)tt;
                } else if (tv == HGRID_THETA) {
                    /* Poisson's equation, T = theta (p / p00)^(Rd / cp) (AMS Glossary of
                     * Meteorology, "potential temperature") */
                    ml[0][i] = (float)(ml[0][i] * pow(ml[1][i] / HG_P00, HG_RD / HG_CP));
                }
            }
            have_t = true;
        }
    }
    if (ok && want_density(m, d)) {
        out->rho_air = malloc(cells * sizeof(float));
        ok = out->rho_air != NULL;
        if (ok && has(m, HGRID_DENSITY)) {
            float *keep = ml[2] = malloc(cells * sizeof(float));
            ok = keep && read_raw(&r, HGRID_DENSITY, counts);
            if (ok) {
                to_mass_levels(m, r.raw, r.f->lay.field[HGRID_DENSITY].stagger, NAN, keep);
                size_t plane = (size_t)m->nx * m->ny;
                for (size_t i = 0; i < cells; i++)
                    if (isnan(keep[i]) || keep[i] <= 0.0f) {
                        double tt, pp;
                        wrf_std_atmosphere(m->z[i / plane], &tt, &pp);
                        keep[i] = (float)(pp / (HG_RD * tt));
                    }
                resample(&r, keep, out->rho_air);
            }
        } else if (ok && have_t && have_p) {
            float *rho = ml[2] = malloc(cells * sizeof(float));
            ok = rho != NULL;
            for (size_t i = 0; ok && i < cells; i++)
                rho[i] = (float)(ml[1][i] / (HG_RD * ml[0][i])); /* ideal gas, dry air */
            if (ok)
                resample(&r, rho, out->rho_air);
        }
    }
    if (ok && d->pressure && have_p) {
        out->pressure = malloc(cells * sizeof(float));
        ok = out->pressure != NULL;
        if (ok)
            resample(&r, ml[1], out->pressure);
    }
    if (ok && want_temperature(m, d) && have_t) {
        out->temperature = malloc(cells * sizeof(float));
        ok = out->temperature != NULL;
        if (ok)
            resample(&r, ml[0], out->temperature);
    }
    if (ok && want_wind(m, d)) {
        /* |(u, v, w)| on the mass levels: u in ml[0], v^2 summed in, w added. */
        if (!ml[2])
            ml[2] = malloc(cells * sizeof(float));
        out->wind = malloc(cells * sizeof(float));
        ok = ml[2] && out->wind;
        static const enum hgrid_var comp[3] = {HGRID_U, HGRID_V, HGRID_W};
        float **keep[3] = {&out->u, &out->v, &out->w};
        for (int c = 0; c < 3 && ok; c++) {
            if (!has(m, comp[c]))
                continue;
            ok = read_raw(&r, comp[c], counts);
            if (ok && d->wind_components)
                ok = (*keep[c] = malloc(cells * sizeof(float))) != NULL;
            if (!ok)
                break;
            to_mass_levels(m, r.raw, r.f->lay.field[comp[c]].stagger, 0.0f, ml[0]);
            if (*keep[c])
                resample(&r, ml[0], *keep[c]);
            for (size_t i = 0; i < cells; i++)
                ml[2][i] = (c ? ml[2][i] : 0.0f) + ml[0][i] * ml[0][i];
        }
        if (ok) {
            for (size_t i = 0; i < cells; i++)
                ml[2][i] = sqrtf(ml[2][i]);
            resample(&r, ml[2], out->wind);
        }
    } else if (ok && d->wind && !want_wind(m, d)) {
        log_warn("%s: no eastward and northward wind: wind speed unavailable", r.f->path);
    }
    data_nc_unlock();
    free(r.raw);
    free(r.col_z);
    free(r.col_v);
    for (int i = 0; i < 3; i++)
        free(ml[i]);
    if (!ok) {
        field_volume_finish(out);
        return false;
    }
    return true;
}
