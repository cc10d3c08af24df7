/* The diffuse light volume on EGL/llvmpipe: the GPU build (shaders/light_volume.comp) against
 * the CPU reference (light_volume_build), and the eye pass reading it
 * (effects.multiple = "volume"). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "thin_layer.h"

#include "common/log.h"
#include "gpu/gpu.h"
#include "light/light.h"
#include "light/light_gpu.h"
#include "light/light_volume.h"
#include "render/render.h"
#include "session/lightmaps.h"
#include "session/scene.h"
#include "session/stats.h"

/* Largest |GPU - CPU| of phi and of each flux component, relative to the largest phi of the
 * CPU's field.  Both solve the same system; the GPU in floats to a relative residual of 1e-5,
 * the CPU in double to 1e-6, from beams that differ by up to 2e-4 (GPU_CPU_TOLERANCE of
 * test_lightmap) and whose differences over a third of a cell are the source. */
#define GPU_CPU_VOLUME_TOLERANCE 5e-4

static struct gpu_context *ctx;
static struct renderer *renderer;

/* PHI_MIN: the least the largest phi must be (real diffuse light, not two empty fields). */
static double gpu_vs_cpu(const char **sets, int n, double phi_min)
{
    struct config cfg;
    struct ext_volume vol = {0};
    test_config_from(&cfg, sets, n);
    test_upload_scene(renderer, &cfg, &vol);
    struct light_settings s;
    light_settings_defaults(&s);
    memcpy(s.resolution, cfg.lightmap.resolution, sizeof(s.resolution));
    light_settings_set_optics(&s, &cfg.optics.params, cfg.lightmap.forward_angle_deg);
    s.multiple = true;
    s.volume = true;
    double sun[3];
    light_sun_direction(cfg.light.azimuth_deg, cfg.light.elevation_deg, sun);

    struct light_gpu *lg = light_gpu_create();
    assert_non_null(lg);
    struct light_gpu_source src = {renderer_volume_texture(renderer), renderer_grid(renderer), 1,
                                   1, renderer_cells(renderer)};
    assert_true(light_gpu_update(lg, &src, sun, &s, LIGHT_GPU_DENSE, NULL));
    struct light_volume gpu = {0}, cpu = {0};
    assert_true(light_gpu_read_volume(lg, &gpu));
    /* The CPU reference over the CPU's beam (the same beam with or without the columns). */
    struct light_map map = {0};
    struct light_settings beam = s;
    beam.multiple = false;
    assert_true(light_map_build(&vol, sun, &beam, &map));
    assert_true(light_volume_build(&vol, &map, &s, NULL, &cpu));
    assert_memory_equal(gpu.grid.n, cpu.grid.n, sizeof(cpu.grid.n));
    size_t count = grid3_count(&cpu.grid);
    double phi_max = 0.0;
    for (size_t c = 0; c < count; c++)
        phi_max = fmax(phi_max, cpu.field[4 * c]);
    print_message("largest phi %.3g\n", phi_max);
    assert_true(phi_max > phi_min);
    /* The same preconditioner to a looser tolerance takes no more iterations. */
    print_message("iterations: GPU %d, CPU %d\n", gpu.iterations, cpu.iterations);
    assert_true(gpu.iterations > 0 && gpu.iterations <= cpu.iterations);
    double worst = 0.0;
    for (size_t i = 0; i < 4 * count; i++) {
        assert_true(isfinite(gpu.field[i]));
        worst = fmax(worst, fabs((double)gpu.field[i] - cpu.field[i]) / phi_max);
    }
    /* Nothing of the columns was built or kept. */
    size_t dense = 0, compressed = 0;
    light_gpu_bytes(lg, &dense, &compressed);
    size_t nodes = (size_t)s.resolution[0] * s.resolution[1] * s.resolution[2];
    assert_int_equal(dense, nodes * sizeof(float) + light_volume_bytes(&cpu));
    light_volume_finish(&gpu);
    light_volume_finish(&cpu);
    light_map_finish(&map);
    light_gpu_destroy(lg);
    ext_volume_finish(&vol);
    return worst;
}

