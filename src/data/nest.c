#include "data/nest.h"

#include <glob.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "common/parallel.h"
#include "data/geo.h"
#include "data/nclock.h"
#include "data/ncopen.h"

#define NEST_SIDE_MAX (1 << 20) /* composite columns a side */
#define NEST_SCALE_MAX 1000     /* the outermost's columns per composite column */

/* What a file says of its domain (the first file of each domain is asked). */
struct domain_attrs {
    int grid_id;
    int parent_id; /* 0 when absent */
    int start[2];  /* I_PARENT_START, J_PARENT_START; 0 when absent */
    int ratio;     /* PARENT_GRID_RATIO; 0 when absent */
    double dx, dy; /* DX, DY */
};

struct nest_set {
    int count;
    struct nest_domain dom[NEST_DOMAIN_MAX]; /* layout order: coarsest first */
    int offset[NEST_DOMAIN_MAX][2];          /* composite columns */
    int scale[NEST_DOMAIN_MAX];
    int blend[NEST_DOMAIN_MAX];
    int parent[NEST_DOMAIN_MAX]; /* index of the domain it is placed in, -1 for [0] */
    char **paths;                /* every file, owned; the domains' path point here */
    int path_count;
};

static bool int_att(int nc, const char *name, int *out)
{
    int v;
    if (nc_get_att_int(nc, NC_GLOBAL, name, &v) != NC_NOERR)
        return false;
    *out = v;
    return true;
}

/* `_dNN_` (or `_dNN` at the end) in the file's name: WRF's own naming of its domains. */
static int name_domain(const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    for (const char *p = strstr(base, "_d"); p; p = strstr(p + 1, "_d")) {
        if (p[2] >= '0' && p[2] <= '9' && p[3] >= '0' && p[3] <= '9' &&
            (p[4] == '_' || p[4] == '.' || p[4] == '\0'))
            return (p[2] - '0') * 10 + (p[3] - '0');
    }
    return 0;
}

/* False (WHY says why) when the file cannot be opened: the WRF reader then reports it. */
static bool read_attrs(const char *path, struct domain_attrs *a)
{
    memset(a, 0, sizeof(*a));
    char why[512];
    int nc;
    data_nc_lock_file(path, "reading", false);
    bool ok = data_nc_open(path, &nc, NULL, why, sizeof(why));
    if (ok) {
        if (!int_att(nc, "GRID_ID", &a->grid_id) || a->grid_id < 1)
            a->grid_id = 0;
        if (!int_att(nc, "PARENT_ID", &a->parent_id) || a->parent_id < 0)
            a->parent_id = 0;
        if (!int_att(nc, "I_PARENT_START", &a->start[0]) || a->start[0] < 1)
            a->start[0] = 0;
        if (!int_att(nc, "J_PARENT_START", &a->start[1]) || a->start[1] < 1)
            a->start[1] = 0;
        if (!int_att(nc, "PARENT_GRID_RATIO", &a->ratio) || a->ratio < 1)
            a->ratio = 0;
        double v;
        a->dx = nc_get_att_double(nc, NC_GLOBAL, "DX", &v) == NC_NOERR ? v : NAN;
        a->dy = nc_get_att_double(nc, NC_GLOBAL, "DY", &v) == NC_NOERR ? v : NAN;
        nc_close(nc);
    }
    data_nc_unlock();
    if (ok && a->grid_id == 0)
        a->grid_id = name_domain(path);
    if (ok && a->grid_id == 0)
        a->grid_id = 1;
    return ok;
}

static void free_paths(char **p, int n)
{
    for (int i = 0; i < n; i++)
        free(p[i]);
    free(p);
}

/* The files PATHS name, patterns expanded in sorted order; a pattern that matches nothing is
 * kept as it is (the WRF reader names it). */
static char **expand(const char *const *paths, int count, int *n)
{
    char **out = NULL;
    int len = 0, cap = 0;
    for (int i = 0; i < count; i++) {
        glob_t g;
        memset(&g, 0, sizeof(g));
        bool globbed = strpbrk(paths[i], "*?[") && glob(paths[i], 0, NULL, &g) == 0;
        size_t m = globbed ? g.gl_pathc : 1;
        for (size_t k = 0; k < m; k++) {
            if (len == cap) {
                cap = cap ? 2 * cap : 16;
                char **grown = realloc(out, (size_t)cap * sizeof(*out));
                if (!grown)
                    goto oom;
                out = grown;
            }
            out[len] = strdup(globbed ? g.gl_pathv[k] : paths[i]);
            if (!out[len])
                goto oom;
            len++;
        }
        if (globbed)
            globfree(&g);
        continue;
    oom:
        if (globbed)
            globfree(&g);
        free_paths(out, len);
        log_error("out of memory listing WRF files");
        return NULL;
    }
    *n = len;
    return out;
}

/* Whether A is within a thousandth of B. */
static bool near(double a, double b)
{
    return fabs(a - b) <= 1e-3 * fabs(b);
}

/* Where domain I's south-west corner lies in the outermost domain's frame, m, from its first
 * column's latitude and longitude on the outermost domain's map (both XLAT/XLONG grids: exact
 * at the columns, bilinear between them).  False when either lacks them or the point cannot
 * be placed. */
