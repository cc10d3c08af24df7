/* The storm in its place on the GPU: height exaggeration scales the volume, the light map and
 * the terrain together; procedural detail is deterministic; the Katrina map survives missing
 * pieces. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "session/lightmaps.h"
#include "session/scene.h"
#include "session/stats.h"
#include "session/map.h"
#include "common/log.h"
#include "data/terrain.h"
#include "gpu/gpu.h"
#include "render/camera.h"
#include "render/render.h"
#include "render/terrain.h"

static struct gpu_context *ctx;

static void load(const char *path, const char **sets, int n, struct config *cfg)
{
    test_config_file(cfg, path, sets, n);
}

/* Renders CFG's volume with its light map, plus MESH (may be NULL), from VIEW into IMG. */
static void render(const struct config *cfg, struct render_mesh *mesh, bool ground_on,
                   const struct render_view *view, struct image *img)
{
    struct renderer *r = renderer_create();
    assert_non_null(r);
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(cfg, &vol));
    assert_true(renderer_set_optics(r, &cfg->optics.params));
    assert_true(renderer_set_volume(r, &vol));
    ext_volume_finish(&vol);
    struct lightmaps light;
    assert_true(lightmaps_init(&light, cfg));
    assert_true(lightmaps_update(&light, cfg, r, NULL));
    if (mesh)
        assert_true(renderer_add_mesh(r, mesh));
    struct render_settings s;
    scene_render_settings(cfg, &s);
    s.ground_on = ground_on;
    struct gpu_texture out = {0};
    assert_true(renderer_draw(r, &s, view, &out));
    assert_true(renderer_read(&out, img));
    gpu_texture_finish(&out);
    lightmaps_finish(&light);
    renderer_destroy(r);
}

/* A flat terrain at HEIGHT metres over [x0, x1] x [y0, y1]. */
static void flat_terrain(double x0, double x1, double y0, double y1, float height,
                         struct terrain *t)
{
    memset(t, 0, sizeof(*t));
    t->nx = t->ny = 2;
    t->x = malloc(2 * sizeof(double));
    t->y = malloc(2 * sizeof(double));
    t->height = malloc(4 * sizeof(float));
    t->kind = malloc(4);
    t->x[0] = x0;
    t->x[1] = x1;
    t->y[0] = y0;
    t->y[1] = y1;
    for (int i = 0; i < 4; i++) {
        t->height[i] = height;
        t->kind[i] = TERRAIN_BARREN;
    }
}

/* The shadow's centroid in world x on the plane z = PLANE_Z, seen straight down. */
static double shadow_centroid_x(const char **sets, int n, double k, double *darkest)
{
    struct config cfg;
    load(NULL, sets, n, &cfg);
    const double terrain_h = 1000.0;
    struct terrain t;
    flat_terrain(-200e3, 200e3, -200e3, 200e3, (float)terrain_h, &t);
    const float skirt[3] = {0.2f, 0.2f, 0.2f};
    struct render_mesh *mesh = render_terrain_mesh(&t, k, 1e6, skirt);
    assert_non_null(mesh);
    terrain_finish(&t);

    const int size = 128;
    const double eye[3] = {-10e3, 5e3, 300e3}, target[3] = {-10e3, 5e3, 0}, up[3] = {0, 1, 0};
    const double half = 30e3; /* half the width seen on the ground */
    double fov = 2.0 * atan(half / (eye[2] - terrain_h * k)) * 180.0 / M_PI;
    struct render_view view;
    camera_look_at(eye, target, up, fov, 100.0, 1e6, size, size, &view);
    struct image img;
    render(&cfg, mesh, false, &view, &img);
    render_mesh_destroy(mesh);

    /* Sunlit terrain: the image's corners. */
    double lit = 0.0;
    const int corners[4][2] = {{2, 2}, {size - 3, 2}, {2, size - 3}, {size - 3, size - 3}};
    for (int c = 0; c < 4; c++)
        lit += img.rgba[4 * (corners[c][1] * size + corners[c][0])] / 4.0;
    assert_true(lit > 0.0);
    double sw = 0.0, swx = 0.0;
    *darkest = 1.0;
    for (int y = 0; y < size; y++) {
        for (int x = 0; x < size; x++) {
            const float *p = img.rgba + 4 * (y * size + x);
            if (p[3] < 0.99f) /* the voxel itself is in front */
                continue;
            double w = fmax(0.0, 1.0 - p[0] / lit);
            *darkest = fmin(*darkest, p[0] / lit);
            if (w < 0.05)
                continue;
            double wx = eye[0] + ((x + 0.5) / size * 2.0 - 1.0) * half;
            sw += w;
            swx += w * wx;
        }
    }
    image_finish(&img);
    assert_true(sw > 0.0);
    return swx / sw;
}

