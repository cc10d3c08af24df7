/* The session's deep light map: config and effects -> light settings -> GPU build when stale. */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "session/lightmaps.h"
#include "session/scene.h"
#include "common/log.h"
#include "light/light_gpu.h"
#include "render/camera.h"

bool lightmaps_init(struct lightmaps *al, const struct config *cfg)
{
    memset(al, 0, sizeof(*al));
    if (cfg->effects.mode[EFFECT_SHADOWS] == EFFECT_OFF)
        return true;
    al->gpu = light_gpu_create();
    return al->gpu != NULL;
}

void lightmaps_set_effects(struct lightmaps *al, const struct effects *e)
{
    al->effects = *e;
    al->have_effects = true;
}

/* The generation of every temporal map's key: step ids never meet the plain map's keys. */
#define TEMPORAL_GENERATION (UINT64_C(1) << 63)

uint64_t lightmaps_step_id(int step, uint64_t gen)
{
    return (gen << 32) ^ (uint64_t)(step + 1);
}

/* The temporal pair's hook: step k's map as the light map, step k + 1's as the second. */
static void bind_pair(const struct render_light *light, const struct gpu_program *prog)
{
    const struct lightmaps *al =
        (const struct lightmaps *)((const char *)light - offsetof(struct lightmaps, pair));
    const struct light_gpu *maps[2] = {al->gpu, al->spare};
    light_gpu_bind(maps[al->pair_first], prog, false);
    light_gpu_bind(maps[1 - al->pair_first], prog, true);
}

/* Logs and counts the build just made of map WHICH (LG).  Its time is logged with it when
 * known at once (software drivers, gpu.h), else when it arrives (lightmaps_collect_timings). */
static void built_one(struct lightmaps *al, int which, struct light_gpu *lg,
                      const struct light_settings *s, enum light_gpu_mode mode, bool half,
                      bool one_phase, struct session_stats *st)
{
    size_t dense, compressed;
    light_gpu_bytes(lg, &dense, &compressed);
    if (st) {
        session_stats_add_build(st);
        st->light_bytes_dense = (double)dense;
        st->light_bytes_compressed = (double)compressed;
    }
    double ms = 0.0;
    bool known = light_gpu_last_build_ms(lg, &ms);
    al->log_pending[which] = al->timing && !known;
    char what[160];
    snprintf(what, sizeof(what), "(%s%s%s%s)",
             mode != LIGHT_GPU_DENSE ? "compressed"
             : half                  ? "dense, half floats"
                                     : "dense",
             s->forward ? (s->peripheral ? ", forward and peripheral" : ", forward")
                        : ", shadow only",
             !s->multiple ? ""
             : s->volume  ? ", diffuse light volume"
             : s->lateral ? ", diffuse light with lateral escape"
                          : ", diffuse light",
             one_phase ? ", one phase" : "");
    char dims[48], key[sizeof(al->logged)];
    snprintf(dims, sizeof(dims), "%dx%dx%d", s->resolution[0], s->resolution[1], s->resolution[2]);
    snprintf(key, sizeof(key), "%s %s", dims, what);
    bool again = strcmp(key, al->logged) == 0;
    al->log_quiet[which] = again;
    memcpy(al->logged, key, sizeof(key));
    char when[64] = "queued";
    if (known)
        snprintf(when, sizeof(when), "built in %.1f ms", ms);
    log_msg(again ? LOG_DEBUG : LOG_INFO, "light map %s %s %s", dims, when, what);
}

static void build_failed(const struct light_settings *s)
{
    log_error("lightmap.resolution [%d, %d, %d]: the light map could not be built (see "
              "above); a smaller resolution needs less GPU memory",
              s->resolution[0], s->resolution[1], s->resolution[2]);
}

/* Builds map WHICH (0 gpu, 1 spare) for SRC when stale; logs and counts a build. */
static bool build(struct lightmaps *al, int which, const struct light_gpu_source *src,
                  const double sun[3], const struct light_settings *s, enum light_gpu_mode mode,
                  bool half, bool one_phase, struct session_stats *st)
{
    struct light_gpu *lg = which ? al->spare : al->gpu;
    bool built = false;
    light_gpu_set_timing(lg, al->timing);
    light_gpu_set_half(lg, half);
    if (!light_gpu_update(lg, src, sun, s, mode, &built)) {
        build_failed(s);
        return false;
    }
    if (built)
        built_one(al, which, lg, s, mode, half, one_phase, st);
    return true;
}