static bool latlon_corner(const struct nest_set *s, int i, double out[2])
{
    const struct wrf_meta *outer = wrf_get_meta(s->dom[0].wrf);
    const struct wrf_meta *m = wrf_get_meta(s->dom[i].wrf);
    if (!m->xlat || !m->xlong || !outer->xlat || !outer->xlong)
        return false;
    struct geo_map map;
    if (!geo_map_init_grid(&map, outer->xlat, outer->xlong, outer->nx, outer->ny, outer->dx,
                           outer->dy))
        return false;
    double x, y;
    bool ok = geo_map_to_frame(&map, m->xlat[0], m->xlong[0], &x, &y);
    geo_map_finish(&map);
    /* The column's centre is half a column in from the domain's corner. */
    out[0] = x - 0.5 * m->dx;
    out[1] = y - 0.5 * m->dy;
    return ok;
}

/* Places domain I by its latitude and longitude. */
static bool place_latlon(struct nest_set *s, int i, double fine_dx, double fine_dy)
{
    const struct wrf_meta *outer = wrf_get_meta(s->dom[0].wrf);
    const struct wrf_meta *m = wrf_get_meta(s->dom[i].wrf);
    if (!m->xlat || !m->xlong || !outer->xlat || !outer->xlong) {
        bool own = m->xlat && m->xlong;
        log_error("%s: domain %d has no PARENT_ID, I_PARENT_START, J_PARENT_START and "
                  "PARENT_GRID_RATIO naming a domain given, and %s%s no XLAT/XLONG: it cannot "
                  "be placed in %s",
                  s->dom[i].path, s->dom[i].grid_id, own ? s->dom[0].path : "",
                  own ? " has" : "has", s->dom[0].path);
        return false;
    }
    double c[2];
    if (!latlon_corner(s, i, c)) {
        log_error("%s: its first column (%.4f N, %.4f E) lies far outside %s: expected a nest "
                  "inside the outermost domain",
                  s->dom[i].path, m->xlat[0], m->xlong[0], s->dom[0].path);
        return false;
    }
    double cx = c[0] / fine_dx, cy = c[1] / fine_dy;
    if (!(fabs(cx) < NEST_SIDE_MAX && fabs(cy) < NEST_SIDE_MAX)) {
        log_error("%s: its first column (%.4f N, %.4f E) lies far outside %s: expected a nest "
                  "inside the outermost domain",
                  s->dom[i].path, m->xlat[0], m->xlong[0], s->dom[0].path);
        return false;
    }
    s->offset[i][0] = (int)lround(cx);
    s->offset[i][1] = (int)lround(cy);
    s->dom[i].by_latlon = true;
    s->dom[i].misfit_m = hypot((cx - s->offset[i][0]) * fine_dx, (cy - s->offset[i][1]) * fine_dy);
    return true;
}

static bool inside(const struct nest_set *s, int i, int p)
{
    const struct wrf_meta *m = wrf_get_meta(s->dom[i].wrf);
    const struct wrf_meta *pm = wrf_get_meta(s->dom[p].wrf);
    int cells[2] = {m->nx, m->ny}, pcells[2] = {pm->nx, pm->ny};
    for (int a = 0; a < 2; a++) {
        if (s->offset[i][a] < s->offset[p][a] ||
            s->offset[i][a] + cells[a] * s->scale[i] > s->offset[p][a] + pcells[a] * s->scale[p])
            return false;
    }
    return true;
}

