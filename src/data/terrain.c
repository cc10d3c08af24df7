#include "data/terrain.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

void terrain_finish(struct terrain *t)
{
    if (!t)
        return;
    free(t->x);
    free(t->y);
    free(t->height);
    free(t->kind);
    memset(t, 0, sizeof(*t));
}

enum terrain_kind terrain_kind_of_land_use(const char *scheme, int c)
{
    if (scheme && strstr(scheme, "MODIS")) {
        /* IGBP classes as WRF's MODIS tables number them (20 or 21 with lakes). */
        if (c >= 1 && c <= 5)
            return TERRAIN_FOREST;
        if (c == 6 || c == 7)
            return TERRAIN_SHRUB;
        if (c == 8 || c == 9 || c == 10)
            return TERRAIN_GRASS;
        if (c == 11)
            return TERRAIN_WETLAND;
        if (c == 12 || c == 14)
            return TERRAIN_CROP;
        if (c == 13)
            return TERRAIN_URBAN;
        if (c == 15)
            return TERRAIN_ICE;
        if (c == 16)
            return TERRAIN_BARREN;
        if (c == 17 || c == 21)
            return TERRAIN_SEA;
        if (c >= 18 && c <= 20)
            return TERRAIN_TUNDRA;
        return TERRAIN_LAND;
    }
    /* USGS 24 classes (28 with playa, lava, white sand and lakes). */
    if (c == 1)
        return TERRAIN_URBAN;
    if (c >= 2 && c <= 6)
        return TERRAIN_CROP;
    if (c == 7 || c == 10)
        return TERRAIN_GRASS;
    if (c == 8 || c == 9)
        return TERRAIN_SHRUB;
    if (c >= 11 && c <= 15)
        return TERRAIN_FOREST;
    if (c == 16 || c == 28)
        return TERRAIN_SEA;
    if (c == 17 || c == 18)
        return TERRAIN_WETLAND;
    if (c == 19 || c == 25 || c == 26 || c == 27)
        return TERRAIN_BARREN;
    if (c >= 20 && c <= 23)
        return TERRAIN_TUNDRA;
    if (c == 24)
        return TERRAIN_ICE;
    return TERRAIN_LAND;
}

void terrain_albedo(enum terrain_kind kind, double h, float rgb[3])
{
    /* Linear albedos, roughly what the surfaces reflect (darker than they look in sRGB). */
    static const float base[TERRAIN_KIND_COUNT][3] = {
        [TERRAIN_SEA] = {0.008f, 0.02f, 0.04f},   [TERRAIN_LAND] = {0.10f, 0.12f, 0.06f},
        [TERRAIN_CROP] = {0.14f, 0.16f, 0.07f},    [TERRAIN_GRASS] = {0.10f, 0.15f, 0.05f},
        [TERRAIN_SHRUB] = {0.13f, 0.13f, 0.07f},   [TERRAIN_FOREST] = {0.04f, 0.08f, 0.03f},
        [TERRAIN_WETLAND] = {0.05f, 0.08f, 0.06f}, [TERRAIN_BARREN] = {0.25f, 0.21f, 0.15f},
        [TERRAIN_TUNDRA] = {0.16f, 0.15f, 0.11f},  [TERRAIN_ICE] = {0.75f, 0.78f, 0.82f},
        [TERRAIN_URBAN] = {0.18f, 0.17f, 0.16f},
    };
    static const float rock[3] = {0.17f, 0.15f, 0.13f}, snow[3] = {0.70f, 0.72f, 0.76f};
    int k = kind >= 0 && kind < TERRAIN_KIND_COUNT ? kind : TERRAIN_LAND;
    double r = kind == TERRAIN_SEA ? 0.0 : fmin(1.0, fmax(0.0, (h - 2000.0) / 2500.0));
    double s = kind == TERRAIN_SEA ? 0.0 : fmin(1.0, fmax(0.0, (h - 5000.0) / 800.0));
    for (int c = 0; c < 3; c++) {
        double v = base[k][c] + r * (rock[c] - base[k][c]);
        rgb[c] = (float)(v + s * (snow[c] - v));
    }
}

