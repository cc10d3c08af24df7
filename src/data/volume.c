#include "data/volume.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

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
    free(v->rho_air);
    memset(v, 0, sizeof(*v));
}

void ext_volume_finish(struct ext_volume *v)
{
    if (!v)
        return;
    free(v->beta);
    free(v->tint);
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

bool ext_volume_from_fields(const struct field_volume *in, const struct optics_params *optics,
                            const struct species_select *sel, struct ext_volume *out)
{
    if (!ext_volume_init(out, &in->grid))
        return false;
    const struct grid3 *g = &in->grid;
    size_t idx = 0;
    for (int k = 0; k < g->n[2]; k++) {
        double z = g->origin[2] + (k + 0.5) * g->spacing[2];
        double rho_std = optics_std_atmosphere_density(z);
        for (int j = 0; j < g->n[1]; j++) {
            for (int i = 0; i < g->n[0]; i++, idx++) {
                double rho = in->rho_air ? in->rho_air[idx] : rho_std;
                if (!isfinite(rho) || rho < 0.0)
                    rho = rho_std;
                double ice = 0.0, water = 0.0;
                for (int f = 0; f < SPECIES_COUNT; f++) {
                    if (!in->q[f] || (sel && !sel->enabled[f]))
                        continue;
                    double b = optics_beta(optics, (enum species)f, in->q[f][idx], rho);
                    if (sel)
                        b *= sel->scale[f];
                    if (species_is_ice((enum species)f))
                        ice += b;
                    else
                        water += b;
                }
                out->beta[2 * idx] = (float)ice;
                out->beta[2 * idx + 1] = (float)water;
            }
        }
    }
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

bool ext_volume_from_scalar(const struct grid3 *grid, const float *scalar, const float *lut,
                            int n, double lo, double hi, double density,
                            struct ext_volume *out)
{
    if (!ext_volume_init(out, grid))
        return false;
    out->tint = alloc_tint(grid);
    if (!out->tint) {
        ext_volume_finish(out);
        return false;
    }
    size_t count = grid3_count(grid);
    double span = hi - lo;
    for (size_t i = 0; i < count; i++) {
        double s = scalar ? scalar[i] : 0.0;
        double x = span > 0.0 && isfinite(s) ? (s - lo) / span : 0.0;
        x = x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x;
        int e = (int)(x * (n - 1) + 0.5);
        const float *c = &lut[4 * e];
        out->beta[2 * i] = 0.0f;
        out->beta[2 * i + 1] = (float)(c[3] * density);
        for (int k = 0; k < 3; k++)
            out->tint[4 * i + k] = unorm8(c[k]);
        out->tint[4 * i + 3] = 255;
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
    float inv = (float)(1.0 / k);
    size_t n = 2 * grid3_count(&v->grid);
    for (size_t i = 0; i < n; i++)
        v->beta[i] *= inv;
}