/* Puts the domains in layout order and finds where each lies. */
static bool place(struct nest_set *s, const struct domain_attrs *attrs)
{
    /* The outermost is the coarsest (ties: the lowest GRID_ID); the rest follow coarsest
     * first, so that a nest comes after the domain it sits in. */
    int order[NEST_DOMAIN_MAX];
    for (int i = 0; i < s->count; i++)
        order[i] = i;
    for (int i = 1; i < s->count; i++)
        for (int j = i; j > 0; j--) {
            const struct domain_attrs *a = &attrs[order[j]], *b = &attrs[order[j - 1]];
            if (a->dx > b->dx * (1 + 1e-6) || (near(a->dx, b->dx) && a->grid_id < b->grid_id)) {
                int t = order[j];
                order[j] = order[j - 1];
                order[j - 1] = t;
            }
        }
    struct nest_domain dom[NEST_DOMAIN_MAX];
    struct domain_attrs at[NEST_DOMAIN_MAX];
    for (int i = 0; i < s->count; i++) {
        dom[i] = s->dom[order[i]];
        at[i] = attrs[order[i]];
    }
    memcpy(s->dom, dom, sizeof(dom));

    const struct wrf_meta *outer = wrf_get_meta(s->dom[0].wrf);
    const struct wrf_meta *finest = wrf_get_meta(s->dom[s->count - 1].wrf);
    for (int i = 0; i < s->count; i++)
        if (wrf_moves(s->dom[i].wrf))
            log_warn("%s: domain %d moves (a moving nest): the composite of the domains keeps "
                     "it, and its map, where its first step has it, at every step",
                     s->dom[i].path, s->dom[i].grid_id);
    /* The domains of one run share its map projection (WRF writes the mother domain's into
     * every domain's files): two projections are two runs, whatever their grids say. */
    for (int i = 1; i < s->count; i++) {
        const struct wrf_meta *m = wrf_get_meta(s->dom[i].wrf);
        const double a[3] = {outer->truelat1, outer->truelat2, outer->stand_lon};
        const double b[3] = {m->truelat1, m->truelat2, m->stand_lon};
        bool same = m->map_proj == outer->map_proj;
        for (int k = 0; k < 3 && same; k++)
            same = !(isfinite(a[k]) && isfinite(b[k])) || fabs(a[k] - b[k]) <= 1e-3;
        if (!same) {
            log_error("%s and %s are not domains of one run: their map projections differ "
                      "(MAP_PROJ %d against %d, TRUELAT1 %g against %g, TRUELAT2 %g against "
                      "%g, STAND_LON %g against %g)",
                      s->dom[0].path, s->dom[i].path, outer->map_proj, m->map_proj, a[0], b[0],
                      a[1], b[1], a[2], b[2]);
            return false;
        }
    }
    for (int i = 0; i < s->count; i++) {
        const struct wrf_meta *m = wrf_get_meta(s->dom[i].wrf);
        double r = m->dx / finest->dx;
        s->scale[i] = (int)lround(r);
        if (s->scale[i] < 1 || !near(m->dx, s->scale[i] * finest->dx) ||
            !near(m->dy, s->scale[i] * finest->dy)) {
            log_error("%s: domain %d's spacing DX %g m, DY %g m is not a whole multiple of the "
                      "finest domain's %g m, %g m (%s): expected nests whose ratios divide",
                      s->dom[i].path, s->dom[i].grid_id, m->dx, m->dy, finest->dx, finest->dy,
                      s->dom[s->count - 1].path);
            return false;
        }
    }
    /* What an int indexes, with room: a composite side of at most 2^20 columns. */
    if (s->scale[0] > NEST_SCALE_MAX || (double)outer->nx * s->scale[0] > NEST_SIDE_MAX ||
        (double)outer->ny * s->scale[0] > NEST_SIDE_MAX) {
        log_error("%s: %d x %d columns of %g m at the finest domain's spacing of %g m (%s) "
                  "are more than anvil composes (%d a side, ratios up to %d)",
                  s->dom[0].path, outer->nx, outer->ny, outer->dx, finest->dx,
                  s->dom[s->count - 1].path, NEST_SIDE_MAX, NEST_SCALE_MAX);
        return false;
    }
    /* The composite's spacing is the outermost's divided exactly. */
    double fine_dx = outer->dx / s->scale[0], fine_dy = outer->dy / s->scale[0];
    s->offset[0][0] = s->offset[0][1] = 0;
    s->parent[0] = -1;
    s->blend[0] = 0;
    s->dom[0].parent_id = 0;
    s->dom[0].ratio = 1;
    for (int i = 1; i < s->count; i++) {
        struct nest_domain *d = &s->dom[i];
        const struct domain_attrs *a = &at[i];
        int p = -1;
        for (int j = 0; j < i; j++)
            if (s->dom[j].grid_id == a->parent_id && a->parent_id != d->grid_id)
                p = j;
        bool attributes = p >= 0 && a->start[0] >= 1 && a->start[1] >= 1 && a->ratio >= 1;
        if (!attributes && a->parent_id > 0 && a->parent_id != d->grid_id && p < 0) {
            /* Its parent is finer than it, or not given. */
            for (int j = i + 1; j < s->count; j++)
                if (s->dom[j].grid_id == a->parent_id) {
                    log_error("%s: domain %d's parent (PARENT_ID %d, %s) is finer than it "
                              "(DX %g m against %g m): inconsistent spacing",
                              d->path, d->grid_id, a->parent_id, s->dom[j].path,
                              wrf_get_meta(s->dom[j].wrf)->dx, wrf_get_meta(d->wrf)->dx);
                    return false;
                }
        }
        if (attributes) {
            double pdx = wrf_get_meta(s->dom[p].wrf)->dx, dx = wrf_get_meta(d->wrf)->dx;
            if (a->ratio > NEST_SCALE_MAX || !near(pdx, a->ratio * dx) ||
                s->scale[p] != a->ratio * s->scale[i]) {
                log_error("%s: PARENT_GRID_RATIO %d, but DX %g m against its parent's %g m "
                          "(%s) is a ratio of %g: inconsistent",
                          d->path, a->ratio, dx, pdx, s->dom[p].path, pdx / dx);
                return false;
            }
            const struct wrf_meta *pm = wrf_get_meta(s->dom[p].wrf);
            int pcells[2] = {pm->nx, pm->ny};
            for (int ax = 0; ax < 2; ax++) /* a start beyond the parent fails below */
                s->offset[i][ax] =
                    s->offset[p][ax] +
                    ((a->start[ax] <= pcells[ax] ? a->start[ax] : pcells[ax] + 1) - 1) *
                        s->scale[p];
            d->parent_id = a->parent_id;
            d->ratio = a->ratio;
            d->start[0] = a->start[0];
            d->start[1] = a->start[1];
            /* Where its latitude and longitude put it: the same place for a nest of this run,
             * elsewhere for files of two runs. */
            double c[2];
            d->misfit_m = NAN;
            if (latlon_corner(s, i, c)) {
                d->misfit_m =
                    hypot(c[0] - s->offset[i][0] * fine_dx, c[1] - s->offset[i][1] * fine_dy);
                if (d->misfit_m > 0.5 * pdx)
                    log_warn("%s: its PARENT attributes put it at column %d, %d of %s, but its "
                             "XLAT/XLONG %.1f km from there: a nest of another run? (placed "
                             "by the attributes)",
                             d->path, a->start[0], a->start[1], s->dom[p].path,
                             d->misfit_m / 1000.0);
            }
        } else {
            if (!place_latlon(s, i, fine_dx, fine_dy))
                return false;
            /* It sits in the finest domain before it that holds it (at least the outermost). */
            p = 0;
            for (int j = 1; j < i; j++)
                if (inside(s, i, j) && s->scale[j] < s->scale[p])
                    p = j;
            d->parent_id = 0;
            d->ratio = s->scale[p] / s->scale[i];
            for (int ax = 0; ax < 2; ax++)
                d->start[ax] =
                    1 + (int)floor((double)(s->offset[i][ax] - s->offset[p][ax]) / s->scale[p]);
        }
        s->parent[i] = p;
        s->blend[i] = s->scale[p];
        const struct wrf_meta *m = wrf_get_meta(d->wrf), *pm = wrf_get_meta(s->dom[p].wrf);
        if (!inside(s, i, p) || !inside(s, i, 0)) {
            log_error("%s: domain %d (%d x %d columns of %g m) starts at column %d, %d of %s "
                      "(%d x %d columns of %g m) and does not fit inside it: expected a nest "
                      "inside its parent",
                      d->path, d->grid_id, m->nx, m->ny, m->dx, d->start[0], d->start[1],
                      s->dom[p].path, pm->nx, pm->ny, pm->dx);
            return false;
        }
    }
    return true;
}

