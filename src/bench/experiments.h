/*
 * bench/experiments: physics experiments with one exact answer per direction, the renderer at
 * its default settings against the Monte Carlo reference (docs/accuracy.md):
 *
 *  - the plane-parallel layer seen from every side: a uniform water cloud layer of optical
 *    depth 20 (480 x 480 x 2 km, the slab test scene) lit like the Katrina sample (azimuth 120
 *    degrees, elevation 40), looked at through an 8 degree field from each of
 *    bench_layer_elevations and each of bench_layer_azimuths relative to the sun's: how well
 *    the model gets the angular distribution of the light a cloud top reflects;
 *  - the uniform wall under four suns: a box 2 km thick, 60 km long and 10 km high of the same
 *    cloud (optical depth 20 across), its long face toward the sun's azimuth, seen square-on
 *    from 50 km at 10 degrees of elevation with the sun behind the camera, under each of
 *    bench_wall_elevations.  Every light column is solved as a layer lit at the sun's
 *    elevation, a deck's slant and not a wall's: what that costs a tower's sunlit side.
 *
 * Each scene is a config made of overrides of the built-in defaults.  Needs the GL context
 * current.  It knows nothing of tables or files but the reference cache.
 */
#ifndef ANVIL_BENCH_EXPERIMENTS_H
#define ANVIL_BENCH_EXPERIMENTS_H

#include <stdbool.h>

#include "light/light_gpu.h"
#include "render/render.h"

#define BENCH_LAYER_ELEVATIONS 4
#define BENCH_LAYER_AZIMUTHS 4
#define BENCH_WALL_SUNS 4

/* Degrees: the camera's elevation, its azimuth relative to the sun's (0: the sun behind the
 * camera, 180: the camera facing the sun), the wall's sun elevations. */
extern const double bench_layer_elevations[BENCH_LAYER_ELEVATIONS];
extern const double bench_layer_azimuths[BENCH_LAYER_AZIMUTHS];
extern const double bench_wall_elevations[BENCH_WALL_SUNS];

/* One picture against its reference. */
struct bench_angle_result {
    double model, traced, sigma; /* means over pixels and channels; sigma: of the traced mean */
    double scattering_deg;       /* between the sunlight and the light heading to the camera
                                    (0 for the wall) */
};

struct bench_angles {
    struct bench_angle_result layer[BENCH_LAYER_ELEVATIONS][BENCH_LAYER_AZIMUTHS];
    struct bench_angle_result wall[BENCH_WALL_SUNS];
};

/* The CPU times of the diffuse light volume's pictures (bench_volume_image), summed. */
struct bench_volume_timing {
    double map_ms;    /* the light map's CPU build, with the columns' diffuse pass */
    double volume_ms; /* the diffuse light volume's build on top of it */
    int builds;
    int iterations;   /* the solves' conjugate gradient iterations, summed */
};

/* How the experiments are run: QUICK halves the images (16 x 12 instead of 32 x 24) and the
 * wall's grid; SPP reference samples per pixel; references cached in CACHE_DIR.  CPU_VOLUME:
 * the model's pictures come from bench_volume_image (the diffuse light volume, CPU only; the
 * renderer and light map arguments may be NULL), whose times add up in TIMING (may be NULL).
 * VOLUME: the renderer draws with effects.multiple = "volume" (else its default). */
struct bench_experiments_desc {
    bool quick;
    int spp;
    const char *cache_dir;
    bool cpu_volume;
    bool volume;
    struct bench_volume_timing *timing;
};

struct bench_scene;
struct image;

/* The picture of SC with the diffuse light of the 3-D volume (light/light_volume.h) in place
 * of the light map's columns, drawn on the CPU (bench/volume_cpu.c): the CPU light map of SC's
 * settings, the volume over it, and a fine ray march through both that scatters the sun's
 * P_v(psi) L and the volume's max(phi + 3 g F.w, 0) toward the eye, as the eye pass does with
 * the columns'.  OUT is initialised here; times add to TIMING (may be NULL).  No GL. */
bool bench_volume_image(const struct bench_scene *sc, struct image *out,
                        struct bench_volume_timing *timing);

/* The CPU builds of the default storm (the quick run's smaller one when QUICK; CONFIGS as
 * bench_scene_config's) at its default light map: the light map with the columns' diffuse
 * pass, then the diffuse light volume over it, once each, into OUT; the volume's cells into
 * CELLS.  False (logged) on failure.  No GL. */
bool bench_volume_time_storm(const char *configs, bool quick, struct bench_volume_timing *out,
                             int cells[3]);

/* Runs the layer from every direction, then the wall under every sun, into OUT.  R and LG are
 * the caller's; R's volume and optics are replaced.  Progress goes to the log.  False
 * (logged) on the first failure. */
bool bench_angles_measure(struct renderer *r, struct light_gpu *lg,
                          const struct bench_experiments_desc *d, struct bench_angles *out);

#endif
