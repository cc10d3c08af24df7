#include "data/volume.h"

#include <assert.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "common/parallel.h"

/* ---- the vertical coordinate ------------------------------------------------------------ */

double grid3_z_to_voxel(const struct grid3 *g, double z)
{
    if (!grid3_stretched(g))
        return (z - g->origin[2]) / g->spacing[2];
    int n = g->z_levels;
    const double *c = g->z_centre;
    double bottom = g->origin[2], top = bottom + n * g->spacing[2];
    if (!(z > c[0])) /* below the first centre (or NaN) */
        return 0.5 * (z - bottom) / (c[0] - bottom);
    if (z >= c[n - 1])
        return n - 0.5 + 0.5 * (z - c[n - 1]) / (top - c[n - 1]);
    int lo = 0, hi = n - 1; /* c[lo] < z <= c[hi] */
    while (hi - lo > 1) {
        int m = (lo + hi) / 2;
        if (c[m] < z)
            lo = m;
        else
            hi = m;
    }
    return lo + 0.5 + (z - c[lo]) / (c[hi] - c[lo]);
}

double grid3_voxel_to_z(const struct grid3 *g, double u)
{
    int n = g->n[2];
    u = u < 0.0 ? 0.0 : u > n ? n : u;
    if (!grid3_stretched(g))
        return g->origin[2] + u * g->spacing[2];
    const double *c = g->z_centre;
    double bottom = g->origin[2], top = bottom + n * g->spacing[2];
    if (u <= 0.5)
        return bottom + 2.0 * u * (c[0] - bottom);
    if (u >= n - 0.5)
        return c[n - 1] + 2.0 * (u - (n - 0.5)) * (top - c[n - 1]);
    int k = (int)(u - 0.5);
    k = k > n - 2 ? n - 2 : k;
    return c[k] + (u - 0.5 - k) * (c[k + 1] - c[k]);
}

double grid3_centre_z(const struct grid3 *g, int k)
{
    return grid3_stretched(g) ? g->z_centre[k] : g->origin[2] + (k + 0.5) * g->spacing[2];
}

double grid3_level_dz(const struct grid3 *g, int k)
{
    if (!grid3_stretched(g))
        return g->spacing[2];
    int n = g->z_levels;
    double lo = k > 0 ? 0.5 * (g->z_centre[k - 1] + g->z_centre[k]) : g->origin[2];
    double hi = k < n - 1 ? 0.5 * (g->z_centre[k] + g->z_centre[k + 1])
                          : g->origin[2] + n * g->spacing[2];
    return hi - lo;
}

double grid3_min_dz(const struct grid3 *g)
{
    double m = g->spacing[2];
    for (int k = 0; k < g->z_levels; k++) {
        double d = grid3_level_dz(g, k);
        m = d < m ? d : m;
    }
    return m;
}

void grid3_z_voxel_range(const struct grid3 *g, double z0, double z1, int *k0, int *k1)
{
    /* A point at voxel coordinate u reads levels floor(u - 0.5) and the one above. */
    int n = g->n[2];
    int a = (int)floor(grid3_z_to_voxel(g, z0) - 0.5);
    int b = (int)floor(grid3_z_to_voxel(g, z1) - 0.5) + 1;
    *k0 = a < 0 ? 0 : a > n - 1 ? n - 1 : a;
    *k1 = b < 0 ? 0 : b > n - 1 ? n - 1 : b;
}

bool grid3_set_levels(struct grid3 *g, const double *zc, int n, double bottom, double top)
{
    if (n < 1 || n > GRID3_LEVELS_MAX) {
        log_error("%d levels: a stretched grid holds 1 to %d", n, GRID3_LEVELS_MAX);
        return false;
    }
    for (int k = 0; k < n; k++) {
        if (!(zc[k] > (k ? zc[k - 1] : bottom)) || !(zc[k] < top)) {
            log_error("level %d at %g m: expected heights increasing upward inside [%g, %g] m",
                      k, zc[k], bottom, top);
            return false;
        }
    }
    g->n[2] = n;
    g->origin[2] = bottom;
    g->spacing[2] = (top - bottom) / n;
    g->z_levels = n;
    memset(g->z_centre, 0, sizeof(g->z_centre));
    memcpy(g->z_centre, zc, (size_t)n * sizeof(double));
    return true;
}

