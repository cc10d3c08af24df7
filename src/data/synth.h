/*
 * data/synth: synthetic scenes that need no files.  The procedural storm (all five species: a
 * cumulus tower with a cirrus anvil of ice and snow, rain and graupel below) as mass ratios,
 * and the test scenes (slab, sphere, empty, single voxel) directly as extinction.
 * Deterministic for a given description.  No GL.
 */
#ifndef ANVIL_DATA_SYNTH_H
#define ANVIL_DATA_SYNTH_H

#include <stdbool.h>

#include "data/volume.h"

enum synth_kind { SYNTH_STORM, SYNTH_SLAB, SYNTH_SPHERE, SYNTH_EMPTY, SYNTH_VOXEL };

struct synth_desc {
    enum synth_kind kind;
    int n[3];            /* voxels */
    double extent_m[3];  /* physical size, metres; the box sits on the ground (origin z = 0) */
    double tau;          /* test scenes: optical depth (slab: vertical; sphere: diameter;
                            voxel: vertical through the voxel) */
    bool ice_phase;      /* test scenes: medium scatters with the ice phase, else water */
    unsigned seed;       /* storm: random seed */
    double time;         /* storm: evolution in [0, 1] (grows, drifts) */
};

/* The procedural storm as mass ratios (rho_air left NULL: standard atmosphere).
 * Returns false (logged) on allocation failure or a size above 500x500x100. */
bool synth_storm_fields(const struct synth_desc *d, struct field_volume *out);

/* Any scene as extinction: the storm converted with OPTICS (all species on), the test scenes
 * built directly so their optical depth is exact. */
bool synth_extinction(const struct synth_desc *d, const struct optics_params *optics,
                      struct ext_volume *out);

#endif
