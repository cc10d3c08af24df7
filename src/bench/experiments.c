/* The layer seen from sixteen directions and the wall under four suns (experiments.h). */
#include "bench/experiments.h"

#include <math.h>
#include <stdio.h>

#include "bench/bench.h"
#include "bench/scenes.h"
#include "common/log.h"
#include "config/config.h"
#include "render/camera.h"

const double bench_layer_elevations[BENCH_LAYER_ELEVATIONS] = {12.0, 30.0, 60.0, 85.0};
const double bench_layer_azimuths[BENCH_LAYER_AZIMUTHS] = {0.0, 75.0, 120.0, 180.0};
const double bench_wall_elevations[BENCH_WALL_SUNS] = {10.0, 20.0, 45.0, 70.0};

/* The means of scene NAME (the defaults with the overrides SETS) at the default settings and
 * of its Monte Carlo reference, W x H pixels, into OUT (its scattering_deg is left alone). */
static bool scene_means(const struct bench_experiments_desc *d, struct renderer *r,
                        struct light_gpu *lg, const char *name, char **sets, int n_sets, int w,
                        int h, struct bench_angle_result *out)
{
    struct config cfg;
    if (!config_load_overrides(NULL, sets, n_sets, &cfg))
        return false;
    struct ext_volume vol = {0};
    struct bench_scene sc;
    struct image ref = {0}, err = {0}, img = {0};
    bool ok = false;
    if (!bench_scene_prepare(name, &cfg, w, h, &vol, &sc))
        goto done;
    if (!bench_reference(&sc, d->spp, d->cache_dir, &ref, &err, NULL))
        goto done;
    if (d->cpu_volume) {
        if (!bench_volume_image(&sc, &img, d->timing))
            goto done;
    } else {
        struct bench_variant def;
        if (bench_variants(&sc, true, &def, 1) != 1 ||
            !renderer_set_optics(r, &cfg.optics.params) || !renderer_set_volume(r, &vol) ||
            !bench_render(r, lg, &sc, &def, &img))
            goto done;
    }
    double a = 0.0, b = 0.0, var = 0.0;
    for (int i = 0; i < w * h; i++) {
        for (int c = 0; c < 3; c++) {
            a += img.rgba[4 * i + c];
            b += ref.rgba[4 * i + c];
            var += (double)err.rgba[4 * i + c] * err.rgba[4 * i + c];
        }
    }
    int n = 3 * w * h;
    out->model = a / n;
    out->traced = b / n;
    out->sigma = sqrt(var) / n;
    ok = true;
done:
    image_finish(&ref);
    image_finish(&err);
    image_finish(&img);
    ext_volume_finish(&vol);
    return ok;
}

/* The renderer's diffuse light: the default, or the volume with D->volume. */
static char *multiple_set(const struct bench_experiments_desc *d)
{
    return d->volume ? "effects.multiple=volume" : "effects.multiple=auto";
}

static bool layer_angle(const struct bench_experiments_desc *d, struct renderer *r,
                        struct light_gpu *lg, double elevation, double rel_azimuth,
                        struct bench_angle_result *out)
{
    const double sun_az = 120.0, sun_el = 40.0, dist_km = 300.0;
    const double target[3] = {240.0, 240.0, 1.0};
    double dir[3], sun[3];
    camera_direction(sun_az + rel_azimuth, elevation, dir);
    camera_direction(sun_az, sun_el, sun);
    char sun_set[2][48], cam_set[80];
    snprintf(sun_set[0], sizeof(sun_set[0]), "light.azimuth=%g", sun_az);
    snprintf(sun_set[1], sizeof(sun_set[1]), "light.elevation=%g", sun_el);
    snprintf(cam_set, sizeof(cam_set), "camera.position=[%.4f,%.4f,%.4f]",
             target[0] + dist_km * dir[0], target[1] + dist_km * dir[1],
             target[2] + dist_km * dir[2]);
    char *sets[] = {"scene.kind=slab", "scene.size=[64,64,16]", "scene.extent=[480,480,2]",
                    "scene.tau=20", "scene.phase=water", sun_set[0], sun_set[1], cam_set,
                    "camera.target=[240,240,1]", "camera.fov=8", "camera.far=5000",
                    "render.sky=[0,0,0]", "render.ground_on=false", multiple_set(d)};
    int w = d->quick ? 16 : 32, h = d->quick ? 12 : 24;
    if (!scene_means(d, r, lg, "layer", sets, (int)(sizeof(sets) / sizeof(sets[0])), w, h, out))
        return false;
    /* Sunlight travels along -sun; the light reaching the camera travels along +dir. */
    double c = -(sun[0] * dir[0] + sun[1] * dir[1] + sun[2] * dir[2]);
    out->scattering_deg = acos(fmax(-1.0, fmin(1.0, c))) * (180.0 / 3.14159265358979323846);
    log_info("bench: layer seen from elevation %g, azimuth %g from the sun: %.4g against "
             "%.4g +- %.2g", elevation, rel_azimuth, out->model, out->traced, out->sigma);
    return true;
}

static bool wall_sun(const struct bench_experiments_desc *d, struct renderer *r,
                     struct light_gpu *lg, double sun_el, struct bench_angle_result *out)
{
    char sun_set[48];
    snprintf(sun_set, sizeof(sun_set), "light.elevation=%g", sun_el);
    char *sets[] = {"scene.kind=slab", d->quick ? "scene.size=[8,32,32]" : "scene.size=[16,64,64]",
                    "scene.extent=[2,60,10]", "scene.tau=100", "scene.phase=water",
                    "light.azimuth=270", sun_set, "camera.position=[-50,30,13.8164]",
                    "camera.target=[0,30,5]", "camera.fov=8", "camera.far=5000",
                    "render.sky=[0,0,0]", "render.ground_on=false", multiple_set(d)};
    int w = d->quick ? 16 : 32, h = d->quick ? 12 : 24;
    if (!scene_means(d, r, lg, "wall", sets, (int)(sizeof(sets) / sizeof(sets[0])), w, h, out))
        return false;
    out->scattering_deg = 0.0;
    log_info("bench: wall under a sun at elevation %g: %.4g against %.4g +- %.2g", sun_el,
             out->model, out->traced, out->sigma);
    return true;
}

bool bench_angles_measure(struct renderer *r, struct light_gpu *lg,
                          const struct bench_experiments_desc *d, struct bench_angles *out)
{
    for (int i = 0; i < BENCH_LAYER_ELEVATIONS; i++) {
        for (int j = 0; j < BENCH_LAYER_AZIMUTHS; j++) {
            if (!layer_angle(d, r, lg, bench_layer_elevations[i], bench_layer_azimuths[j],
                             &out->layer[i][j]))
                return false;
        }
    }
    for (int i = 0; i < BENCH_WALL_SUNS; i++) {
        if (!wall_sun(d, r, lg, bench_wall_elevations[i], &out->wall[i]))
            return false;
    }
    return true;
}
