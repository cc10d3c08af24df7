/*
 * bench/scenes: the scenes the benchmarks measure, made from configs.  A named scene is a
 * config file in a folder the caller names (or the built-in defaults) plus overrides:
 *
 *  - "sphere": CONFIGS/sphere.cfg, a homogeneous ball;
 *  - "storm": the built-in procedural storm (smaller, with a smaller light map, when quick);
 *  - "katrina": CONFIGS/katrina.cfg, the WRF sample, whose data file the config names
 *    relative to itself.
 *
 * bench_scene_prepare turns any config into the volume and the struct bench_scene that anvil
 * render would draw: the config's camera and sun, the effects decided from the scene as for
 * one time step (session/effects.h).  No GL.  The only files read are the configs and the data
 * they name; where the configs folder is, is the caller's to say.
 */
#ifndef ANVIL_BENCH_SCENES_H
#define ANVIL_BENCH_SCENES_H

#include <stdbool.h>

#include "bench/bench.h"
#include "config/config.h"
#include "data/volume.h"

#define BENCH_MAX_SCENES 3

/* The named scenes, in the order a run measures them when none is asked for. */
extern const char *const bench_scene_names[BENCH_MAX_SCENES];

/* Whether NAME is one of bench_scene_names. */
bool bench_scene_known(const char *name);

/* The config of the named scene NAME: its file in CONFIGS_DIR (none for the storm), the quick
 * run's smaller storm when QUICK, then the N_SETS overrides SETS ("path=value", as --set).
 * False (logged) on an unreadable or invalid config. */
bool bench_scene_config(const char *name, const char *configs_dir, bool quick, char **sets,
                        int n_sets, struct config *cfg);

/* The first of CFG's data files (scene.kind = "data") that cannot be read, or NULL when every
 * one can (or the scene has none).  The pointer is into CFG. */
const char *bench_scene_missing_data(const struct config *cfg);

/* The scene CFG describes, as anvil render draws it (effects decided from the scene) at W x H,
 * named NAME: builds the volume into VOL (the caller finishes it, also on failure) and fills
 * SC, which borrows VOL.  False (logged) when the volume cannot be built or measured. */
bool bench_scene_prepare(const char *name, const struct config *cfg, int w, int h,
                         struct ext_volume *vol, struct bench_scene *sc);

#endif
