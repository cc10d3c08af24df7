/* The benchmarks' scenes from configs (scenes.h). */
#include "bench/scenes.h"

#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "render/camera.h"
#include "session/effects.h"
#include "session/scene.h"

const char *const bench_scene_names[BENCH_MAX_SCENES] = {"sphere", "storm", "katrina"};

bool bench_scene_known(const char *name)
{
    for (int i = 0; i < BENCH_MAX_SCENES; i++) {
        if (strcmp(name, bench_scene_names[i]) == 0)
            return true;
    }
    return false;
}

bool bench_scene_config(const char *name, const char *configs_dir, bool quick, char **sets,
                        int n_sets, struct config *cfg)
{
    char path[PATH_MAX];
    const char *file = NULL;
    if (strcmp(name, "sphere") == 0)
        file = "sphere.cfg";
    else if (strcmp(name, "katrina") == 0)
        file = "katrina.cfg";
    if (file)
        snprintf(path, sizeof(path), "%s/%s", configs_dir, file);
    char *all[16];
    int n = 0;
    static char quick_size[] = "scene.size=[48,48,24]";
    static char quick_light[] = "lightmap.resolution=[64,64,64]";
    if (quick && strcmp(name, "storm") == 0) {
        all[n++] = quick_size;
        all[n++] = quick_light;
    }
    for (int i = 0; i < n_sets && n < 16; i++)
        all[n++] = sets[i];
    return config_load_overrides(file ? path : NULL, all, n, cfg);
}

const char *bench_scene_missing_data(const struct config *cfg)
{
    if (cfg->scene.kind != SCENE_DATA)
        return NULL;
    for (int i = 0; i < cfg->data.file_count; i++) {
        if (access(cfg->data.files[i], R_OK) != 0)
            return cfg->data.files[i];
    }
    return NULL;
}

bool bench_scene_prepare(const char *name, const struct config *cfg, int w, int h,
                         struct ext_volume *vol, struct bench_scene *sc)
{
    memset(sc, 0, sizeof(*sc));
    snprintf(sc->name, sizeof(sc->name), "%s", name);
    if (!scene_build_volume(cfg, vol))
        return false;
    camera_direction(cfg->light.azimuth_deg, cfg->light.elevation_deg, sc->sun);
    scene_camera_view(cfg, w, h, &sc->view);
    struct effects_facts facts;
    effects_facts_init(&facts);
    if (!effects_measure_volume(vol, sc->sun, &cfg->optics.params, &facts))
        return false;
    facts.time_steps = 1;
    facts.views_known = true;
    facts.ground_visible = cfg->render.ground_on && effects_view_sees_ground(&sc->view);
    struct effects e;
    effects_decide(cfg, &facts, &e);
    scene_render_settings(cfg, &sc->settings);
    effects_apply_render(&e, &sc->settings);
    effects_light_settings(cfg, &e, &sc->light);
    sc->shadows = e.on[EFFECT_SHADOWS];
    sc->mode = cfg->lightmap.mode == LIGHTMAP_COMPRESSED ? LIGHT_GPU_COMPRESSED : LIGHT_GPU_DENSE;
    sc->optics = cfg->optics.params;
    sc->vol = vol;
    return true;
}
