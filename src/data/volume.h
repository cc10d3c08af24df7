/*
 * data/volume: the in-memory volumes every other part reads.  A field volume holds what the
 * weather model wrote (mass ratios per species, air density); an extinction volume holds what
 * the renderer needs (extinction per phase).  No GL, no files.
 *
 * World frame: metres, x east, y north, z up; the ground (sea level) is z = 0.  A volume is a
 * box from ORIGIN to ORIGIN + N * SPACING; voxel (i, j, k) is centred at
 * origin + (i + 0.5, j + 0.5, k + 0.5) * spacing; x varies fastest: index = i + n0 (j + n1 k).
 */
#ifndef ANVIL_DATA_VOLUME_H
#define ANVIL_DATA_VOLUME_H

#include <stdbool.h>
#include <stddef.h>

#include "optics/optics.h"

struct grid3 {
    int n[3];          /* voxels along x, y, z */
    double spacing[3]; /* metres; anisotropic in general */
    double origin[3];  /* box minimum corner, metres */
};

static inline size_t grid3_count(const struct grid3 *g)
{
    return (size_t)g->n[0] * (size_t)g->n[1] * (size_t)g->n[2];
}

static inline size_t grid3_index(const struct grid3 *g, int i, int j, int k)
{
    return (size_t)i + (size_t)g->n[0] * ((size_t)j + (size_t)g->n[1] * (size_t)k);
}

/* Mass ratios as the model wrote them.  A species the data lacks has q[f] == NULL and reads
 * as zero.  rho_air == NULL means "use the standard atmosphere at the voxel's height". */
struct field_volume {
    struct grid3 grid;
    float *q[SPECIES_COUNT]; /* kg/kg, grid3_count values each, or NULL */
    float *qvapor;           /* kg/kg or NULL */
    float *rho_air;          /* kg/m^3 or NULL */
};

/* Extinction per phase: beta[2 i] scatters with the ice phase (ice + snow + graupel),
 * beta[2 i + 1] with the water phase (cloud + rain); 1/m. */
struct ext_volume {
    struct grid3 grid;
    float *beta;
};

/* Frees the arrays and zeroes the struct; NULL and zeroed structs are fine. */
void field_volume_finish(struct field_volume *v);
void ext_volume_finish(struct ext_volume *v);

/* Allocates a zero-filled extinction volume on GRID.  Returns false (logged) when out of
 * memory. */
bool ext_volume_init(struct ext_volume *v, const struct grid3 *grid);

/* Per-species selection and scale applied when converting mass ratios to extinction. */
struct species_select {
    bool enabled[SPECIES_COUNT];
    double scale[SPECIES_COUNT];
};
void species_select_defaults(struct species_select *s); /* all on, scale 1 */

/* Converts mass ratios to extinction (Nes eq. 5.3-5.4) on the same grid.  Air density from
 * the volume where present, else the standard atmosphere at the voxel centre's height.
 * OUT is initialised here (caller finishes it). */
bool ext_volume_from_fields(const struct field_volume *in, const struct optics_params *optics,
                            const struct species_select *sel, struct ext_volume *out);

/* Largest extinction (sum of both phases) in the volume, 1/m. */
double ext_volume_max_beta(const struct ext_volume *v);

#endif
