/*
 * bench: what accuracy costs in time.  This header is the measuring kit, over scenes already
 * prepared (struct bench_scene: bench/scenes.h makes them from configs; nothing here reads a
 * config):
 *
 *  - views: the frame cost of N views sharing one deep light map against the same N views
 *    each rebuilding it (what a renderer that lights every view on its own pays);
 *  - quality: one-knob-at-a-time sweeps around the default settings (ray step, light map
 *    resolution, dense vs compressed and epsilon, forward angle, peripheral and forward
 *    scattering on/off, no light map at all), each measured in GPU milliseconds per light
 *    build and per view (timer queries, medians of repeats) and in error against the Monte
 *    Carlo reference (reference/reference.h), cached on disk;
 *  - the Pareto front and the PNG plot of error against milliseconds.
 *
 * The rest of the part: bench/scenes.h (scenes from configs), bench/experiments.h (the layer
 * from 16 directions, the wall under 4 suns), bench/tables.h (tables and verdicts as text),
 * bench/paraview.h (ParaView's side of the views), bench/run.h (anvil bench's whole run,
 * the one entry point of the command).  Measuring needs the GL context current; the Pareto
 * front and the plot do not.  Nothing here prints: progress goes to the log.  It must not
 * know windows or the command line.
 *
 * Must not know: windows, the command line.
 */
#ifndef ANVIL_BENCH_BENCH_H
#define ANVIL_BENCH_BENCH_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "data/volume.h"
#include "light/light.h"
#include "light/light_gpu.h"
#include "optics/optics.h"
#include "render/image.h"
#include "render/render.h"

/* One scene as the renderer would draw it by default.  VOL is borrowed. */
struct bench_scene {
    char name[32];
    const struct ext_volume *vol;
    struct render_settings settings; /* the default eye pass (effects applied) */
    struct render_view view;
    struct optics_params optics;
    double sun[3];                   /* toward the sun */
    struct light_settings light;     /* the default light map (effects applied) */
    enum light_gpu_mode mode;        /* the default storage */
    bool shadows;                    /* the default has a light map */
};

/* One point of the sweep: the default with one knob changed (or a named combination). */
struct bench_variant {
    char knob[24];  /* "default", "ray step", "resolution", "compressed", ... */
    char value[64]; /* the knob's value as written in the table */
    bool is_default;
    bool shadows;   /* false: no light map (unshadowed single scattering) */
    struct light_settings light;
    enum light_gpu_mode mode;
    float step_m;   /* eye pass ray step, metres (0: half the voxel crossing along each ray) */
};

struct bench_result {
    struct bench_variant v;
    double build_ms, view_ms;         /* medians over the repeats of every result doing the
                                         same work (bench_pool_timings) */
    double build_samples[32];         /* the build times measured for this result */
    int n_build_samples;
    double view_samples[32];          /* ... and the view times */
    int n_view_samples;
    double build_spread, view_spread; /* 1.48 x the median absolute deviation */
    double rmse, max_err;             /* linear radiance, over pixels and RGB channels */
    double rmse_model;                /* sqrt(RMSE^2 - sigma^2): the part of the RMSE the
                                         reference's own noise does not explain, an
                                         unbiased estimate of the squared error against the
                                         noise-free image (bench_beats, the plot) */
    double rmse_rel, max_rel;         /* both over the reference's RMS standard error */
    double self_rmse;                 /* against the renderer's own converged image (finest
                                         ray step and light map, the default model) */
    bool pareto;                      /* on the Pareto front of its scene (rmse) */
    bool pareto_self;                 /* ... with self_rmse as the error */
};

/* The most variants one sweep has (bench_variants' MAX for a whole sweep). */
#define BENCH_MAX_VARIANTS 32

/* The quality sweep's results on one scene, as the tables and plots report them. */
struct bench_scene_results {
    char name[32];
    struct bench_result res[BENCH_MAX_VARIANTS];
    int n;
    double sigma; /* the reference's RMS standard error per pixel and channel */
    int spp;      /* its samples per pixel */
};

/* The sweep around SC's defaults into OUT (at most MAX); QUICK leaves out the costliest
 * points.  Returns the count. */
int bench_variants(const struct bench_scene *sc, bool quick, struct bench_variant *out, int max);

/* The Monte Carlo reference of SC at SPP samples per pixel (all threads), read from
 * CACHE_DIR when an earlier run left it there (the file name holds a hash of everything it
 * depends on), else rendered and stored.  MEAN and ERR are initialised here; *CACHED (may be
 * NULL) says whether it was read.  No GL. */
bool bench_reference(const struct bench_scene *sc, int spp, const char *cache_dir,
                     struct image *mean, struct image *err, bool *cached);

/* Starts OUT for V on SC: one untimed build and draw (it compiles the variants) whose image
 * is compared with REF (mean) and REF_ERR (both NULL: no error measured) and with SELF_REF
 * (may be NULL).  R must hold SC's volume and optics.  GL context current. */
bool bench_measure(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                   const struct bench_variant *v, const struct image *ref,
                   const struct image *ref_err, const struct image *self_ref,
                   struct bench_result *out);