static void test_gpu_matches_cpu(void **state)
{
    (void)state;
    const char *storm[] = {"scene.size=[48,48,24]", "lightmap.resolution=[48,48,48]"};
    const char *sphere[] = {"scene.kind=sphere", "scene.size=[24,24,24]", "scene.tau=30",
                            "lightmap.resolution=[32,32,32]", "light.elevation=20"};
    const char *layer[] = {"scene.kind=slab", "scene.size=[32,32,16]",
                           "scene.extent=[480,480,2]", "scene.tau=20",
                           "lightmap.resolution=[32,32,32]", "light.azimuth=120",
                           "light.elevation=40"};
    /* A cloud layer 100 m thick on the model's own uneven levels: the GPU's source samples
     * through the height table as the CPU's does. */
    char path[512], files[600];
    snprintf(path, sizeof(path), "%s", test_tmp_path("thin.nc"));
    assert_true(thin_layer_write(path));
    snprintf(files, sizeof(files), "data.files=[\"%s\"]", path);
    const char *levels[] = {"scene.kind=data", files, "data.vertical=native",
                            "lightmap.resolution=[16,16,64]", "light.elevation=30"};
    double e[4] = {gpu_vs_cpu(storm, 2, 0.5), gpu_vs_cpu(sphere, 5, 0.5),
                   gpu_vs_cpu(layer, 7, 0.5), gpu_vs_cpu(levels, 5, 0.01)};
    remove(path);
    print_message("diffuse light volume GPU vs CPU (of the largest phi): storm %.2g, sphere "
                  "%.2g, layer %.2g, native levels %.2g\n", e[0], e[1], e[2], e[3]);
    for (int i = 0; i < 4; i++)
        assert_true(e[i] < GPU_CPU_VOLUME_TOLERANCE);
}

static void render_sets(const char **sets, int n, struct image *img, unsigned *builds)
{
    struct config cfg;
    struct ext_volume vol = {0};
    test_config_from(&cfg, sets, n);
    test_upload_scene(renderer, &cfg, &vol);
    struct lightmaps al;
    assert_true(lightmaps_init(&al, &cfg));
    struct render_settings rs;
    scene_render_settings(&cfg, &rs);
    struct render_view v;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &v);
    struct session_stats st = {0};
    assert_true(lightmaps_update(&al, &cfg, renderer, &st));
    /* A second view of the same frame reuses the map and its volume. */
    assert_true(lightmaps_update(&al, &cfg, renderer, &st));
    struct gpu_texture out = {0};
    assert_true(renderer_draw(renderer, &rs, &v, &out));
    assert_true(renderer_read(&out, img));
    gpu_texture_finish(&out);
    *builds = st.light_builds;
    lightmaps_finish(&al);
    ext_volume_finish(&vol);
}

static double mean(const struct image *img)
{
    double s = 0.0;
    for (int i = 0; i < img->width * img->height; i++) {
        for (int c = 0; c < 3; c++) {
            float v = img->rgba[4 * i + c];
            assert_true(isfinite(v) && v >= 0.0f);
            s += v;
        }
    }
    return s / (3.0 * img->width * img->height);
}

static void test_eye_pass_reads_the_volume(void **state)
{
    (void)state;
    const char *base[] = {"scene.size=[48,48,24]", "lightmap.resolution=[48,48,48]",
                          "render.width=64", "render.height=48", "effects.multiple=off"};
    struct image off = {0}, cols = {0}, vol = {0}, vol_c = {0};
    unsigned builds = 0;
    render_sets(base, 5, &off, &builds);
    base[4] = "effects.multiple=on";
    render_sets(base, 5, &cols, &builds);
    base[4] = "effects.multiple=volume";
    render_sets(base, 5, &vol, &builds);
    assert_int_equal(builds, 1);
    const char *comp[] = {base[0], base[1], base[2], base[3], base[4],
                          "lightmap.mode=compressed"};
    render_sets(comp, 6, &vol_c, &builds);
    double m_off = mean(&off), m_cols = mean(&cols), m_vol = mean(&vol), m_vc = mean(&vol_c);
    print_message("storm means: single scattering %.4g, columns %.4g, volume %.4g (compressed "
                  "beam %.4g)\n", m_off, m_cols, m_vol, m_vc);
    /* The diffuse light makes the cloud brighter; the volume is not the columns. */
    assert_true(m_vol > 1.2 * m_off);
    assert_true(fabs(m_vol - m_cols) > 1e-3 * m_cols);
    /* Compressed storage compresses the beam only: the same volume, the picture within the
     * beam's epsilon. */
    assert_true(fabs(m_vc - m_vol) < 0.02 * m_vol);
    image_finish(&off);
    image_finish(&cols);
    image_finish(&vol);
    image_finish(&vol_c);
}

int main(void)
{
    log_set_level(LOG_WARN);
    ctx = test_gl_context_or_skip();
    renderer = renderer_create();
    if (!renderer)
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gpu_matches_cpu),
        cmocka_unit_test(test_eye_pass_reads_the_volume),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return rc;
}
