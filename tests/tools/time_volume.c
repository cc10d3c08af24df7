/* Times the GPU light build with the columns' diffuse pass against the one with the diffuse
 * light volume instead (effects.multiple = "volume"), side by side, on the default storm and
 * the Katrina sample: medians of interleaved builds, the ratio and the volume's iterations.
 * Usage: time_volume [REPEATS] (run from the source tree: configs/katrina.cfg). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "common/log.h"
#include "gpu/gpu.h"
#include "light/light.h"
#include "light/light_gpu.h"
#include "light/light_volume.h"
#include "config/config.h"
#include "render/render.h"

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* One build of LG (a new generation of the source, so the programs stay and the map is
 * rebuilt). */
static double build_ms(struct light_gpu *lg, struct renderer *r, uint64_t generation,
                       const struct light_settings *s, const double sun[3], int *iterations)
{
    struct light_gpu_source src = {renderer_volume_texture(r), renderer_grid(r), 1, generation,
                                   renderer_cells(r)};
    gpu_finish();
    double t0 = time_now_ms();
    bool built = false;
    if (!light_gpu_update(lg, &src, sun, s, LIGHT_GPU_DENSE, &built) || !built)
        exit(1);
    gpu_finish();
    double t = time_now_ms() - t0;
    if (iterations && s->volume) {
        struct light_volume v = {0};
        if (light_gpu_read_volume(lg, &v))
            *iterations = v.iterations;
        light_volume_finish(&v);
    }
    return t;
}

static void scene(struct renderer *r, const char *name, const char *file, int reps)
{
    struct config cfg;
    struct ext_volume vol = {0};
    test_config_file(&cfg, file, NULL, 0);
    test_upload_scene(r, &cfg, &vol);
    struct light_settings s;
    light_settings_defaults(&s);
    memcpy(s.resolution, cfg.lightmap.resolution, sizeof(s.resolution));
    light_settings_set_optics(&s, &cfg.optics.params, cfg.lightmap.forward_angle_deg);
    s.multiple = true;
    double sun[3];
    light_sun_direction(cfg.light.azimuth_deg, cfg.light.elevation_deg, sun);
    struct light_settings sv = s;
    sv.volume = true;
    int it = 0;
    uint64_t gen = 1;
    struct light_gpu *lc = light_gpu_create(), *lv = light_gpu_create();
    if (!lc || !lv)
        exit(1);
    build_ms(lc, r, gen++, &s, sun, NULL); /* the programs made once */
    build_ms(lv, r, gen++, &sv, sun, &it);
    double *a = malloc(reps * sizeof(double)), *b = malloc(reps * sizeof(double));
    for (int i = 0; i < reps; i++) {
        a[i] = build_ms(lc, r, gen++, &s, sun, NULL);
        b[i] = build_ms(lv, r, gen++, &sv, sun, &it);
    }
    light_gpu_destroy(lc);
    light_gpu_destroy(lv);
    qsort(a, reps, sizeof(double), cmp);
    qsort(b, reps, sizeof(double), cmp);
    printf("%s: columns %.1f ms, volume %.1f ms (%d iterations), %.2f x\n", name, a[reps / 2],
           b[reps / 2], it, b[reps / 2] / a[reps / 2]);
    free(a);
    free(b);
    ext_volume_finish(&vol);
}

int main(int argc, char **argv)
{
    int reps = argc > 1 ? atoi(argv[1]) : 5;
    if (reps < 1)
        reps = 1;
    log_set_level(LOG_WARN);
    struct gpu_context *ctx = test_gl_context_or_skip();
    struct renderer *r = renderer_create();
    if (!r)
        return 1;
    scene(r, "storm", NULL, reps);
    scene(r, "katrina", "configs/katrina.cfg", reps);
    renderer_destroy(r);
    gpu_context_destroy(ctx);
    return 0;
}
