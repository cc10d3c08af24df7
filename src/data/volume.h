/*
 * data/volume: the in-memory volumes every other part reads.  A field volume holds what the
 * weather model wrote (mass ratios per species, air density); an extinction volume holds what
 * the renderer needs (extinction per phase).  No GL, no files.
 *
 * World frame: metres, x east, y north, z up; the ground (sea level) is z = 0.  A volume is a
 * box from ORIGIN to ORIGIN + N * SPACING; voxel (i, j, k) is centred at
 * origin + (i + 0.5, j + 0.5, k + 0.5) * spacing; x varies fastest: index = i + n0 (j + n1 k).
 * A stretched grid (z_levels > 0: the model's own levels, docs/data.md "Heights") keeps the
 * box (origin[2] to origin[2] + n[2] spacing[2], spacing[2] the mean level thickness) but puts
 * the centre of level k at z_centre[k]; between centres values are linear in height, and
 * grid3_z_to_voxel is the one mapping from height to the continuous voxel coordinate that
 * every sampler (CPU and GPU) goes through.
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

/* Most levels a stretched grid holds (WRF runs use 30 to 100). */
#define GRID3_LEVELS_MAX 256

struct grid3 {
    int n[3];          /* voxels along x, y, z */
    double spacing[3]; /* metres; anisotropic in general; z: the mean on a stretched grid */
    double origin[3];  /* box minimum corner, metres */
    /* 0: uniform z.  Else n[2]: the heights of the level centres, increasing, strictly inside
     * the box; copied with the grid. */
    int z_levels;
    double z_centre[GRID3_LEVELS_MAX];
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

static inline bool grid3_stretched(const struct grid3 *g)
{
    return g->z_levels > 0;
}

/* Height Z (m) -> continuous voxel coordinate along z (0 at the box bottom, k + 0.5 at level
 * k's centre, n[2] at the top): (z - origin) / spacing on a uniform grid; on a stretched one
 * linear between the centres and between the outer centres and the box faces. */
double grid3_z_to_voxel(const struct grid3 *g, double z);
/* The inverse: the height of continuous voxel coordinate U, clamped to the box. */
double grid3_voxel_to_z(const struct grid3 *g, double u);
/* Height of level K's centre. */
double grid3_centre_z(const struct grid3 *g, int k);
/* The thickness of level K: half the distance between its neighbours' centres (the faces'
 * distance at the box's ends). */
double grid3_level_dz(const struct grid3 *g, int k);
/* The thinnest level's thickness (spacing[2] on a uniform grid). */
double grid3_min_dz(const struct grid3 *g);
/* The voxel levels [*K0, *K1] trilinear interpolation reads anywhere in heights [Z0, Z1]
 * (clamped to the volume). */
void grid3_z_voxel_range(const struct grid3 *g, double z0, double z1, int *k0, int *k1);
/* Makes G stretched with N levels centred at ZC (increasing) in the box [BOTTOM, TOP].  False
 * (logged, G unchanged) when they do not fit: more than GRID3_LEVELS_MAX, not increasing, or
 * not strictly inside the box. */
bool grid3_set_levels(struct grid3 *g, const double *zc, int n, double bottom, double top);
/* Whether A and B are the same grid (the same levels too). */
bool grid3_equal(const struct grid3 *a, const struct grid3 *b);

/* The GPU's and the CPU light map's height mapping (shaders/zmap.glsl): ENTRIES values of
 * grid3_z_to_voxel / n[2] at heights origin + i / (ENTRIES - 1) of the box height, and each
 * height's level thickness.  grid3_zmap_entries says how many resolve the thinnest level (at
 * least 16 entries to it), 2 on a uniform grid. */
int grid3_zmap_entries(const struct grid3 *g);
/* Fills TEX (ENTRIES floats) and DZ (ENTRIES floats, m; NULL: not wanted). */
void grid3_zmap_fill(const struct grid3 *g, int entries, float *tex, float *dz);

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
    float *pressure;         /* air pressure, Pa, or NULL: CM1's and CF's where asked for (the
                                probe) and in the file */
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

/* ext_volume_from_fields' sum, set up once (ext_beta_init) and run on any run of voxels
 * (ext_beta_run), for a reader that makes a step's fields a slab at a time and never holds
 * them whole (wrf_read_step_ext): the same operations in the same order, so the same
 * numbers. */
struct ext_beta {
    int used;                    /* species that add extinction */
    int species[SPECIES_COUNT];  /* which, in species order */
    double denom[SPECIES_COUNT]; /* 2 rho_f r_f of each (Nes eq. 5.3) */
    double scale[SPECIES_COUNT];
    bool ice[SPECIES_COUNT], scaled;
};

/* The species PRESENT marks (held by the fields), SEL enables (NULL: all, unscaled) and OPTICS
 * gives a positive density and radius. */
void ext_beta_init(struct ext_beta *b, const struct optics_params *optics,
                   const struct species_select *sel, const bool present[SPECIES_COUNT]);

/* BETA (ice, water pairs) of N voxels from Q[u], the mass ratios of B's u-th species, and the
 * air density RHO_AIR (NULL, or where not finite or negative: RHO_STD). */
void ext_beta_run(const struct ext_beta *b, const float *const *q, const float *rho_air,
                  double rho_std, size_t n, float *beta);

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

/* Height exaggeration (Nes §5.5.2): multiplies the z origin and spacing (and the level
 * centres, and the slices' surfaces) by K (> 0) and divides
 * the extinction by K, so the volume is K times taller and every vertical column keeps its
 * optical depth (the stretch moves the medium, it does not add any).  K = 1 leaves V as is. */
void ext_volume_stretch_height(struct ext_volume *v, double k);

/* Largest extinction (sum of both phases) in the volume, 1/m. */
double ext_volume_max_beta(const struct ext_volume *v);

#endif