static void test_exaggeration_keeps_the_shadow_under_its_cloud(void **state)
{
    /* One opaque voxel 5 km up over x = y = 5 km, the sun in the east at 35 degrees, a flat
     * terrain 1 km high (the beam's shadow: multiple scattering off).  Its shadow falls (5 km - 1 km) k cot(35 deg) west of it: with the
     * volume, the light map and the terrain all stretched by k, the offset grows k times. */
    const char *one[] = {"scene.kind=voxel", "scene.size=[9,9,9]", "scene.extent=[10,10,10]",
                         "scene.tau=50", "light.azimuth=90", "light.elevation=35",
                         "render.sky=[0,0,0]", "scene.height_exaggeration=1",
                         "effects.multiple=off"};
    const char *five[] = {"scene.kind=voxel", "scene.size=[9,9,9]", "scene.extent=[10,10,10]",
                          "scene.tau=50", "light.azimuth=90", "light.elevation=35",
                          "render.sky=[0,0,0]", "scene.height_exaggeration=5",
                          "effects.multiple=off"};
    double dark1, dark5;
    double x1 = shadow_centroid_x(one, 9, 1.0, &dark1);
    double x5 = shadow_centroid_x(five, 9, 5.0, &dark5);
    double cot = 1.0 / tan(35.0 * M_PI / 180.0);
    double expect1 = 5e3 - 1.0 * 4e3 * cot, expect5 = 5e3 - 5.0 * 4e3 * cot;
    assert_true(fabs(x1 - expect1) < 700.0);
    assert_true(fabs(x5 - expect5) < 1500.0);
    double ratio = (5e3 - x5) / (5e3 - x1);
    assert_true(ratio > 4.5 && ratio < 5.5);
    /* The terrain really is in shadow there (the light map reaches it). */
    assert_true(dark1 < 0.2 && dark5 < 0.2);
}

static void render_storm(const char **sets, int n, struct image *img)
{
    const char *base[16] = {"scene.size=[32,32,16]", "render.width=48", "render.height=36"};
    for (int i = 0; i < n; i++)
        base[3 + i] = sets[i];
    struct config cfg;
    load(NULL, base, 3 + n, &cfg);
    struct render_view view;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &view);
    render(&cfg, NULL, true, &view, img);
}

static bool same_image(const struct image *a, const struct image *b)
{
    return memcmp(a->rgba, b->rgba, (size_t)a->width * a->height * 4 * sizeof(float)) == 0;
}

static void test_detail_is_deterministic_and_zero_is_off(void **state)
{
    const char *on[] = {"effects.detail=on", "detail.seed=42"};
    const char *zero[] = {"effects.detail=on",     "detail.cloud=0", "detail.rain=0",
                          "detail.ice=0",          "detail.snow=0",  "detail.graupel=0"};
    const char *off[] = {"effects.detail=off"};
    struct image a, b, z, o;
    render_storm(on, 2, &a);
    render_storm(on, 2, &b);
    render_storm(zero, 6, &z);
    render_storm(off, 1, &o);
    assert_true(same_image(&a, &b)); /* same seed, same image */
    assert_true(same_image(&z, &o)); /* amount 0 is off */
    assert_false(same_image(&a, &o)); /* and detail does something */
    image_finish(&a);
    image_finish(&b);
    image_finish(&z);
    image_finish(&o);
}