/* The same in pieces for about BUDGET_MS (light_gpu_build_step); *DONE once built. */
static bool build_pieces(struct lightmaps *al, int which, const struct light_gpu_source *src,
                         const double sun[3], const struct light_settings *s,
                         enum light_gpu_mode mode, bool half, bool one_phase,
                         double budget_ms, bool *done, struct session_stats *st)
{
    struct light_gpu *lg = which ? al->spare : al->gpu;
    bool needed = false;
    *done = false;
    light_gpu_set_timing(lg, al->timing);
    light_gpu_set_half(lg, half);
    if (!light_gpu_build_begin(lg, src, sun, s, mode, &needed) ||
        (needed && !light_gpu_build_step(lg, budget_ms, done))) {
        build_failed(s);
        return false;
    }
    if (!needed) {
        *done = true;
        return true;
    }
    if (*done)
        built_one(al, which, lg, s, mode, half, one_phase, st);
    return true;
}

/* effects.temporal: one map per step in the ring {gpu, spare}.  The map that already holds
 * step k (or else the one not holding k + 1) serves k, the other k + 1: advancing a step finds
 * the new k built as the old next and builds only the new next. */
/* The map of the ring that serves step k (the other serves k + 1). */
static int serving_slot(const struct lightmaps *al, bool pair)
{
    if (al->spare && al->held[1] == al->step_id)
        return 1;
    if (al->held[0] != al->step_id && al->spare && pair && al->held[0] == al->next_id)
        return 1;
    return 0;
}

/* The next volume's map: its own cells when it was staged whole, else the pair's (a cell
 * empty in the pair is empty in both). */
static bool build_next(struct lightmaps *al, int slot, struct renderer *r,
                       const struct lightmaps_params *p, double budget_ms, bool *done,
                       struct session_stats *st)
{
    const struct render_cells *cells = renderer_next_cells(r);
    struct light_gpu_source next = {
        .beta = renderer_next_texture(r),
        .grid = renderer_next_grid(r),
        .volume_id = al->next_id,
        .generation = TEMPORAL_GENERATION,
        .cells = cells ? cells : renderer_pair_cells(r),
    };
    al->held[slot] = 0;
    *done = true;
    if (budget_ms > 0.0) {
        if (!build_pieces(al, slot, &next, p->sun, &p->light, p->mode, p->half, p->one_phase,
                          budget_ms, done, st))
            return false;
    } else if (!build(al, slot, &next, p->sun, &p->light, p->mode, p->half, p->one_phase, st)) {
        return false;
    }
    if (*done)
        al->held[slot] = al->next_id;
    return true;
}

bool lightmaps_prepare_next(struct lightmaps *al, const struct lightmaps_params *p,
                            struct renderer *r, double budget_ms, bool *done,
                            struct session_stats *st)
{
    *done = true;
    if (!al->gpu || !p->shadows || !al->temporal || al->step_id == 0 || al->next_id == 0 ||
        !renderer_has_next(r))
        return true;
    if (!al->spare && !(al->spare = light_gpu_create()))
        return false;
    return build_next(al, 1 - serving_slot(al, true), r, p, budget_ms, done, st);
}

enum light_build_phase lightmaps_next_phase(const struct lightmaps *al)
{
    const struct light_gpu *lg = 1 - serving_slot(al, true) ? al->spare : al->gpu;
    return lg ? light_gpu_build_phase(lg) : LIGHT_BUILD_START;
}

const char *lightmaps_next_doing(const struct lightmaps *al)
{
    const struct light_gpu *lg = 1 - serving_slot(al, true) ? al->spare : al->gpu;
    return lg ? light_gpu_build_doing(lg) : "the light build's start";
}

bool lightmaps_next_built(const struct lightmaps *al, uint64_t next_id)
{
    if (!al->gpu || (al->have_effects && !al->effects.on[EFFECT_SHADOWS]))
        return true; /* no light map to build */
    return next_id != 0 && (al->held[0] == next_id || (al->spare && al->held[1] == next_id));
}

static bool update_temporal(struct lightmaps *al, struct renderer *r,
                            const struct lightmaps_params *p, struct session_stats *st)
{
    bool pair = al->next_id != 0 && renderer_has_next(r);
    if (pair && !al->spare && !(al->spare = light_gpu_create()))
        return false;
    int cur = serving_slot(al, pair);
    struct light_gpu *maps[2] = {al->gpu, al->spare};
    struct light_gpu_source src = {
        .beta = renderer_volume_texture(r),
        .grid = renderer_grid(r),
        .volume_id = al->step_id,
        .generation = TEMPORAL_GENERATION,
        .cells = renderer_cells(r),
    };
    al->held[cur] = 0;
    if (!build(al, cur, &src, p->sun, &p->light, p->mode, p->half, p->one_phase, st))
        return false;
    al->held[cur] = al->step_id;
    /* Without the blend the next step's map is built between frames only
     * (lightmaps_prepare_next): the frame draws step k alone. */
    if (!pair || al->ahead_only) {
        renderer_set_light(r, light_gpu_render_light(maps[cur]));
        return true;
    }
    bool done;
    if (!build_next(al, 1 - cur, r, p, 0.0, &done, st))
        return false;
    al->pair_first = cur;
    /* Step k's variant (LIGHTMAP, MULTIPLE) and the pair: both maps are built alike. */
    snprintf(al->pair_defines, sizeof(al->pair_defines), "%s#define LIGHTMAP_PAIR 1\n",
             light_gpu_render_light(maps[cur])->defines);
    al->pair.defines = al->pair_defines;
    al->pair.bind = bind_pair;
    renderer_set_light(r, &al->pair);
    return true;
}

