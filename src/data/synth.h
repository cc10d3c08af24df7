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

/* Largest synthetic grid, voxels per axis (every kind). */
#define SYNTH_MAX_NXY 500
#define SYNTH_MAX_NZ 100

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

/* The default scene: the storm on 128x128x64 voxels over 60 x 60 x 16 km, seed 1, time 0.5,
 * tau 10 with the water phase for the test scenes. */
void synth_desc_defaults(struct synth_desc *d);

/* The procedural storm as mass ratios of all five species (rho_air and qvapor left NULL:
 * standard atmosphere) on the grid with origin (0, 0, 0) and spacing extent / n.  Heights are
 * physical (cloud base 1.5 km, tower top 9.5-12.5 km, anvil 8.6-12.2 km); horizontal sizes
 * scale with min(extent_x, extent_y) / 60 km.  OUT is initialised here and the caller
 * finishes it with field_volume_finish.  Returns false (logged) on a bad description
 * (size above SYNTH_MAX_*, extent not positive, time outside [0, 1]) or out of memory. */
bool synth_storm_fields(const struct synth_desc *d, struct field_volume *out);

/* As synth_storm_fields with THREADS worker threads over z slices: 0 = one per online CPU,
 * 1 = the calling thread only.  The result does not depend on THREADS. */
bool synth_storm_fields_threads(const struct synth_desc *d, int threads,
                                struct field_volume *out);

/* Any scene as extinction: the storm converted with OPTICS (all species on; NULL means
 * optics_params_defaults), the test scenes built directly so their optical depth is exact
 * (OPTICS unused).  Grid origin (0, 0, 0), spacing extent / n.  OUT is initialised here and
 * the caller finishes it.  Returns false (logged) on a bad description or out of memory.
 * The test scenes (docs/scenes.md):
 *   slab:   beta = tau / extent_z in every voxel;
 *   sphere: ball at the box centre, radius R = min(extent) / 2, beta = tau / (2 R) times the
 *           fraction of the voxel inside the ball (4x4x4 supersampling on the surface);
 *   empty:  all zero;
 *   voxel:  only voxel (n/2, n/2, n/2) (integer division), beta = tau / spacing_z.
 * ICE_PHASE puts the medium in beta[2 i] (ice phase), else in beta[2 i + 1] (water phase). */
bool synth_extinction(const struct synth_desc *d, const struct optics_params *optics,
                      struct ext_volume *out);

#endif