bool grid3_equal(const struct grid3 *a, const struct grid3 *b)
{
    for (int i = 0; i < 3; i++)
        if (a->n[i] != b->n[i] || a->spacing[i] != b->spacing[i] || a->origin[i] != b->origin[i])
            return false;
    if (a->z_levels != b->z_levels)
        return false;
    for (int k = 0; k < a->z_levels; k++)
        if (a->z_centre[k] != b->z_centre[k])
            return false;
    return true;
}

/* The mapping is piecewise linear with a corner at each centre, so a table linear between its
 * entries errs only in the entries holding a corner; 16 entries to the thinnest level keep
 * that within a sixteenth of it. */
#define ZMAP_PER_LEVEL 16
#define ZMAP_MAX 16384

int grid3_zmap_entries(const struct grid3 *g)
{
    if (!grid3_stretched(g))
        return 2;
    double e = ceil(ZMAP_PER_LEVEL * g->n[2] * g->spacing[2] / grid3_min_dz(g)) + 1.0;
    return e > ZMAP_MAX ? ZMAP_MAX : e < 2.0 ? 2 : (int)e;
}

void grid3_zmap_fill(const struct grid3 *g, int entries, float *tex, float *dz)
{
    double h = g->n[2] * g->spacing[2];
    for (int i = 0; i < entries; i++) {
        double z = g->origin[2] + h * i / (entries - 1);
        double u = grid3_z_to_voxel(g, z);
        tex[i] = (float)(u / g->n[2]);
        if (dz) {
            int k = (int)u;
            k = k < 0 ? 0 : k > g->n[2] - 1 ? g->n[2] - 1 : k;
            dz[i] = (float)grid3_level_dz(g, k);
        }
    }
}

/* ---- volumes ----------------------------------------------------------------------------- */

void field_volume_finish(struct field_volume *v)
{
    if (!v)
        return;
    for (int f = 0; f < SPECIES_COUNT; f++)
        free(v->q[f]);
    free(v->qvapor);
    free(v->temperature);
    free(v->wind);
    free(v->u);
    free(v->v);
    free(v->w);
    free(v->vorticity);
    free(v->level_z);
    free(v->rho_air);
    free(v->pressure);
    memset(v, 0, sizeof(*v));
}

void ext_volume_finish(struct ext_volume *v)
{
    if (!v)
        return;
    free(v->beta);
    free(v->tint);
    for (int i = 0; i < TRANSFER_LAYER_MAX; i++)
        free(v->layer[i]);
    for (int i = 0; i < TRANSFER_SLICE_MAX; i++) {
        free(v->slice[i]);
        free(v->slice_surface[i]);
    }
    free(v->histogram);
    memset(v, 0, sizeof(*v));
}

bool ext_volume_init(struct ext_volume *v, const struct grid3 *grid)
{
    memset(v, 0, sizeof(*v));
    v->grid = *grid;
    size_t n = grid3_count(grid);
    v->beta = calloc(n * 2, sizeof(float));
    if (!v->beta) {
        log_error("out of memory for a %dx%dx%d extinction volume (%zu MiB)", grid->n[0],
                  grid->n[1], grid->n[2], n * 2 * sizeof(float) >> 20);
        return false;
    }
    return true;
}

void species_select_defaults(struct species_select *s)
{
    for (int f = 0; f < SPECIES_COUNT; f++) {
        s->enabled[f] = true;
        s->scale[f] = 1.0;
    }
}