struct nest_set *nest_open(const char *const *paths, int count, double memory_mb, bool *single)
{
    *single = true;
    int n = 0;
    char **list = expand(paths, count, &n);
    if (!list) {
        *single = false;
        return NULL;
    }
    /* A series whose names all say one domain (WRF's wrfout_d01_...) is one without opening
     * its files twice. */
    int named = name_domain(list[0]);
    for (int i = 1; i < n && named; i++)
        if (name_domain(list[i]) != named)
            named = 0;
    if (named) {
        free_paths(list, n);
        return NULL;
    }
    /* Each file's domain; a file that cannot be read is left to the WRF reader. */
    int *id = calloc((size_t)(n ? n : 1), sizeof(*id));
    struct domain_attrs attrs[NEST_DOMAIN_MAX];
    int ids[NEST_DOMAIN_MAX], first[NEST_DOMAIN_MAX], domains = 0;
    if (!id) {
        free_paths(list, n);
        *single = false;
        log_error("out of memory listing WRF files");
        return NULL;
    }
    for (int i = 0; i < n; i++) {
        struct domain_attrs a;
        if (!read_attrs(list[i], &a))
            continue;
        id[i] = a.grid_id;
        int k = 0;
        while (k < domains && ids[k] != a.grid_id)
            k++;
        if (k == domains) {
            if (domains == NEST_DOMAIN_MAX) {
                log_error("%s: domain %d: more than %d domains in one scene", list[i], a.grid_id,
                          NEST_DOMAIN_MAX);
                free(id);
                free_paths(list, n);
                *single = false;
                return NULL;
            }
            ids[domains] = a.grid_id;
            first[domains] = i;
            attrs[domains++] = a;
        }
    }
    if (domains <= 1) {
        free(id);
        free_paths(list, n);
        return NULL;
    }
    *single = false;
    struct nest_set *s = calloc(1, sizeof(*s));
    const char **group = calloc((size_t)n, sizeof(*group));
    if (!s || !group) {
        free(s);
        free(group);
        free(id);
        free_paths(list, n);
        log_error("out of memory opening WRF domains");
        return NULL;
    }
    s->paths = list;
    s->path_count = n;
    s->count = domains;
    for (int k = 0; k < domains; k++) {
        int m = 0;
        for (int i = 0; i < n; i++)
            if (id[i] == ids[k] || (id[i] == 0 && k == 0)) /* unreadable: named by the first */
                group[m++] = list[i];
        s->dom[k].path = list[first[k]];
        s->dom[k].grid_id = ids[k];
        s->dom[k].wrf = wrf_open(group, m, memory_mb);
        if (!s->dom[k].wrf) {
            free(group);
            free(id);
            nest_close(s);
            return NULL;
        }
    }
    free(group);
    free(id);
    if (!place(s, attrs)) {
        nest_close(s);
        return NULL;
    }
    for (int i = 1; i < s->count; i++)
        if (s->dom[i].by_latlon && s->dom[i].misfit_m > 0.25 * wrf_get_meta(s->dom[i].wrf)->dx)
            log_warn("%s: placed from its latitude and longitude %.0f m from where its columns "
                     "fall on the composite grid",
                     s->dom[i].path, s->dom[i].misfit_m);
    return s;
}

void nest_close(struct nest_set *s)
{
    if (!s)
        return;
    for (int i = 0; i < s->count; i++)
        wrf_close(s->dom[i].wrf);
    free_paths(s->paths, s->path_count);
    free(s);
}

int nest_domain_count(const struct nest_set *s)
{
    return s->count;
}

const struct nest_domain *nest_domain(const struct nest_set *s, int i)
{
    return &s->dom[i];
}

struct wrf *nest_outer(struct nest_set *s)
{
    return s->dom[0].wrf;
}

