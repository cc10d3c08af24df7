#include "data/volume.h"

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
    free(v->rho_air);
    memset(v, 0, sizeof(*v));
}

void ext_volume_finish(struct ext_volume *v)
{
    if (!v)
        return;
    free(v->beta);
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