void ext_beta_init(struct ext_beta *b, const struct optics_params *optics,
                   const struct species_select *sel, const bool present[SPECIES_COUNT])
{
    memset(b, 0, sizeof(*b));
    b->scaled = sel != NULL;
    for (int f = 0; f < SPECIES_COUNT; f++) {
        double dn = 2.0 * optics->density[f] * optics->radius_m[f];
        if (!present[f] || (sel && !sel->enabled[f]) || !(dn > 0.0))
            continue;
        b->species[b->used] = f;
        b->denom[b->used] = dn;
        b->scale[b->used] = sel ? sel->scale[f] : 1.0;
        b->ice[b->used] = species_is_ice((enum species)f);
        b->used++;
    }
}

/* Voxels [I0, I1) one at a time. */
static void ext_beta_voxels(const struct ext_beta *b, const float *const *q,
                            const float *rho_air, double rho_std, size_t i0, size_t i1,
                            float *beta)
{
    for (size_t i = i0; i < i1; i++) {
        double rho = rho_air ? rho_air[i] : rho_std;
        if (!isfinite(rho) || rho < 0.0)
            rho = rho_std;
        double sum[2] = {0.0, 0.0}; /* ice, water */
        for (int u = 0; u < b->used && rho > 0.0; u++) {
            double x = q[u][i];
            if (!(x > 0.0) || !isfinite(x))
                continue;
            double v = 3.0 * rho * x / b->denom[u]; /* Nes eq. 5.3 */
            if (b->scaled)
                v *= b->scale[u];
            sum[b->ice[u] ? 0 : 1] += v;
        }
        beta[2 * i] = (float)sum[0];
        beta[2 * i + 1] = (float)sum[1];
    }
}

/* Whether the mass ratio X adds extinction (ext_beta_run's test, for floats). */
static inline bool adds(float x)
{
    return x > 0.0f && x <= FLT_MAX;
}

/* optics_beta with its constant part taken out of the loop.  Most of a storm's volume is clear
 * air: a block of voxels where no species adds anything is written as zeros (what the sums
 * give there) after one branch-free test that vectorises. */
void ext_beta_run(const struct ext_beta *b, const float *const *q, const float *rho_air,
                  double rho_std, size_t n, float *beta)
{
    enum { BLOCK = 64 };
    for (size_t i0 = 0; i0 < n; i0 += BLOCK) {
        size_t i1 = n - i0 < BLOCK ? n : i0 + BLOCK;
        int any = 0;
        for (int u = 0; u < b->used; u++)
            for (size_t i = i0; i < i1; i++)
                any |= adds(q[u][i]);
        if (!any) {
            memset(beta + 2 * i0, 0, 2 * (i1 - i0) * sizeof(float));
            continue;
        }
        ext_beta_voxels(b, q, rho_air, rho_std, i0, i1, beta);
    }
}

/* ext_volume_from_fields over planes [begin, end). */
struct beta_job {
    const struct field_volume *in;
    struct ext_beta b;
    float *beta;
};

static bool beta_planes(void *ctx, int share, size_t begin, size_t end)
{
    const struct beta_job *j = ctx;
    const struct grid3 *g = &j->in->grid;
    size_t plane = (size_t)g->n[0] * (size_t)g->n[1];
    for (size_t k = begin; k < end; k++) {
        const float *q[SPECIES_COUNT];
        for (int u = 0; u < j->b.used; u++)
            q[u] = j->in->q[j->b.species[u]] + plane * k;
        double rho_std = optics_std_atmosphere_density(grid3_centre_z(g, (int)k));
        ext_beta_run(&j->b, q, j->in->rho_air ? j->in->rho_air + plane * k : NULL, rho_std,
                     plane, j->beta + 2 * plane * k);
    }
    return true;
}

bool ext_volume_from_fields(const struct field_volume *in, const struct optics_params *optics,
                            const struct species_select *sel, struct ext_volume *out)
{
    if (!ext_volume_init(out, &in->grid))
        return false;
    struct beta_job j = {.in = in, .beta = out->beta};
    bool present[SPECIES_COUNT];
    for (int f = 0; f < SPECIES_COUNT; f++)
        present[f] = in->q[f] != NULL;
    ext_beta_init(&j.b, optics, sel, present);
    parallel_for((size_t)in->grid.n[2], 1, &j, beta_planes);
    return true;
}