bool nest_layout(const struct nest_set *s, const struct wrf_desc *d, struct nest_layout *out)
{
    memset(out, 0, sizeof(*out));
    for (int a = 0; a < 3; a++)
        if (d->stride[a] > 1) {
            log_error("%s and its nests: data.stride would undo the nests' resolution: not with "
                      "nests (data.crop selects a part of the composite)",
                      s->dom[0].path);
            return false;
        }
    /* The outermost's heights before a crop along z: every domain is read on them. */
    struct wrf_desc full = *d;
    for (int i = 0; i < 6; i++)
        full.crop[i] = -1;
    struct grid3 g;
    if (!wrf_grid(s->dom[0].wrf, &full, &g))
        return false;
    out->levels = g.n[2];
    out->bottom_m = g.origin[2];
    out->top_m = g.origin[2] + g.n[2] * g.spacing[2];
    out->heights = g;
    /* Along z as the reader crops; along x and y in composite columns. */
    struct wrf_desc zc = full;
    zc.crop[4] = d->crop[4];
    zc.crop[5] = d->crop[5];
    if (!wrf_grid(s->dom[0].wrf, &zc, &g))
        return false;
    out->count = s->count;
    out->grid = g;
    int lo[2] = {0, 0};
    for (int a = 0; a < 2; a++) {
        int n = g.n[a] * s->scale[0];
        int c0 = d->crop[2 * a] >= 0 ? d->crop[2 * a] : 0;
        int c1 = d->crop[2 * a + 1] >= 0 ? d->crop[2 * a + 1] : n - 1;
        if (c0 > c1 || c1 >= n) {
            log_error("%s and its nests: data.crop along %c keeps columns %d to %d of the "
                      "composite's %d (with nests the crop counts the composite's columns of "
                      "%g m)",
                      s->dom[0].path, "xy"[a], c0, c1, n, g.spacing[a] / s->scale[0]);
            return false;
        }
        lo[a] = c0;
        out->grid.n[a] = c1 - c0 + 1;
        out->grid.spacing[a] = g.spacing[a] / s->scale[0];
        out->grid.origin[a] = g.origin[a] + c0 * out->grid.spacing[a];
    }
    for (int i = 0; i < s->count; i++) {
        out->place[i].offset[0] = s->offset[i][0] - lo[0];
        out->place[i].offset[1] = s->offset[i][1] - lo[1];
        out->place[i].scale = s->scale[i];
        out->place[i].blend = s->blend[i];
    }
    return true;
}

/* Whether domain I's box overlaps L's grid. */
static bool overlaps(const struct nest_layout *l, const struct nest_set *s, int i)
{
    const struct wrf_meta *m = wrf_get_meta(s->dom[i].wrf);
    int cells[2] = {m->nx, m->ny};
    for (int a = 0; a < 2; a++) {
        int o = l->place[i].offset[a];
        if (o >= l->grid.n[a] || o + cells[a] * l->place[i].scale <= 0)
            return false;
    }
    return true;
}

/* A domain's read: the outermost's heights (and crop along z), all its columns. */
static void nest_desc(const struct nest_layout *l, const struct wrf_desc *d, struct wrf_desc *out)
{
    *out = *d;
    out->levels = l->levels;
    out->bottom_m = l->bottom_m;
    out->top_m = l->top_m;
    /* The model's own levels: the outermost's, not each nest's own mean column (their levels
     * even: the uniform grid they are, as levels, bottom and top say). */
    out->native_from = d->native_levels && grid3_stretched(&l->heights) ? &l->heights : NULL;
    out->native_levels = out->native_from != NULL;
    for (int i = 0; i < 4; i++)
        out->crop[i] = -1;
}

size_t nest_step_bytes(const struct nest_set *s, const struct wrf_desc *d)
{
    struct nest_layout l;
    if (!nest_layout(s, d, &l))
        return 0;
    struct wrf_desc nd;
    nest_desc(&l, d, &nd);
    double total = 0.0, outer = 0.0;
    for (int i = 0; i < s->count; i++) {
        if (i > 0 && !overlaps(&l, s, i))
            continue;
        size_t b = wrf_step_bytes(s->dom[i].wrf, &nd);
        if (b == 0 || b == SIZE_MAX)
            return b;
        total += (double)b;
        if (i == 0)
            outer = (double)b;
    }
    /* The composite holds the outermost's arrays on its share of the columns, scale^2 times
     * finer. */
    const struct wrf_meta *m = wrf_get_meta(s->dom[0].wrf);
    total += outer * ((double)l.grid.n[0] * l.grid.n[1]) / ((double)m->nx * m->ny);
    return total >= (double)SIZE_MAX ? SIZE_MAX : (size_t)total;
}

/* ---- composing ---------------------------------------------------------------------------- */

/* Where each composite column along one axis reads a domain: its lower and upper column and
 * the weight of the upper (bilinear between the domain's column centres, clamped to its edge
 * columns as the eye pass's sampler clamps), and its distance from the domain's edge in
 * composite columns. */
struct axis_tap {
    int lo, hi;
    double f, edge;
};

static void axis_taps(int cells, int scale, struct axis_tap *out)
{
    int n = cells * scale;
    for (int c = 0; c < n; c++) {
        double u = fmin(fmax((c + 0.5) / scale - 0.5, 0.0), cells - 1.0);
        int lo = cells > 1 ? (int)floor(u) : 0;
        if (cells > 1 && lo > cells - 2)
            lo = cells - 2;
        out[c].lo = lo;
        out[c].hi = cells > 1 ? lo + 1 : lo;
        out[c].f = cells > 1 ? u - lo : 0.0;
        out[c].edge = fmin(c + 0.5, n - c - 0.5);
    }
}

