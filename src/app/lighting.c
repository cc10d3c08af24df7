/* The session's deep light map: config and effects -> light settings -> GPU build when stale. */
#include <string.h>

#include "app/app.h"
#include "common/log.h"
#include "light/light_gpu.h"
#include "render/camera.h"

bool app_light_init(struct app_light *al, const struct config *cfg)
{
    memset(al, 0, sizeof(*al));
    if (cfg->effects.mode[EFFECT_SHADOWS] == EFFECT_OFF)
        return true;
    al->gpu = light_gpu_create();
    return al->gpu != NULL;
}

void app_light_set_effects(struct app_light *al, const struct effects *e)
{
    al->effects = *e;
    al->have_effects = true;
}

bool app_light_update(struct app_light *al, const struct config *cfg, struct renderer *r,
                      struct app_stats *st)
{
    struct effects decided;
    const struct effects *e = &al->effects;
    if (!al->have_effects) {
        effects_decide(cfg, NULL, &decided);
        e = &decided;
    }
    if (!al->gpu || !e->on[EFFECT_SHADOWS]) {
        renderer_set_light(r, NULL);
        return true;
    }
    struct light_settings s;
    effects_light_settings(cfg, e, &s);
    double sun[3];
    light_sun_direction(cfg->light.azimuth_deg, cfg->light.elevation_deg, sun);
    struct light_gpu_source src = {
        .beta = renderer_volume_texture(r),
        .grid = renderer_grid(r),
        .volume_id = 1,
        .generation = al->generation,
    };
    enum light_gpu_mode mode =
        cfg->lightmap.mode == LIGHTMAP_COMPRESSED ? LIGHT_GPU_COMPRESSED : LIGHT_GPU_DENSE;
    bool built = false;
    if (!light_gpu_update(al->gpu, &src, sun, &s, mode, &built)) {
        log_error("lightmap.resolution [%d, %d, %d]: the light map could not be built (see "
                  "above); a smaller resolution needs less GPU memory",
                  s.resolution[0], s.resolution[1], s.resolution[2]);
        return false;
    }
    if (built) {
        double ms = light_gpu_last_build_ms(al->gpu);
        if (st)
            app_stats_add_build(st, ms);
        size_t dense, compressed;
        light_gpu_bytes(al->gpu, &dense, &compressed);
        if (st) {
            st->light_bytes_dense = (double)dense;
            st->light_bytes_compressed = (double)compressed;
        }
        log_info("light map %dx%dx%d built in %.1f ms (%s%s%s)", s.resolution[0],
                 s.resolution[1], s.resolution[2], ms,
                 mode == LIGHT_GPU_DENSE ? "dense" : "compressed",
                 s.forward ? (s.peripheral ? ", forward and peripheral" : ", forward")
                           : ", shadow only",
                 e->on[EFFECT_PHASE] ? "" : ", one phase");
    }
    renderer_set_light(r, light_gpu_render_light(al->gpu));
    return true;
}

void app_light_finish(struct app_light *al)
{
    light_gpu_destroy(al->gpu);
    al->gpu = NULL;
}
