/* Light transport through the light-space grid, slice by slice from the sun (Nes §5.2.3). */
#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "light/light.h"

#define PI 3.14159265358979323846

/* The volume's sampling constants in float32, as the GPU holds them. */
struct beta_sampler {
    const float *beta;
    int n[3];
    float origin[3];
    float inv_spacing[3];
};

static void sampler_init(struct beta_sampler *s, const struct ext_volume *vol)
{
    s->beta = vol->beta;
    for (int a = 0; a < 3; a++) {
        s->n[a] = vol->grid.n[a];
        s->origin[a] = (float)vol->grid.origin[a];
        s->inv_spacing[a] = (float)(1.0 / vol->grid.spacing[a]);
    }
}

/* Continuous voxel coordinate X (voxel units from the box minimum) -> lower voxel index and
 * weight of the upper one, clamped to the edge voxels. */
static int axis_weight(float x, int n, float *t)
{
    float f = x - 0.5f;
    if (n < 2 || f <= 0.0f) {
        *t = 0.0f;
        return 0;
    }
    if (f >= (float)(n - 1)) {
        *t = 1.0f;
        return n - 2;
    }
    int i = (int)f;
    *t = f - (float)i;
    return i;
}

static void sample_beta(const struct beta_sampler *s, const float p[3], float out[2])
{
    float x[3];
    for (int a = 0; a < 3; a++) {
        x[a] = (p[a] - s->origin[a]) * s->inv_spacing[a];
        if (!(x[a] >= 0.0f && x[a] <= (float)s->n[a])) { /* outside the box (or NaN) */
            out[0] = out[1] = 0.0f;
            return;
        }
    }
    float t[3];
    int i0[3], di[3];
    for (int a = 0; a < 3; a++) {
        i0[a] = axis_weight(x[a], s->n[a], &t[a]);
        di[a] = s->n[a] > 1 ? 1 : 0;
    }
    size_t sx = (size_t)di[0], sy = (size_t)di[1] * (size_t)s->n[0];
    size_t sz = (size_t)di[2] * (size_t)s->n[0] * (size_t)s->n[1];
    size_t base = (size_t)i0[0] + (size_t)s->n[0] * ((size_t)i0[1] + (size_t)s->n[1] * i0[2]);
    for (int c = 0; c < 2; c++) {
        const float *b = s->beta + c;
        float c00 = b[2 * base] + t[0] * (b[2 * (base + sx)] - b[2 * base]);
        float c10 = b[2 * (base + sy)] + t[0] * (b[2 * (base + sy + sx)] - b[2 * (base + sy)]);
        float c01 = b[2 * (base + sz)] + t[0] * (b[2 * (base + sz + sx)] - b[2 * (base + sz)]);
        float c11 = b[2 * (base + sz + sy)] +
                    t[0] * (b[2 * (base + sz + sy + sx)] - b[2 * (base + sz + sy)]);
        float c0 = c00 + t[1] * (c10 - c00);
        float c1 = c01 + t[1] * (c11 - c01);
        float v = c0 + t[2] * (c1 - c0);
        out[c] = v >= 0.0f ? fminf(v, 1e30f) : 0.0f; /* NaN -> 0; Inf kept finite */
    }
}

void light_sample_beta(const struct ext_volume *vol, const float p[3], float out[2])
{
    struct beta_sampler s;
    sampler_init(&s, vol);
    sample_beta(&s, p, out);
}

void light_settings_defaults(struct light_settings *s)
{
    memset(s, 0, sizeof(*s));
    s->resolution[0] = s->resolution[1] = s->resolution[2] = 128;
    s->forward_angle_deg = 20.0;
    s->forward = true;
    s->peripheral = true;
    s->epsilon = 0.002;
    s->substeps = 0;
}

int light_auto_substeps(const struct light_grid *g, const struct grid3 *box)
{
    double cross = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (fabs(g->w[a]) > 0.0)
            cross = fmin(cross, box->spacing[a] / fabs(g->w[a]));
    }
    double m = ceil(g->step[2] / cross - 1e-9);
    return m < 1.0 ? 1 : m > 128.0 ? 128 : (int)m;
}

void light_settings_set_optics(struct light_settings *s, const struct optics_params *optics,
                               double forward_angle_deg)
{
    s->forward_angle_deg = forward_angle_deg;
    optics_forward_cp(optics, forward_angle_deg * (PI / 180.0), &s->cp);
}

double light_peripheral_offset(double forward_angle_deg, double dz)
{
    /* Riley §4.4: the outer band runs from theta/4 to theta/2; its four samples are taken at
     * the band's middle angle, 3 theta / 8, one slice back. */
    return dz * tan(0.375 * forward_angle_deg * (PI / 180.0));
}

/* Bilinear lookup in node plane PL (n0 x n1) at node coordinates (x, y); nodes outside the
 * plane read as the incident light 1. */
static float plane_tap(const float *pl, int n0, int n1, float x, float y)
{
    float fx = floorf(x), fy = floorf(y);
    float tx = x - fx, ty = y - fy;
    int ix = (int)fx, iy = (int)fy;
    float v[2][2];
    for (int b = 0; b < 2; b++) {
        for (int a = 0; a < 2; a++) {
            int i = ix + a, j = iy + b;
            v[b][a] = (i < 0 || j < 0 || i >= n0 || j >= n1) ? 1.0f : pl[i + (size_t)n0 * j];
        }
    }
    float r0 = v[0][0] + tx * (v[0][1] - v[0][0]);
    float r1 = v[1][0] + tx * (v[1][1] - v[1][0]);
    return r0 + ty * (r1 - r0);
}

void light_map_finish(struct light_map *map)
{
    if (!map)
        return;
    free(map->light);
    memset(map, 0, sizeof(*map));
}