/* One domain's pass over rows (plane k, composite row) [BEGIN, END): its columns I_LO to
 * I_HI and rows J_LO on, of its own box (the part the grid holds). */
struct compose_pass {
    const struct nest_place *p;
    const float *src; /* NULL: zero */
    int cx, cy, nx, ny;
    int i_lo, i_hi, j_lo, rows;
    const struct axis_tap *tx, *ty;
    float *dst;
};

static bool compose_rows(void *ctx, int share, size_t begin, size_t end)
{
    (void)share;
    const struct compose_pass *c = ctx;
    const struct nest_place *p = c->p;
    size_t plane = (size_t)c->nx * c->ny, cplane = (size_t)c->cx * c->cy;
    for (size_t r = begin; r < end; r++) {
        int k = (int)(r / (size_t)c->rows), jr = c->j_lo + (int)(r % (size_t)c->rows);
        const struct axis_tap *ty = &c->ty[jr];
        float *t = c->dst + k * plane + (size_t)(p->offset[1] + jr) * c->nx + p->offset[0];
        const float *s = c->src ? c->src + k * cplane : NULL;
        for (int ir = c->i_lo; ir < c->i_hi; ir++) {
            const struct axis_tap *tx = &c->tx[ir];
            double val = 0.0;
            if (s) {
                const float *r0 = s + (size_t)ty->lo * c->cx, *r1 = s + (size_t)ty->hi * c->cx;
                /* Weights exactly 0 keep a column's value bit for bit. */
                double lo =
                    tx->f > 0.0 ? r0[tx->lo] + tx->f * (r0[tx->hi] - r0[tx->lo]) : r0[tx->lo];
                double hi =
                    tx->f > 0.0 ? r1[tx->lo] + tx->f * (r1[tx->hi] - r1[tx->lo]) : r1[tx->lo];
                val = ty->f > 0.0 ? lo + ty->f * (hi - lo) : lo;
            }
            double w = p->blend > 0 ? fmin(1.0, fmin(tx->edge, ty->edge) / p->blend) : 1.0;
            t[ir] = w >= 1.0 ? (float)val : (float)(w * val + (1.0 - w) * t[ir]);
        }
    }
    return true;
}

static int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* One array of every domain onto the composite: NZ planes of the composite's columns, the
 * domains in order (each blends into what those before it wrote), each cut into shares of
 * rows.  SRC[i] NULL reads as zero.  False when out of memory. */
static bool compose_array(const struct nest_layout *l, const struct field_volume *in,
                          float *const *src, int nz, float *dst)
{
    for (int d = 0; d < l->count; d++) {
        const struct nest_place *p = &l->place[d];
        struct compose_pass c = {.p = p,
                                 .src = src[d],
                                 .cx = in[d].grid.n[0],
                                 .cy = in[d].grid.n[1],
                                 .nx = l->grid.n[0],
                                 .ny = l->grid.n[1],
                                 .dst = dst};
        int w = c.cx * p->scale, h = c.cy * p->scale;
        c.i_lo = clampi(-p->offset[0], 0, w);
        c.i_hi = clampi(c.nx - p->offset[0], 0, w);
        c.j_lo = clampi(-p->offset[1], 0, h);
        c.rows = clampi(c.ny - p->offset[1], 0, h) - c.j_lo;
        if (c.i_hi <= c.i_lo || c.rows <= 0)
            continue;
        struct axis_tap *tx = malloc(((size_t)w + h) * sizeof(*tx));
        if (!tx)
            return false;
        axis_taps(c.cx, p->scale, tx);
        axis_taps(c.cy, p->scale, tx + w);
        c.tx = tx;
        c.ty = tx + w;
        parallel_for((size_t)nz * c.rows, 16, &c, compose_rows);
        free(tx);
    }
    return true;
}

/* The member of a field volume that nest_compose carries, by number. */
static float **member(struct field_volume *v, int m)
{
    if (m < SPECIES_COUNT)
        return &v->q[m];
    float **rest[] = {&v->qvapor, &v->rho_air, &v->temperature, &v->wind,   &v->u,
                      &v->v,      &v->w,       &v->vorticity,   &v->level_z};
    return rest[m - SPECIES_COUNT];
}
#define MEMBER_COUNT (SPECIES_COUNT + 9)
#define MEMBER_LEVEL_Z (MEMBER_COUNT - 1)