static void test_katrina_map(void **state)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s/configs/katrina.cfg", ANVIL_SOURCE_DIR);
    const char *sets[] = {"map.graticule=true", "render.width=64", "render.height=48",
                          "lightmap.resolution=[32,32,32]"};
    struct config cfg;
    load(path, sets, 4, &cfg);
    struct renderer *r = renderer_create();
    assert_non_null(r);
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    assert_true(renderer_set_volume(r, &vol));
    ext_volume_finish(&vol);

    struct scene_map *m = scene_map_create(&cfg, r, NULL);
    assert_non_null(m);
    struct scene_map_info info;
    scene_map_get_info(m, &info);
    assert_true(info.terrain && info.placed);
    assert_true(info.coast_segments > 50); /* the Yucatan coast within the 300 km margin */
    assert_true(info.graticule_segments > 0 && info.labels >= 4);
    assert_float_equal(info.step_deg, 2.0, 0.0);
    struct render_settings s;
    scene_render_settings(&cfg, &s);
    scene_map_apply_settings(m, &s);
    assert_false(s.ground_on); /* the terrain and its skirt are the ground */
    struct render_view view;
    scene_camera_view(&cfg, 64, 48, &view);
    struct gpu_texture out = {0};
    assert_true(renderer_draw(r, &s, &view, &out));
    struct image img;
    assert_true(renderer_read(&out, &img));
    assert_int_equal(image_count_nonfinite(&img), 0);
    image_finish(&img);
    gpu_texture_finish(&out);
    scene_map_destroy(m, r);

    /* No GSHHG files: a message, no coastlines, the rest as before. */
    setenv("ANVIL_GSHHG_DIR", test_tmp_path("no_gshhg_here"), 1);
    m = scene_map_create(&cfg, r, NULL);
    unsetenv("ANVIL_GSHHG_DIR");
    assert_non_null(m);
    scene_map_get_info(m, &info);
    assert_int_equal(info.coast_segments, 0);
    assert_true(info.terrain);
    scene_map_destroy(m, r);

    /* Terrain off: the analytic flat ground stays. */
    assert_true(config_set(&cfg, "map.terrain=false"));
    m = scene_map_create(&cfg, r, NULL);
    assert_non_null(m);
    scene_map_get_info(m, &info);
    assert_false(info.terrain);
    scene_render_settings(&cfg, &s);
    scene_map_apply_settings(m, &s);
    assert_true(s.ground_on);
    scene_map_destroy(m, r);
    renderer_destroy(r);
}

static void test_synthetic_storm_placed_by_origin(void **state)
{
    /* No XLAT/XLONG: nothing placed unless map.use_origin; then Florida's coast appears. */
    const char *plain[] = {"map.graticule=true"};
    const char *placed[] = {"map.graticule=true", "map.use_origin=true", "map.origin=[25.5,-80.6]"};
    struct config cfg;
    struct renderer *r = renderer_create();
    assert_non_null(r);
    struct ext_volume vol = {0};
    load(NULL, plain, 1, &cfg);
    assert_true(scene_build_volume(&cfg, &vol));
    assert_true(renderer_set_volume(r, &vol));
    ext_volume_finish(&vol);
    struct scene_map *m = scene_map_create(&cfg, r, NULL);
    struct scene_map_info info;
    scene_map_get_info(m, &info);
    assert_false(info.placed || info.terrain);
    assert_int_equal(info.coast_segments + info.graticule_segments, 0);
    scene_map_destroy(m, r);
    load(NULL, placed, 3, &cfg);
    m = scene_map_create(&cfg, r, NULL);
    scene_map_get_info(m, &info);
    assert_true(info.placed && !info.terrain);
    assert_true(info.coast_segments > 10 && info.graticule_segments > 0);
    scene_map_destroy(m, r);
    renderer_destroy(r);
}

int main(void)
{
    log_set_level(LOG_NONE);
    ctx = test_gl_context_or_skip();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exaggeration_keeps_the_shadow_under_its_cloud),
        cmocka_unit_test(test_detail_is_deterministic_and_zero_is_off),
        cmocka_unit_test(test_katrina_map),
        cmocka_unit_test(test_synthetic_storm_placed_by_origin),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    gpu_context_destroy(ctx);
    return rc;
}