bool light_map_build(const struct ext_volume *vol, const double sun[3],
                     const struct light_settings *s, struct light_map *map)
{
    assert(vol && vol->beta && sun && s && map);
    float *reuse = map->light;
    size_t old_count = map->light ? (size_t)map->grid.n[0] * map->grid.n[1] * map->grid.n[2] : 0;
    map->light = NULL;
    if (!light_grid_init(&map->grid, sun, &vol->grid, s->resolution)) {
        free(reuse);
        light_map_finish(map);
        return false;
    }
    const struct light_grid *g = &map->grid;
    const int n0 = g->n[0], n1 = g->n[1], n2 = g->n[2];
    size_t plane = (size_t)n0 * n1, count = plane * n2;
    if (reuse && old_count == count) {
        map->light = reuse;
    } else {
        free(reuse);
        map->light = malloc(count * sizeof(float));
        if (!map->light) {
            log_error("light map: out of memory for %d x %d x %d nodes", n0, n1, n2);
            light_map_finish(map);
            return false;
        }
    }

    struct beta_sampler bs;
    sampler_init(&bs, vol);
    map->substeps = s->substeps > 0 ? s->substeps : light_auto_substeps(g, &vol->grid);
    const int sub = map->substeps;
    const float dsub = (float)(g->step[2] / sub);
    const bool fwd = s->forward;
    const bool per = s->forward && s->peripheral;
    const float cpc_water = (float)s->cp.water_ctr, cpc_ice = (float)s->cp.ice_ctr;
    const float cpp_water = (float)s->cp.water_per, cpp_ice = (float)s->cp.ice_per;
    const double r = light_peripheral_offset(s->forward_angle_deg, g->step[2]);
    const float rx = (float)(r / g->step[0]), ry = (float)(r / g->step[1]);

    float *L = map->light;
    for (size_t c = 0; c < plane; c++)
        L[c] = 1.0f; /* node plane 0 touches the box only at its sun-most corner */

    for (int k = 1; k < n2; k++) {
        const float *prev = L + plane * (size_t)(k - 1);
        float *cur = L + plane * (size_t)k;
        for (int j = 0; j < n1; j++) {
            for (int i = 0; i < n0; i++) {
                /* Segment from node plane k-1 to k: optical depth by the midpoint rule on SUB
                 * equal parts (one part, the segment midpoint, when the grids match). */
                float b[2] = {0.0f, 0.0f};
                for (int m = 0; m < sub; m++) {
                    float kz = (float)(k - 1) + ((float)m + 0.5f) / (float)sub;
                    float p[3], bm[2];
                    for (int a = 0; a < 3; a++)
                        p[a] = g->origin[a] + (float)i * g->du[a] + (float)j * g->dv[a] +
                               kz * g->dw[a];
                    sample_beta(&bs, p, bm);
                    b[0] += bm[0];
                    b[1] += bm[1];
                }
                float beta = b[0] + b[1]; /* sum over the parts: tau = beta dsub */
                float l_in = prev[i + (size_t)n0 * j];
                float t = expf(-beta * dsub); /* tau >> 100 underflows to 0: fine */
                float l = l_in * t;           /* Nes eq. 5.8 */
                if (fwd && beta > 0.0f) {
                    float f_ice = b[0] / beta;
                    float scat = 1.0f - t;
                    float cpc = cpc_water + f_ice * (cpc_ice - cpc_water);
                    l += l_in * scat * cpc; /* Nes eq. 5.9, Riley eq. 15 */
                    if (per) {
                        float fi = (float)i, fj = (float)j;
                        float l_per = 0.25f * (plane_tap(prev, n0, n1, fi + rx, fj) +
                                               plane_tap(prev, n0, n1, fi - rx, fj) +
                                               plane_tap(prev, n0, n1, fi, fj + ry) +
                                               plane_tap(prev, n0, n1, fi, fj - ry));
                        float cpp = cpp_water + f_ice * (cpp_ice - cpp_water);
                        l += l_per * scat * cpp; /* Nes eq. 5.10, Riley eq. 16 */
                    }
                }
                /* Nes eq. 5.11; never above the incident light, never negative. */
                cur[i + (size_t)n0 * j] = fminf(fmaxf(l, 0.0f), 1.0f);
            }
        }
    }
    return true;
}

size_t light_map_bytes(const struct light_map *m)
{
    return (size_t)m->grid.n[0] * m->grid.n[1] * m->grid.n[2] * sizeof(float);
}

int light_tex_node(float tex, int n, float *t)
{
    float x = tex * (float)n - 0.5f;
    if (!(x > 0.0f)) {
        *t = 0.0f;
        return 0;
    }
    if (x >= (float)(n - 1)) {
        *t = 1.0f;
        return n - 2;
    }
    int i = (int)x;
    *t = x - (float)i;
    return i;
}

float light_map_sample(const struct light_map *m, const float tex[3])
{
    const int *n = m->grid.n;
    int i[3];
    float t[3];
    for (int a = 0; a < 3; a++)
        i[a] = light_tex_node(tex[a], n[a], &t[a]);
    float c[2][2];
    for (int dk = 0; dk < 2; dk++) {
        for (int dj = 0; dj < 2; dj++) {
            float a0 = light_map_node(m, i[0], i[1] + dj, i[2] + dk);
            float a1 = light_map_node(m, i[0] + 1, i[1] + dj, i[2] + dk);
            c[dk][dj] = a0 + t[0] * (a1 - a0);
        }
    }
    float c0 = c[0][0] + t[1] * (c[0][1] - c[0][0]);
    float c1 = c[1][0] + t[1] * (c[1][1] - c[1][0]);
    return c0 + t[2] * (c1 - c0);
}