bool nest_compose(const struct nest_layout *l, const struct field_volume *in,
                  struct field_volume *out)
{
    memset(out, 0, sizeof(*out));
    const struct grid3 *g = &l->grid;
    for (int d = 0; d < l->count; d++) {
        const struct grid3 *dg = &in[d].grid;
        const struct nest_place *p = &l->place[d];
        if (dg->n[2] != g->n[2] || fabs(dg->origin[2] - g->origin[2]) > 1e-3 * g->spacing[2] ||
            fabs(dg->spacing[2] - g->spacing[2]) > 1e-6 * g->spacing[2] || p->scale < 1 ||
            fabs(dg->spacing[0] - p->scale * g->spacing[0]) > 1e-3 * dg->spacing[0] ||
            dg->n[0] < 1 || dg->n[1] < 1) {
            log_error("domain %d of %d: its grid (%d x %d x %d, %g m, heights from %g m by %g m) "
                      "does not fit the composite (%d x %d x %d, %g m, from %g m by %g m)",
                      d + 1, l->count, dg->n[0], dg->n[1], dg->n[2], dg->spacing[0], dg->origin[2],
                      dg->spacing[2], g->n[0], g->n[1], g->n[2], g->spacing[0], g->origin[2],
                      g->spacing[2]);
            return false;
        }
    }
    out->grid = *g;
    size_t plane = (size_t)g->n[0] * g->n[1];
    for (int m = 0; m < MEMBER_COUNT; m++) {
        bool any = false, all = true;
        int nz = m == MEMBER_LEVEL_Z ? in[0].level_count : g->n[2];
        float *src[NEST_DOMAIN_MAX];
        for (int d = 0; d < l->count; d++) {
            src[d] = *member((struct field_volume *)&in[d], m);
            any = any || src[d];
            all = all && src[d] && (m != MEMBER_LEVEL_Z || in[d].level_count == nz);
        }
        /* Mass ratios absent in one domain are zero there; the rest are all or nothing. */
        bool mass = m <= SPECIES_COUNT;
        if (!any || (!mass && !all))
            continue;
        float *dst = calloc(plane * (size_t)nz, sizeof(float));
        if (!dst) {
            field_volume_finish(out);
            log_error("out of memory composing %d domains (%d x %d x %d voxels)", l->count, g->n[0],
                      g->n[1], nz);
            return false;
        }
        *member(out, m) = dst;
        if (!compose_array(l, in, src, nz, dst)) {
            field_volume_finish(out);
            log_error("out of memory composing %d domains", l->count);
            return false;
        }
        if (m == MEMBER_LEVEL_Z)
            out->level_count = nz;
    }
    return true;
}

/* Domain I's step at the outermost's STEP's Times (its index where there are none), or -1. */
static int match_step(struct nest_set *s, int i, int step)
{
    const char *date = wrf_step_date(s->dom[0].wrf, step);
    struct wrf *w = s->dom[i].wrf;
    for (int t = 0; t < wrf_step_count(w); t++)
        if (date[0] ? !strcmp(wrf_step_date(w, t), date) : t == step)
            return t;
    return -1;
}

enum wrf_point_result nest_read_point(struct nest_set *s, int step, const struct wrf_desc *d,
                                      const double p[3], struct wrf_point *out)
{
    memset(out, 0, sizeof(*out));
    struct nest_layout l;
    if (!nest_layout(s, d, &l))
        return WRF_POINT_ERROR;
    const struct grid3 *g = &l.grid;
    for (int a = 0; a < 2; a++)
        if (!(p[a] >= g->origin[a] && p[a] <= g->origin[a] + g->n[a] * g->spacing[a]))
            return WRF_POINT_OUTSIDE;
    struct wrf_desc nd;
    nest_desc(&l, d, &nd);
    /* The finest domain there with a step at that time. */
    for (int i = s->count - 1; i >= 0; i--) {
        const struct wrf_meta *m = wrf_get_meta(s->dom[i].wrf);
        double q[3] = {p[0] - s->offset[i][0] * (g->spacing[0]),
                       p[1] - s->offset[i][1] * (g->spacing[1]), p[2]};
        if (q[0] < 0.0 || q[1] < 0.0 || q[0] > m->nx * m->dx || q[1] > m->ny * m->dy)
            continue;
        int t = i ? match_step(s, i, step) : step;
        if (t < 0)
            continue;
        return wrf_read_point(s->dom[i].wrf, t, &nd, q, out);
    }
    return WRF_POINT_OUTSIDE;
}

bool nest_read_step(struct nest_set *s, int step, const struct wrf_desc *d,
                    struct field_volume *out, struct wrf_stats *stats)
{
    memset(out, 0, sizeof(*out));
    struct nest_layout l;
    if (!nest_layout(s, d, &l))
        return false;
    size_t need = nest_step_bytes(s, d);
    if (need == 0)
        return false;
    if ((d->memory_mb > 0 && (double)need > d->memory_mb * 1048576.0) || need == SIZE_MAX) {
        log_error("%s and %d nest%s: a time step of every domain and their composite on "
                  "%d x %d x %d voxels need %.0f MiB, above the budget data.memory = %.0f MiB",
                  s->dom[0].path, s->count - 1, s->count > 2 ? "s" : "", l.grid.n[0], l.grid.n[1],
                  l.grid.n[2], (double)need / 1048576.0, d->memory_mb);
        return false;
    }
    struct wrf_desc nd;
    nest_desc(&l, d, &nd);
    struct field_volume in[NEST_DOMAIN_MAX];
    memset(in, 0, sizeof(in));
    struct nest_layout used = l;
    used.count = 0;
    int from[NEST_DOMAIN_MAX]; /* the set's domain each used one is */
    /* The outermost whole along x and y (the crop is the composite's), cropped along z. */
    struct wrf_desc od = *d;
    for (int i = 0; i < 4; i++)
        od.crop[i] = -1;
    bool ok = wrf_read_step(s->dom[0].wrf, step, &od, &in[0], stats);
    if (ok) {
        used.count = 1;
        from[0] = 0;
    }
    const char *date = wrf_step_date(s->dom[0].wrf, step);
    for (int i = 1; ok && i < s->count; i++) {
        struct wrf *w = s->dom[i].wrf;
        int match = match_step(s, i, step);
        if (match < 0) {
            log_warn("%s: domain %d has no step at %s: the time step shows the domains around "
                     "it only",
                     s->dom[i].path, s->dom[i].grid_id, date[0] ? date : "this index");
            continue;
        }
        if (!overlaps(&l, s, i))
            continue; /* outside the crop: not read */
        /* A nest of a nest left out leaves it out too: it blends into its parent. */
        bool parent_used = false;
        for (int j = 0; j < used.count; j++)
            parent_used = parent_used || from[j] == s->parent[i];
        if (!parent_used)
            continue;
        int at = used.count;
        ok = wrf_read_step(w, match, &nd, &in[at], NULL);
        if (ok) {
            used.place[at] = l.place[i];
            from[at] = i;
            used.count++;
        }
    }
    if (ok)
        ok = nest_compose(&used, in, out);
    for (int i = 0; i < used.count; i++)
        field_volume_finish(&in[i]);
    return ok;
}

