/*
 * app: the command line, the main loop and the wiring between parts.  This file gathers what
 * the commands share: turning a config into a volume, lighting settings and a camera, and
 * the --stats report.
 */
#ifndef ANVIL_APP_H
#define ANVIL_APP_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "app/effects.h"
#include "config/config.h"
#include "data/volume.h"
#include "render/render.h"

/* Exit codes of the program (documented in docs/user-guide.md). */
enum {
    EXIT_OK = 0,
    EXIT_BAD_INPUT = 1, /* a config, data file or option value is wrong */
    EXIT_USAGE = 2,     /* the command line itself is wrong */
    EXIT_NO_GPU = 3,    /* no OpenGL 4.5 context could be made */
    EXIT_FAILED = 4,    /* the work failed for another reason (out of memory, write error) */
};

/* Loads CONFIG_PATH (or the built-in defaults when NULL) and applies the --set overrides. */
bool app_load_config(const char *config_path, char **sets, int n_sets, struct config *cfg);

/* Builds the volume the config describes as extinction. */
bool app_build_volume(const struct config *cfg, struct ext_volume *out);

/* Time steps the config's scene has: 1 for synthetic scenes, the data files' count for data
 * (0 when they cannot be opened; the reason is logged). */
int app_time_steps(const struct config *cfg);

/* The sun's transmittance through a clear atmosphere at ELEVATION_DEG, per R, G, B, relative to
 * the sun overhead (light.atmosphere; an approximation, docs/terrain.md). */
void app_sun_transmittance(double elevation_deg, double rgb[3]);

/* Lighting and background from the config. */
void app_render_settings(const struct config *cfg, struct render_settings *s);

/* The config's camera at WIDTH x HEIGHT. */
void app_camera_view(const struct config *cfg, int width, int height, struct render_view *view);

/* What a run did, written by --stats FILE.json. */
struct app_stats {
    const char *command;
    const char *device;
    unsigned views;
    unsigned light_builds;
    /* The times of the timed views and light map builds (view_ms and build_ms in the file),
     * lent to the renderer and the light map (renderer_set_timing, app_light_set_timing);
     * they arrive frames later, so collect them all before writing. */
    struct gpu_timings view_times, build_times;
    double light_bytes_dense, light_bytes_compressed;
    size_t gpu_bytes;
    size_t nonfinite_pixels;
    double volume_ms, upload_ms, total_ms;
    /* Playback (anvil run, app/interact.h): the time series cache and the frames. */
    unsigned frames;          /* frames drawn */
    int time_step;            /* the time step on screen at the end */
    unsigned cache_hits, cache_misses, cache_loads;
    unsigned frames_waited;   /* frames that blocked on a load (only a scripted run's end) */
    unsigned frames_stale;    /* frames that showed an older step: the wanted one was loading */
    unsigned volume_uploads;  /* volumes uploaded after the first (with effects.temporal
                                 also each next step's, into the second texture) */
    double load_ms, convert_ms, wait_ms, upload_ms_total;
    double frame_ms_max;      /* longest frame of the loop */
};

/* Counts a view drawn and a light map built; their times go to view_times and build_times. */
void app_stats_add_view(struct app_stats *st);
void app_stats_add_build(struct app_stats *st);
/* Writes ST as JSON to PATH (atomically).  A time that has not arrived is written as null. */
bool app_stats_write(const struct app_stats *st, const char *path);

/* The deep light map of a session: built on the GPU when the config asks for one, rebuilt
 * only when the sun, the volume (GENERATION), the optics or the light map settings change.
 * Needs the GL context current. */
struct light_gpu;
struct app_light {
    struct light_gpu *gpu; /* NULL when effects.shadows = "off" */
    uint64_t generation;   /* bump when the volume on the GPU changes */
    struct effects effects; /* valid when have_effects (app_light_set_effects) */
    bool have_effects;
    /* effects.temporal, set by app/interact.c each frame: the time steps in the renderer's
     * volume and next volume (app_light_step_id; 0: none, the plain single map).  A light map
     * is built per step and kept keyed by it in a ring of two (gpu, spare), so a step change
     * builds only the new next step's; the eye pass blends the pair (LIGHTMAP_PAIR). */
    bool temporal;
    uint64_t step_id, next_id;
    struct light_gpu *spare; /* the second map of the ring (made on first use) */
    uint64_t held[2];        /* the step each of gpu, spare was last built for */
    int pair_first;          /* which of them holds step_id while the pair is bound */
    struct render_light pair; /* the hook that binds both */
    char pair_defines[96];
    struct gpu_timings *timing; /* where build times go (app_light_set_timing), or NULL */
    bool log_pending[2];        /* gpu's, spare's last build is logged when its time arrives */
};

/* The identity of time step STEP made with look generation GEN (never 0). */
uint64_t app_light_step_id(int step, uint64_t gen);

bool app_light_init(struct app_light *al, const struct config *cfg);
/* Uses the decisions E (copied) from now on; without them every auto effect is on. */
void app_light_set_effects(struct app_light *al, const struct effects *e);
/* Builds when stale and points the renderer at the light map; counts builds in ST (may be
 * NULL).  Never waits for the GPU (but on software drivers while timed, gpu.h "timers"). */
bool app_light_update(struct app_light *al, const struct config *cfg, struct renderer *r,
                      struct app_stats *st);
/* Times every following build into LOG (NULL: untimed, the default).  LOG is borrowed until
 * app_light_collect_timings(al, true) returned or app_light_finish. */
void app_light_set_timing(struct app_light *al, struct gpu_timings *log);
/* Moves the build times the GPU has ready into the log (all of them with WAIT) and logs the
 * builds whose time was not known when they were made.  Returns how many are in flight. */
int app_light_collect_timings(struct app_light *al, bool wait);
void app_light_finish(struct app_light *al);

int cmd_render(int argc, char **argv);
int cmd_run(int argc, char **argv);

#endif
