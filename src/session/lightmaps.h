/*
 * session/lightmaps: the deep light map(s) of a session.  Built on the GPU when the effects ask
 * for one, rebuilt only when the sun, the volume (GENERATION), the optics or the light map
 * settings change; with effects.temporal one map per time step in a ring of two, blended by
 * the eye pass.  Needs the GL context current.  Knows nothing of views or windows.
 */
#ifndef ANVIL_SESSION_LIGHTMAPS_H
#define ANVIL_SESSION_LIGHTMAPS_H

#include <stdbool.h>
#include <stdint.h>

#include "config/config.h"
#include "light/light.h"
#include "light/light_gpu.h"
#include "render/render.h"
#include "session/effects.h"
#include "session/stats.h"

struct light_gpu;

struct lightmaps {
    struct light_gpu *gpu; /* NULL when effects.shadows = "off" */
    uint64_t generation;   /* bump when the volume on the GPU changes */
    struct effects effects; /* valid when have_effects (lightmaps_set_effects) */
    bool have_effects;
    /* effects.temporal, set each frame: the time steps in the renderer's volume and next
     * volume (lightmaps_step_id; 0: none, the plain single map).  A light map is built per
     * step and kept keyed by it in a ring of two (gpu, spare), so a step change builds only
     * the new next step's; the eye pass blends the pair (LIGHTMAP_PAIR). */
    bool temporal;
    /* With TEMPORAL: the next step's map is only built ahead of its step change
     * (lightmaps_prepare_next: staged playback) and never bound; false: the eye pass blends
     * the pair (effects.temporal). */
    bool ahead_only;
    uint64_t step_id, next_id;
    struct light_gpu *spare; /* the second map of the ring (made on first use) */
    uint64_t held[2];        /* the step each of gpu, spare was last built for */
    int pair_first;          /* which of them holds step_id while the pair is bound */
    struct render_light pair; /* the hook that binds both */
    char pair_defines[96];
    struct gpu_timings *timing; /* where build times go (lightmaps_set_timing), or NULL */
    bool log_pending[2];        /* gpu's, spare's last build is logged when its time arrives */
    bool log_quiet[2];          /* ... at LOG_DEBUG: its description was the last logged */
    /* What the last build logged at LOG_INFO said of the map: a build that says the same again
     * (every step of a played series, every sun a key moves) goes to LOG_DEBUG (--verbose). */
    char logged[208];
};

/* What a build depends on besides the volume: the sun, the light map settings (the effects'
 * and the session's quality), the storage. */
struct lightmaps_params {
    double sun[3];               /* toward the sun */
    struct light_settings light; /* effects_light_settings, then the session's quality */
    enum light_gpu_mode mode;
    bool shadows;                /* effects.shadows: without it there is no light map */
    bool one_phase;              /* effects.phase off (for the log) */
    bool half;                   /* render.precision half: the dense map in half floats */
};

/* The parameters CFG's lightmap.* and E (NULL: decided without facts) ask for, with the sun at
 * AZIMUTH_DEG, ELEVATION_DEG. */
void lightmaps_params_from(const struct config *cfg, const struct effects *e, double azimuth_deg,
                           double elevation_deg, struct lightmaps_params *out);

/* The identity of time step STEP made with look generation GEN (never 0). */
uint64_t lightmaps_step_id(int step, uint64_t gen);

bool lightmaps_init(struct lightmaps *al, const struct config *cfg);
/* Uses the decisions E (copied) from now on; without them every auto effect is on. */
void lightmaps_set_effects(struct lightmaps *al, const struct effects *e);
/* Builds when stale (the light key: sun, volume generation, optics, settings, storage) and
 * points the renderer at the light map; counts builds in ST (may be NULL).  Never waits for
 * the GPU (but on software drivers while timed: gpu.h, "timers"). */
bool lightmaps_update_params(struct lightmaps *al, const struct lightmaps_params *p,
                             struct renderer *r, struct session_stats *st);
/* Staged playback and effects.temporal: builds the map of the renderer's next volume
 * (NEXT_ID) when stale, without touching what the views use, so that the step change finds
 * it built.  Meant for the time between frames: with BUDGET_MS > 0 in pieces of about that
 * long a call (light_gpu_build_step; *DONE once built, the calls after the first resume it),
 * else whole.  No-op without a next volume. */
bool lightmaps_prepare_next(struct lightmaps *al, const struct lightmaps_params *p,
                            struct renderer *r, double budget_ms, bool *done,
                            struct session_stats *st);
/* What the next lightmaps_prepare_next works on (light_gpu_build_phase), and in words. */
enum light_build_phase lightmaps_next_phase(const struct lightmaps *al);
const char *lightmaps_next_doing(const struct lightmaps *al);
/* Whether the ring holds a map built for step NEXT_ID (true without light maps). */
bool lightmaps_next_built(const struct lightmaps *al, uint64_t next_id);
/* The same with the parameters of CFG, its sun and the decisions set (lightmaps_params_from). */
bool lightmaps_update(struct lightmaps *al, const struct config *cfg, struct renderer *r,
                      struct session_stats *st);
/* Times every following build into LOG (NULL: untimed, the default).  LOG is borrowed until
 * lightmaps_collect_timings(al, true) returned or lightmaps_finish. */
void lightmaps_set_timing(struct lightmaps *al, struct gpu_timings *log);
/* Moves the build times the GPU has ready into the log (all of them with WAIT) and logs the
 * builds whose time was not known when they were made.  Returns how many are in flight. */
int lightmaps_collect_timings(struct lightmaps *al, bool wait);
void lightmaps_finish(struct lightmaps *al);

/* Builds so far of the map that serves the step on screen (0 without one). */
unsigned lightmaps_builds(const struct lightmaps *al);
/* The light map of the step on screen at world point P (light_gpu_sample): false without one.
 * *BUILDS (may be NULL) counts that map's builds, so a caller can tell a rebuilt map. */
bool lightmaps_sample(const struct lightmaps *al, const double p[3], float *beam,
                      float diffuse[2], bool *have_diffuse, unsigned *builds);

#endif