void nest_describe(const struct nest_set *s, int i, char *out, size_t size)
{
    const struct nest_domain *d = &s->dom[i];
    const struct wrf_meta *m = wrf_get_meta(d->wrf);
    if (i == 0) {
        snprintf(out, size,
                 "d%02d %d x %d columns of %g m: the outermost domain, the scene's "
                 "frame (%s)",
                 d->grid_id, m->nx, m->ny, m->dx, d->path);
        return;
    }
    const struct nest_domain *p = &s->dom[s->parent[i]];
    int n =
        snprintf(out, size,
                 "d%02d %d x %d columns of %g m in d%02d from its column %d, %d "
                 "(ratio %d), ",
                 d->grid_id, m->nx, m->ny, m->dx, p->grid_id, d->start[0], d->start[1], d->ratio);
    if (n < 0 || (size_t)n >= size)
        return;
    if (d->by_latlon)
        snprintf(out + n, size - (size_t)n,
                 "placed by its XLAT/XLONG (%.0f m off the grid) "
                 "(%s)",
                 d->misfit_m, d->path);
    else if (isfinite(d->misfit_m))
        snprintf(out + n, size - (size_t)n,
                 "placed by PARENT_ID, I/J_PARENT_START and "
                 "PARENT_GRID_RATIO; XLAT/XLONG agree within %.0f m (%s)",
                 d->misfit_m, d->path);
    else
        snprintf(out + n, size - (size_t)n,
                 "placed by PARENT_ID, I/J_PARENT_START and "
                 "PARENT_GRID_RATIO (%s)",
                 d->path);
}

bool nest_cut(const struct field_volume *fine, int ratio, const int *box, struct field_volume *out)
{
    memset(out, 0, sizeof(*out));
    const struct grid3 *g = &fine->grid;
    struct grid3 og = *g;
    if (box) {
        if (box[0] < 0 || box[1] < 0 || box[2] < 1 || box[3] < 1 || box[0] + box[2] > g->n[0] ||
            box[1] + box[3] > g->n[1]) {
            log_error("nest: columns %d to %d, %d to %d lie outside the %d x %d columns", box[0],
                      box[0] + box[2] - 1, box[1], box[1] + box[3] - 1, g->n[0], g->n[1]);
            return false;
        }
        og.n[0] = box[2];
        og.n[1] = box[3];
        og.origin[0] += box[0] * g->spacing[0];
        og.origin[1] += box[1] * g->spacing[1];
    } else {
        if (ratio < 1 || g->n[0] % ratio || g->n[1] % ratio) {
            log_error("nest: a ratio of %d does not divide %d x %d columns", ratio, g->n[0],
                      g->n[1]);
            return false;
        }
        for (int a = 0; a < 2; a++) {
            og.n[a] = g->n[a] / ratio;
            og.spacing[a] = g->spacing[a] * ratio;
        }
    }
    out->grid = og;
    size_t n = grid3_count(&og);
    /* The fine columns a coarse column averages: its central one, or the central 2 x 2. */
    int lo = (ratio - 1) / 2, hi = ratio / 2;
    for (int m = 0; m < SPECIES_COUNT + 2; m++) {
        const float *src = *member((struct field_volume *)fine, m);
        if (!src)
            continue;
        float *dst = malloc(n * sizeof(float));
        if (!dst) {
            field_volume_finish(out);
            log_error("nest: out of memory");
            return false;
        }
        for (int k = 0; k < og.n[2]; k++)
            for (int j = 0; j < og.n[1]; j++)
                for (int i = 0; i < og.n[0]; i++) {
                    double sum = 0.0;
                    int cnt = 0;
                    if (box) {
                        sum = src[grid3_index(g, box[0] + i, box[1] + j, k)];
                        cnt = 1;
                    } else {
                        for (int b = lo; b <= hi; b++)
                            for (int a = lo; a <= hi; a++, cnt++)
                                sum += src[grid3_index(g, i * ratio + a, j * ratio + b, k)];
                    }
                    dst[grid3_index(&og, i, j, k)] = (float)(sum / cnt);
                }
        *member(out, m) = dst;
    }
    return true;
}
