/*
 * data/volume: the in-memory volumes every other part reads.  A field volume holds what the
 * weather model wrote (mass ratios per species, air density); an extinction volume holds what
 * the renderer needs (extinction per phase).  No GL, no files.
 *
 * World frame: metres, x east, y north, z up; the ground (sea level) is z = 0.  A volume is a
 * box from ORIGIN to ORIGIN + N * SPACING; voxel (i, j, k) is centred at
 * origin + (i + 0.5, j + 0.5, k + 0.5) * spacing; x varies fastest: index = i + n0 (j + n1 k).
 *
 * Must not know: GL, configs (callers fill the desc structs), views, the session.
 */
#ifndef ANVIL_DATA_VOLUME_H
#define ANVIL_DATA_VOLUME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "optics/optics.h"
#include "optics/transfer.h"

struct grid3 {
    int n[3];          /* voxels along x, y, z */
    double spacing[3]; /* metres; anisotropic in general */
    double origin[3];  /* box minimum corner, metres */
};

/* What a file's grid may be: outside these it is refused as damaged (a DX of 1e-30 m once
 * made a 188 M-vertex mesh).  Spacing along any axis and heights above sea level, m: a large
 * eddy simulation's decimetres to a global model's 1000 km; the Dead Sea shore to the top of
 * the height grid data.top may ask for. */
#define DATA_SPACING_MIN_M 0.1
#define DATA_SPACING_MAX_M 1.0e6
#define DATA_HEIGHT_MIN_M (-1000.0)
#define DATA_HEIGHT_MAX_M 100000.0

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
    float *temperature;      /* absolute air temperature, K, or NULL */
    float *wind;             /* wind speed |(U, V, W)| at the mass points, m/s, or NULL */
    float *u, *v, *w;        /* the wind's components at the mass points, m/s: u east, v north,
                                w up; NULL unless asked for (the probe's direction) and in the
                                data (w: NULL where the data has no vertical wind); WRF's are
                                grid-relative (along the map's x and y) */
    float *vorticity;        /* vertical vorticity dv/dx - du/dy, 1/s, or NULL: WRF's, from its
                                staggered U and V on the model levels (data/derived.h) */
    float *rho_air;          /* kg/m^3 or NULL */
    /* The model's own levels where it has terrain-following ones (WRF): the height above sea
     * level of mass level k (0 the lowest) at column (i, j), level_z[i + n0 (j + n1 k)], m,
     * for k < LEVEL_COUNT; NULL unless asked for.  On height-level data the grid's levels are
     * the model's. */
    float *level_z;
    int level_count;
};

/* Extinction per phase: beta[2 i] scatters with the ice phase (ice + snow + graupel),
 * beta[2 i + 1] with the water phase (cloud + rain); 1/m. */
struct ext_volume {
    struct grid3 grid;
    float *beta;
    uint8_t *tint; /* NULL (white), or RGBA8 per voxel: the colour the scattered light takes
                      (the beta-weighted species tints) */
    /* The look's colour-mapped layers (optics/transfer.h): layer i's scalar field, grid3_count
     * values, or NULL; LAYER_FIELD[i] says which field it is (classified on the GPU). */
    float *layer[TRANSFER_LAYER_MAX];
    enum transfer_field layer_field[TRANSFER_LAYER_MAX];
    /* The look's slices' fields, likewise. */
    float *slice[TRANSFER_SLICE_MAX];
    enum transfer_field slice_field[TRANSFER_SLICE_MAX];
    /* A slice that follows a model level (transfer_slice.level): that level's height at each
     * column, n[0] * n[1] values (world z, metres, x fastest), or NULL. */
    float *slice_surface[TRANSFER_SLICE_MAX];
    struct transfer_histogram *histogram; /* NULL, or owned: the values of the look's transfer
                                             field of the step it was made from */
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

/* Per-species tints (linear RGB in [0, 1]); white everywhere means no tint. */
struct species_tint {
    float rgb[SPECIES_COUNT][3];
};
void species_tint_defaults(struct species_tint *t); /* all white */
bool species_tint_is_white(const struct species_tint *t);

/* Adds OUT->tint (allocated here): per voxel the beta-weighted mean of the tints of the
 * species that IN holds, with the same selection and scales as ext_volume_from_fields.
 * White tints leave OUT->tint NULL.  Returns false (logged) when out of memory. */
bool ext_volume_tint_from_fields(const struct field_volume *in,
                                 const struct optics_params *optics,
                                 const struct species_select *sel,
                                 const struct species_tint *tint, struct ext_volume *out);

/* Height exaggeration (Nes §5.5.2): multiplies the z origin and spacing (and the slices'
 * surfaces) by K (> 0) and divides
 * the extinction by K, so the volume is K times taller and every vertical column keeps its
 * optical depth (the stretch moves the medium, it does not add any).  K = 1 leaves V as is. */
void ext_volume_stretch_height(struct ext_volume *v, double k);

/* Largest extinction (sum of both phases) in the volume, 1/m. */
double ext_volume_max_beta(const struct ext_volume *v);

#endif
