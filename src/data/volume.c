#include "data/volume.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "common/parallel.h"

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

/* ext_volume_from_fields over planes [begin, end): optics_beta with its constant part taken
 * out of the loop, the same operations in the same order, so the same numbers. */
struct beta_job {
    const struct field_volume *in;
    const float *q[SPECIES_COUNT];
    double denom[SPECIES_COUNT], scale[SPECIES_COUNT];
    bool ice[SPECIES_COUNT], scaled;
    int used;
    float *beta;
};

static bool beta_planes(void *ctx, int share, size_t begin, size_t end)
{
    const struct beta_job *j = ctx;
    const struct grid3 *g = &j->in->grid;
    const float *rho_air = j->in->rho_air;
    size_t plane = (size_t)g->n[0] * (size_t)g->n[1];
    for (size_t k = begin; k < end; k++) {
        double z = g->origin[2] + ((double)k + 0.5) * g->spacing[2];
        double rho_std = optics_std_atmosphere_density(z);
        for (size_t idx = plane * k; idx < plane * (k + 1); idx++) {
            double rho = rho_air ? rho_air[idx] : rho_std;
            if (!isfinite(rho) || rho < 0.0)
                rho = rho_std;
            double sum[2] = {0.0, 0.0}; /* ice, water */
            for (int u = 0; u < j->used && rho > 0.0; u++) {
                double x = j->q[u][idx];
                if (!(x > 0.0) || !isfinite(x))
                    continue;
                double b = 3.0 * rho * x / j->denom[u]; /* Nes eq. 5.3 */
                if (j->scaled)
                    b *= j->scale[u];
                sum[j->ice[u] ? 0 : 1] += b;
            }
            j->beta[2 * idx] = (float)sum[0];
            j->beta[2 * idx + 1] = (float)sum[1];
        }
    }
    return true;
}

bool ext_volume_from_fields(const struct field_volume *in, const struct optics_params *optics,
                            const struct species_select *sel, struct ext_volume *out)
{
    if (!ext_volume_init(out, &in->grid))
        return false;
    struct beta_job j = {.in = in, .scaled = sel != NULL, .beta = out->beta};
    for (int f = 0; f < SPECIES_COUNT; f++) {
        double dn = 2.0 * optics->density[f] * optics->radius_m[f];
        if (!in->q[f] || (sel && !sel->enabled[f]) || !(dn > 0.0))
            continue;
        j.q[j.used] = in->q[f];
        j.denom[j.used] = dn;
        j.scale[j.used] = sel ? sel->scale[f] : 1.0;
        j.ice[j.used] = species_is_ice((enum species)f);
        j.used++;
    }
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
        double rho_std = optics_std_atmosphere_density(g->origin[2] + (k + 0.5) * g->spacing[2]);
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
    size_t plane = (size_t)v->grid.n[0] * (size_t)v->grid.n[1];
    for (int s = 0; s < TRANSFER_SLICE_MAX; s++)
        for (size_t i = 0; v->slice_surface[s] && i < plane; i++)
            v->slice_surface[s][i] *= (float)k;
    float inv = (float)(1.0 / k);
    size_t n = 2 * grid3_count(&v->grid);
    for (size_t i = 0; i < n; i++)
        v->beta[i] *= inv;
}