void lightmaps_params_from(const struct config *cfg, const struct effects *e, double azimuth_deg,
                           double elevation_deg, struct lightmaps_params *out)
{
    struct effects decided;
    if (!e) {
        effects_decide(cfg, NULL, &decided);
        e = &decided;
    }
    memset(out, 0, sizeof(*out));
    out->shadows = e->on[EFFECT_SHADOWS];
    out->one_phase = !e->on[EFFECT_PHASE];
    effects_light_settings(cfg, e, &out->light);
    light_sun_direction(azimuth_deg, elevation_deg, out->sun);
    out->mode = cfg->lightmap.mode == LIGHTMAP_COMPRESSED ? LIGHT_GPU_COMPRESSED : LIGHT_GPU_DENSE;
    out->half = cfg->render.precision == PRECISION_HALF;
}

bool lightmaps_update_params(struct lightmaps *al, const struct lightmaps_params *p,
                             struct renderer *r, struct session_stats *st)
{
    if (!al->gpu || !p->shadows) {
        renderer_set_light(r, NULL);
        return true;
    }
    if (al->temporal && al->step_id != 0)
        return update_temporal(al, r, p, st);
    struct light_gpu_source src = {
        .beta = renderer_volume_texture(r),
        .grid = renderer_grid(r),
        .volume_id = 1,
        .generation = al->generation,
        .cells = renderer_cells(r),
    };
    al->held[0] = 0;
    if (!build(al, 0, &src, p->sun, &p->light, p->mode, p->half, p->one_phase, st))
        return false;
    renderer_set_light(r, light_gpu_render_light(al->gpu));
    return true;
}

bool lightmaps_update(struct lightmaps *al, const struct config *cfg, struct renderer *r,
                      struct session_stats *st)
{
    struct lightmaps_params p;
    lightmaps_params_from(cfg, al->have_effects ? &al->effects : NULL, cfg->light.azimuth_deg,
                          cfg->light.elevation_deg, &p);
    return lightmaps_update_params(al, &p, r, st);
}

void lightmaps_set_timing(struct lightmaps *al, struct gpu_timings *log)
{
    al->timing = log;
}

int lightmaps_collect_timings(struct lightmaps *al, bool wait)
{
    struct light_gpu *maps[2] = {al->gpu, al->spare};
    int in_flight = 0;
    for (int i = 0; i < 2; i++) {
        if (!maps[i])
            continue;
        in_flight += light_gpu_collect_timings(maps[i], wait);
        double ms;
        if (al->log_pending[i] && light_gpu_last_build_ms(maps[i], &ms)) {
            log_msg(al->log_quiet[i] ? LOG_DEBUG : LOG_INFO,
                    "light map built in %.1f ms on the GPU", ms);
            al->log_pending[i] = false;
        }
    }
    return in_flight;
}

void lightmaps_finish(struct lightmaps *al)
{
    light_gpu_destroy(al->gpu);
    light_gpu_destroy(al->spare);
    al->gpu = NULL;
    al->spare = NULL;
}

/* The map that serves the step on screen (NULL without one). */
static const struct light_gpu *serving(const struct lightmaps *al)
{
    if (al->temporal && al->step_id != 0 && al->spare && al->held[1] == al->step_id)
        return al->spare;
    return al->gpu;
}

unsigned lightmaps_builds(const struct lightmaps *al)
{
    const struct light_gpu *lg = serving(al);
    return lg ? light_gpu_builds(lg) : 0;
}

bool lightmaps_sample(const struct lightmaps *al, const double p[3], float *beam,
                      float diffuse[2], bool *have_diffuse, unsigned *builds)
{
    const struct light_gpu *lg = serving(al);
    if (builds)
        *builds = lg ? light_gpu_builds(lg) : 0;
    *have_diffuse = false;
    return lg && light_gpu_sample(lg, p, beam, diffuse, have_diffuse);
}
