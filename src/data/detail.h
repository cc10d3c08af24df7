/*
 * data/detail: procedural detail (Riley §4.5).  Storm-scale models lack the medium-scale
 * turbulence that gives clouds their texture, so a user-adjustable share of each species'
 * field is multiplied by noise: billowing (rounded, puffy) for cloud and graupel, wispy
 * (stretched horizontally, ridged) for ice and snow, streaky (stretched vertically) for rain.
 *
 * It runs on the CPU when mass ratios become extinction, so the light map and the eye pass see
 * the same detailed volume for free; it is seeded and deterministic (the noise is a function of
 * the world position and the seed only).  Off costs nothing: the pass is skipped.  Detail can
 * only be as fine as the voxels: features smaller than two voxels alias into per-voxel noise.
 * No GL, no files.
 */
#ifndef ANVIL_DATA_DETAIL_H
#define ANVIL_DATA_DETAIL_H

#include <stdbool.h>

#include "data/volume.h"

struct detail_desc {
    bool on;                      /* false: nothing is touched */
    double amount[SPECIES_COUNT]; /* share of the field modulated, [0, 1]; 0 = untouched */
    double scale_m;               /* wavelength of the coarsest octave, metres (> 0) */
    unsigned seed;
};

/* The factor a species' field is multiplied by at world point P (metres):
 * 1 + amount (2 n - 1), n in [0, 1] the species' noise, never below 0.  Its mean over space is
 * close to 1, so detail moves mass around rather than adding it. */
double detail_factor(const struct detail_desc *d, enum species f, const double p[3]);

/* Multiplies every present species of V by its factor (voxel centres). */
void detail_apply_fields(const struct detail_desc *d, struct field_volume *v);

/* For extinction volumes, where the species are summed: the ice-phase channel takes ice's
 * noise and amount, the water-phase channel cloud's. */
void detail_apply_ext(const struct detail_desc *d, struct ext_volume *v);

#endif