/* Adds one timing sample to OUT (started by bench_measure): a forced light build when BUILD,
 * then one eye pass.  The caller goes round all the variants once per repeat, so that the
 * shared machine's load drifts over every variant alike rather than over one block of them;
 * bench_timings_finish then takes the medians. */
bool bench_time_once(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                     bool build, struct bench_result *out);
void bench_timings_finish(struct bench_result *out);

/* Renders V on SC once into OUT (initialised here): e.g. the converged image of the
 * renderer's own model.  GL context current. */
bool bench_render(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                  const struct bench_variant *v, struct image *out);

/* Whether A and B do the same work, build and view: the same light map shader variant, grid
 * and storage (the forward angle, a uniform, may differ) and the same ray step. */
bool bench_same_work(const struct bench_variant *a, const struct bench_variant *b);

/* Results that do the same work share their timings, so that the machine's load does not
 * decide between them: each one's build_ms (and spread) becomes the median of the build
 * samples of every result whose build does the same work (a build does not depend on the eye
 * pass's knobs), its view_ms that of the view samples of every result with bench_same_work. */
void bench_pool_timings(struct bench_result *res, int n);

/* Marks the results (N of one scene) that no other result beats: another result beats one
 * when it is no worse in both milliseconds (build + view) and error, and better in one, by
 * more than the noise: BENCH_TIME_NOISE relative in time, BENCH_ERROR_NOISE relative in
 * error (rmse_model against Monte Carlo, self_rmse against the converged renderer). */
#define BENCH_TIME_NOISE 0.10
#define BENCH_ERROR_NOISE 0.01

/* Whether B beats A: no slower and no worse beyond the noise, and faster or better beyond
 * it.  The time noise is the larger of BENCH_TIME_NOISE and the relative spread of either's
 * repeats (a shared machine scatters far more than a quiet GPU), counting only the build or
 * view that the two do not share: rows that do the same work carry one pooled median
 * (bench_pool_timings), whose scatter is common to both. */
bool bench_beats(const struct bench_result *b, const struct bench_result *a, bool self);
/* The same with "no slower and no worse" only (ties allowed): a setting that dominates on
 * every scene must tie or win on each and win on one. */
bool bench_no_worse(const struct bench_result *b, const struct bench_result *a, bool self);
/* The error bench_beats compares. */
double bench_error(const struct bench_result *r, bool self);
void bench_pareto(struct bench_result *res, int n);

/* Builds the light map of SC with SETTINGS and MODE (forced: a new generation), waits for it
 * and points R at it; *MS its time (0 and no map when SHADOWS is false). */
bool bench_timed_build(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                       bool shadows, const struct light_settings *settings,
                       enum light_gpu_mode mode, double *ms);
/* Draws VIEW with S into OUT and waits for it; *MS its time. */
bool bench_timed_draw(struct renderer *r, const struct render_settings *s,
                      const struct render_view *view, struct gpu_texture *out, double *ms);

/* ---- views -------------------------------------------------------------------------- */

struct bench_views_row {
    int views;
    double shared_ms;  /* one frame after a change: one build, then every view */
    double static_ms;  /* one frame without a change: every view, no build */
    double rebuild_ms; /* one frame with a build before every view */
    double build_ms, view_ms; /* medians of one build and of one view */
};

/* Frame costs for each of the N_COUNTS view counts, views of W x H orbiting SC's volume,
 * medians of REPEATS frames.  R must hold SC's volume.  GL context current. */
bool bench_views(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                 const int *counts, int n_counts, int w, int h, int repeats,
                 struct bench_views_row *out);

/* ---- files -------------------------------------------------------------------------- */

/* Creates the folder DIR and its parents, as mkdir -p.  False (logged) when DIR cannot be
 * made. */
bool bench_make_dir(const char *dir);

/* ---- plots -------------------------------------------------------------------------- */

/* Whether V is the 3-D diffusion tier of multiple scattering (effects.multiple = "volume"),
 * the one the plots mark apart from the columns. */
bool bench_is_volume_tier(const struct bench_variant *v);

/* The colour of the plots' marker of the 3-D diffusion tier (bench_is_volume_tier), RGB. */
extern const uint8_t bench_plot_volume_rgb[3];

/* A plot of RMSE (SELF: self_rmse) against milliseconds (build + view, both axes
 * logarithmic), one panel per scene, the Pareto front joined, the default ringed and the 3-D
 * diffusion tier squared, with a key, as 8-bit RGB rows from the top.  *W and *H get its
 * size; the caller frees the pixels.  RES[s] holds N[s] results of scene NAMES[s].  NULL
 * (logged) when out of memory. */
uint8_t *bench_plot_rgb(const char *title, int n_scenes, const char *const *names,
                        const struct bench_result *const *res, const int *n, bool self, int *w,
                        int *h);

/* bench_plot_rgb into a PNG at PATH.  Returns false (logged) on a failed write. */
bool bench_plot_png(const char *path, const char *title, int n_scenes, const char *const *names,
                    const struct bench_result *const *res, const int *n, bool self);

#endif