/* Columns whose centres (c + 0.5) D lie in [lo, hi], plus the two box faces. */
static int axis_vertices(int n_cols, double d, double lo, double hi, double **pos, int **col)
{
    int c0 = (int)ceil(lo / d - 0.5), c1 = (int)floor(hi / d - 0.5);
    c0 = c0 < 0 ? 0 : c0;
    c1 = c1 > n_cols - 1 ? n_cols - 1 : c1;
    if (c1 < c0)
        return 0;
    int n = c1 - c0 + 3;
    *pos = malloc((size_t)n * sizeof(double));
    *col = malloc((size_t)n * sizeof(int));
    if (!*pos || !*col) {
        free(*pos);
        free(*col);
        return -1;
    }
    (*pos)[0] = lo;
    (*col)[0] = c0;
    for (int c = c0; c <= c1; c++) {
        (*pos)[c - c0 + 1] = (c + 0.5) * d;
        (*col)[c - c0 + 1] = c;
    }
    (*pos)[n - 1] = hi;
    (*col)[n - 1] = c1;
    return n;
}

bool terrain_from_wrf(const struct wrf_meta *m, const struct grid3 *box, struct terrain *out)
{
    memset(out, 0, sizeof(*out));
    if (!m->hgt) {
        log_warn("the data has no HGT: the ground is flat");
        return false;
    }
    int *ci = NULL, *cj = NULL;
    double lo[2], hi[2];
    for (int a = 0; a < 2; a++) {
        lo[a] = box->origin[a];
        hi[a] = box->origin[a] + box->n[a] * box->spacing[a];
    }
    int nx = axis_vertices(m->nx, m->dx, lo[0], hi[0], &out->x, &ci);
    int ny = nx > 0 ? axis_vertices(m->ny, m->dy, lo[1], hi[1], &out->y, &cj) : 0;
    if (nx <= 0 || ny <= 0) {
        if (nx < 0 || ny < 0)
            log_error("out of memory for the terrain");
        else
            log_warn("the volume covers no terrain column: the ground is flat");
        free(ci);
        free(cj);
        terrain_finish(out);
        return false;
    }
    out->nx = nx;
    out->ny = ny;
    out->height = malloc((size_t)nx * ny * sizeof(float));
    out->kind = malloc((size_t)nx * ny);
    if (!out->height || !out->kind) {
        log_error("out of memory for the terrain");
        free(ci);
        free(cj);
        terrain_finish(out);
        return false;
    }
    out->has_landmask = m->landmask != NULL;
    out->has_land_use = m->lu_index != NULL;
    for (int j = 0; j < ny; j++) {
        for (int i = 0; i < nx; i++) {
            size_t src = (size_t)cj[j] * m->nx + ci[i], dst = (size_t)j * nx + i;
            float h = m->hgt[src];
            h = isfinite(h) && fabsf(h) < 1e4f ? h : 0.0f;
            enum terrain_kind k = TERRAIN_LAND;
            if (m->lu_index && isfinite(m->lu_index[src]))
                k = terrain_kind_of_land_use(m->land_use, (int)lrintf(m->lu_index[src]));
            if (m->landmask) {
                bool land = m->landmask[src] >= 0.5f;
                if (!land)
                    k = TERRAIN_SEA;
                else if (k == TERRAIN_SEA)
                    k = TERRAIN_LAND;
            } else if (!m->lu_index) {
                k = h > 0.5f ? TERRAIN_LAND : TERRAIN_SEA;
            }
            out->height[dst] = h;
            out->kind[dst] = (unsigned char)k;
        }
    }
    free(ci);
    free(cj);
    return true;
}

/* Index of the interval of POS (increasing, N values) holding V, and the fraction in it. */
static int locate(const double *pos, int n, double v, double *f)
{
    if (v <= pos[0]) {
        *f = 0.0;
        return 0;
    }
    if (v >= pos[n - 1]) {
        *f = 1.0;
        return n - 2;
    }
    int a = 0, b = n - 1;
    while (b - a > 1) {
        int mid = (a + b) / 2;
        if (pos[mid] <= v)
            a = mid;
        else
            b = mid;
    }
    double w = pos[b] - pos[a];
    *f = w > 0 ? (v - pos[a]) / w : 0.0;
    return a;
}

double terrain_height_at(const struct terrain *t, double x, double y)
{
    if (!t->height || t->nx < 2 || t->ny < 2)
        return 0.0;
    double u, v;
    int i = locate(t->x, t->nx, x, &u), j = locate(t->y, t->ny, y, &v);
    const float *h = t->height;
    size_t a = (size_t)j * t->nx + i;
    double h00 = h[a], h10 = h[a + 1], h01 = h[a + t->nx], h11 = h[a + t->nx + 1];
    return (1 - v) * ((1 - u) * h00 + u * h10) + v * ((1 - u) * h01 + u * h11);
}
