#include "data/detail.h"

#include <math.h>
#include <stdint.h>

#define STB_PERLIN_IMPLEMENTATION
#include <stb_perlin.h>

#define OCTAVES 3

enum noise_style { BILLOW, WISPY, STREAKY };

static enum noise_style style_of(enum species f)
{
    switch (f) {
    case SPECIES_ICE:
    case SPECIES_SNOW:
        return WISPY;
    case SPECIES_RAIN:
        return STREAKY;
    default:
        return BILLOW;
    }
}

/* A well-mixed 32-bit hash (for per-seed, per-species offsets). */
static uint32_t hash32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

/* Noise in [0, 1] of STYLE at point Q (in units of the coarsest wavelength). */
static double noise(enum noise_style style, const double q[3], int seed8)
{
    double sum = 0.0, norm = 0.0, amp = 1.0, freq = 1.0;
    for (int o = 0; o < OCTAVES; o++) {
        float n = stb_perlin_noise3_seed((float)(q[0] * freq), (float)(q[1] * freq),
                                         (float)(q[2] * freq), 0, 0, 0, seed8 + o);
        double v;
        switch (style) {
        case BILLOW:
            v = fabs(n); /* creases between rounded puffs */
            break;
        case WISPY: {
            double r = 1.0 - fabs(n); /* thin ridges: strands */
            v = r * r * r;
            break;
        }
        default:
            v = 0.5 + 0.5 * n;
            break;
        }
        sum += amp * v;
        norm += amp;
        amp *= 0.5;
        freq *= 2.0;
    }
    double v = sum / norm;
    /* Stretch each style's typical range onto [0, 1]. */
    switch (style) {
    case BILLOW:
        v = v / 0.5;
        break;
    case WISPY:
        v = (v - 0.1) / 0.6;
        break;
    default:
        v = (v - 0.25) / 0.5;
        break;
    }
    return v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
}

static double species_noise(const struct detail_desc *d, enum species f, const double p[3])
{
    enum noise_style style = style_of(f);
    /* Wisps are long across and thin up; rain streaks the other way. */
    static const double stretch[3][3] = {{1, 1, 1}, {3, 1.5, 0.25}, {0.7, 0.7, 4}};
    uint32_t h = hash32(d->seed * 2654435761U + (uint32_t)f * 97U + 1U);
    double off[3] = {(h & 1023) * 0.37, ((h >> 10) & 1023) * 0.41, ((h >> 20) & 1023) * 0.43};
    double q[3];
    for (int a = 0; a < 3; a++)
        q[a] = p[a] / (d->scale_m * stretch[style][a]) + off[a];
    return noise(style, q, (int)(hash32(d->seed) & 0xff));
}

double detail_factor(const struct detail_desc *d, enum species f, const double p[3])
{
    double a = d->amount[f];
    if (!d->on || !(a > 0.0))
        return 1.0;
    double m = 1.0 + a * (2.0 * species_noise(d, f, p) - 1.0);
    return m > 0.0 ? m : 0.0;
}

static void voxel_centre(const struct grid3 *g, int i, int j, int k, double p[3])
{
    p[0] = g->origin[0] + (i + 0.5) * g->spacing[0];
    p[1] = g->origin[1] + (j + 0.5) * g->spacing[1];
    p[2] = grid3_centre_z(g, k);
}

void detail_apply_fields(const struct detail_desc *d, struct field_volume *v)
{
    if (!d->on)
        return;
    const struct grid3 *g = &v->grid;
    for (int f = 0; f < SPECIES_COUNT; f++) {
        float *q = v->q[f];
        if (!q || !(d->amount[f] > 0.0))
            continue;
        for (int k = 0; k < g->n[2]; k++) {
            for (int j = 0; j < g->n[1]; j++) {
                for (int i = 0; i < g->n[0]; i++) {
                    size_t idx = grid3_index(g, i, j, k);
                    if (!(q[idx] > 0.0f)) /* empty air stays empty, and costs nothing */
                        continue;
                    double p[3];
                    voxel_centre(g, i, j, k, p);
                    q[idx] = (float)(q[idx] * detail_factor(d, (enum species)f, p));
                }
            }
        }
    }
}

void detail_apply_ext(const struct detail_desc *d, struct ext_volume *v)
{
    if (!d->on)
        return;
    const struct grid3 *g = &v->grid;
    const enum species channel[2] = {SPECIES_ICE, SPECIES_CLOUD};
    for (int c = 0; c < 2; c++) {
        if (!(d->amount[channel[c]] > 0.0))
            continue;
        for (int k = 0; k < g->n[2]; k++) {
            for (int j = 0; j < g->n[1]; j++) {
                for (int i = 0; i < g->n[0]; i++) {
                    float *b = &v->beta[2 * grid3_index(g, i, j, k) + c];
                    if (!(*b > 0.0f))
                        continue;
                    double p[3];
                    voxel_centre(g, i, j, k, p);
                    *b = (float)(*b * detail_factor(d, channel[c], p));
                }
            }
        }
    }
}