void species_tint_defaults(struct species_tint *t)
{
    for (int f = 0; f < SPECIES_COUNT; f++)
        for (int c = 0; c < 3; c++)
            t->rgb[f][c] = 1.0f;
}

bool species_tint_is_white(const struct species_tint *t)
{
    for (int f = 0; f < SPECIES_COUNT; f++)
        for (int c = 0; c < 3; c++)
            if (t->rgb[f][c] != 1.0f)
                return false;
    return true;
}

static uint8_t unorm8(double v)
{
    v = v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
    return (uint8_t)(v * 255.0 + 0.5);
}

static uint8_t *alloc_tint(const struct grid3 *g)
{
    uint8_t *t = malloc(grid3_count(g) * 4);
    if (!t)
        log_error("out of memory for a %dx%dx%d tint volume", g->n[0], g->n[1], g->n[2]);
    return t;
}

bool ext_volume_tint_from_fields(const struct field_volume *in,
                                 const struct optics_params *optics,
                                 const struct species_select *sel,
                                 const struct species_tint *tint, struct ext_volume *out)
{
    free(out->tint);
    out->tint = NULL;
    if (!tint || species_tint_is_white(tint))
        return true;
    const struct grid3 *g = &in->grid;
    out->tint = alloc_tint(g);
    if (!out->tint)
        return false;
    size_t idx = 0;
    for (int k = 0; k < g->n[2]; k++) {
        double rho_std = optics_std_atmosphere_density(grid3_centre_z(g, k));
        for (int j = 0; j < g->n[1]; j++) {
            for (int i = 0; i < g->n[0]; i++, idx++) {
                double rho = in->rho_air ? in->rho_air[idx] : rho_std;
                if (!isfinite(rho) || rho < 0.0)
                    rho = rho_std;
                double sum = 0.0, rgb[3] = {0.0, 0.0, 0.0};
                for (int f = 0; f < SPECIES_COUNT; f++) {
                    if (!in->q[f] || (sel && !sel->enabled[f]))
                        continue;
                    double b = optics_beta(optics, (enum species)f, in->q[f][idx], rho);
                    if (sel)
                        b *= sel->scale[f];
                    if (!(b > 0.0) || !isfinite(b))
                        continue;
                    sum += b;
                    for (int c = 0; c < 3; c++)
                        rgb[c] += b * tint->rgb[f][c];
                }
                uint8_t *t = &out->tint[4 * idx];
                for (int c = 0; c < 3; c++)
                    t[c] = unorm8(sum > 0.0 ? rgb[c] / sum : 1.0);
                t[3] = 255;
            }
        }
    }
    return true;
}

double ext_volume_max_beta(const struct ext_volume *v)
{
    double m = 0.0;
    size_t n = grid3_count(&v->grid);
    for (size_t i = 0; i < n; i++) {
        double b = (double)v->beta[2 * i] + (double)v->beta[2 * i + 1];
        if (b > m)
            m = b;
    }
    return m;
}

void ext_volume_stretch_height(struct ext_volume *v, double k)
{
    assert(k > 0.0);
    if (k == 1.0)
        return;
    v->grid.origin[2] *= k;
    v->grid.spacing[2] *= k;
    for (int l = 0; l < v->grid.z_levels; l++)
        v->grid.z_centre[l] *= k;
    size_t plane = (size_t)v->grid.n[0] * (size_t)v->grid.n[1];
    for (int s = 0; s < TRANSFER_SLICE_MAX; s++)
        for (size_t i = 0; v->slice_surface[s] && i < plane; i++)
            v->slice_surface[s][i] *= (float)k;
    float inv = (float)(1.0 / k);
    size_t n = 2 * grid3_count(&v->grid);
    for (size_t i = 0; i < n; i++)
        v->beta[i] *= inv;
}
