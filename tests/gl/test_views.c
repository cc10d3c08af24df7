/* View sets on EGL/llvmpipe: the Null HMD through its lens warp, twelve CAVE views from one
 * renderer with nothing built per frame, and an eye inside a homogeneous box. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "session/lightmaps.h"
#include "session/scene.h"
#include "session/stats.h"
#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "render/render.h"

static struct gpu_context *ctx;
static struct renderer *renderer;
static struct render_settings settings;

/* Uploads the scene of the default config with the --set strings SETS. */
static void scene(const char **sets, int n)
{
    struct config cfg;
    config_defaults(&cfg);
    for (int i = 0; i < n; i++)
        assert_true(config_set(&cfg, sets[i]));
    assert_true(config_validate(&cfg));
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    assert_true(renderer_set_volume(renderer, &vol));
    assert_true(renderer_set_optics(renderer, &cfg.optics.params));
    ext_volume_finish(&vol);
    scene_render_settings(&cfg, &settings);
}

static struct display *open_display(const struct display_config *cfg, int height)
{
    struct display *d = display_create(cfg, &(struct display_desc){
        .offscreen = true, .context = ctx, .height = height});
    assert_non_null(d);
    return d;
}

static void load_display(const char *name, struct display_config *cfg)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s/displays/%s", ANVIL_SOURCE_DIR, name);
    assert_true(display_config_load(path, cfg));
}

static void read_tex(const struct gpu_texture *t, struct image *img)
{
    assert_true(renderer_read(t, img));
}

static const float *px(const struct image *img, int x, int y)
{
    return &img->rgba[4 * ((size_t)y * img->width + x)];
}

/* Renders the HMD display CFG and returns the warped screen and the plain eyes side by side. */
static void render_hmd(const struct display_config *cfg, struct image *warped,
                       struct image *plain)
{
    struct display *d = open_display(cfg, 48);
    assert_int_equal(display_view_count(d), 2);
    assert_true(display_draw(d, renderer, &settings));
    assert_true(display_present(d, renderer, 1.0f));
    assert_int_equal(display_output_count(d), 1);
    const char *name = NULL;
    read_tex(display_output(d, 0, &name), warped);
    assert_string_equal(name, "screen");
    struct image eyes[2];
    read_tex(&display_view(d, 0)->target, &eyes[0]);
    read_tex(&display_view(d, 1)->target, &eyes[1]);
    assert_int_equal(warped->width, 2 * eyes[0].width);
    assert_int_equal(warped->height, eyes[0].height);
    assert_true(image_init(plain, warped->width, warped->height));
    image_blit(plain, &eyes[0], 0, 0);
    image_blit(plain, &eyes[1], eyes[0].width, 0);
    image_finish(&eyes[0]);
    image_finish(&eyes[1]);
    display_destroy(d);
}

static void test_null_hmd_both_eyes_through_warp(void **state)
{
    const char *sets[] = {"scene.size=[32,32,16]"};
    scene(sets, 1);
    struct display_config cfg;
    load_display("hmd.cfg", &cfg);
    struct image warped, plain;
    render_hmd(&cfg, &warped, &plain);
    int w = plain.width / 2, h = plain.height;
    assert_int_equal(image_count_nonfinite(&warped), 0);
    for (int e = 0; e < 2; e++) {
        /* Each eye is non-empty: lit, and not flat. */
        float lo = INFINITY, hi = -INFINITY;
        int differ = 0;
        for (int y = 0; y < h; y++) {
            for (int x = e * w; x < (e + 1) * w; x++) {
                float g = px(&warped, x, y)[1];
                lo = fminf(lo, g);
                hi = fmaxf(hi, g);
                if (fabsf(g - px(&plain, x, y)[1]) > 1e-3f * (1.0f + fabsf(g)))
                    differ++;
            }
        }
        assert_true(hi > 0.05f);
        assert_true(hi - lo > 0.05f);
        /* The warp moved most pixels, and the barrel blackens the corners that the plain
         * image fills with sky. */
        assert_true(differ > w * h / 8);
        const float *corner = px(&warped, e * w, h - 1), *plain_corner = px(&plain, e * w, h - 1);
        assert_float_equal(corner[0] + corner[1] + corner[2], 0.0f, 0.0);
        assert_true(plain_corner[2] > 0.1f);
    }
    image_finish(&warped);
    image_finish(&plain);

    /* The Null HMD's own lens is the identity: the pass must then reproduce the eyes. */
    cfg.hmd.distortion_set = cfg.hmd.aberration_set = false;
    render_hmd(&cfg, &warped, &plain);
    for (int i = 0; i < plain.width * plain.height * 4; i++) {
        if (i % 4 == 3)
            continue;
        assert_float_equal(warped.rgba[i], plain.rgba[i], 1e-4 * (1.0 + fabs(plain.rgba[i])));
    }
    image_finish(&warped);
    image_finish(&plain);
}

static int binds;

static void count_bind(const struct render_light *light, const struct gpu_program *prog)
{
    binds++;
}

/* Twelve views per frame: exactly twelve renderer_draw calls (each binding the shared light
 * map once for each of its programs: the two passes of empty-space skipping), and nothing else: no GPU memory made after the first frame, the volume untouched.
 * The light map build count itself is checked end to end by cli/test_display.sh
 * (light_map_builds == 1 for 12 views) once the build is wired into the app. */
static void test_twelve_views_draw_only(void **state)
{
    const char *sets[] = {"scene.size=[24,24,12]"};
    scene(sets, 1);
    struct display_config cfg;
    load_display("cave6.cfg", &cfg);
    struct display *d = open_display(&cfg, 16);
    assert_int_equal(display_view_count(d), 12);
    const struct render_light hook = {.defines = NULL, .bind = count_bind};
    renderer_set_light(renderer, &hook);
    unsigned volume = renderer_volume_texture(renderer)->id;
    for (int frame = 0; frame < 3; frame++) {
        binds = 0;
        unsigned before = renderer_stats(renderer)->views;
        size_t bytes = gpu_bytes_allocated();
        assert_true(display_update(d, frame * 0.1));
        assert_true(display_draw(d, renderer, &settings));
        assert_true(display_present(d, renderer, 1.0f));
        assert_int_equal(renderer_stats(renderer)->views - before, 12);
        assert_int_equal(binds, 12 * (settings.no_skip ? 1 : 2));
        if (frame > 0)
            assert_int_equal(gpu_bytes_allocated(), bytes);
        assert_int_equal(renderer_volume_texture(renderer)->id, volume);
    }
    for (int i = 0; i < 12; i++)
        assert_non_null(display_view(d, i)->target.id ? display_view(d, i) : NULL);
    renderer_set_light(renderer, NULL);
    display_destroy(d);
}

/* The real light map: three frames of twelve views, one build (light_map_builds == 1); a sun
 * change rebuilds once more, not once per view. */
static void test_light_map_builds_once_for_12_views(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    const char *sets[] = {"scene.size=[24,24,12]", "lightmap.mode=dense",
                          "lightmap.resolution=[16,16,16]"};
    for (int i = 0; i < 3; i++)
        assert_true(config_set(&cfg, sets[i]));
    assert_true(config_validate(&cfg));
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    assert_true(renderer_set_volume(renderer, &vol));
    ext_volume_finish(&vol);
    scene_render_settings(&cfg, &settings);
    struct lightmaps light = {0};
    struct session_stats stats = {0};
    assert_true(lightmaps_init(&light, &cfg));
    light.generation++;
    struct display_config dcfg;
    load_display("cave6.cfg", &dcfg);
    struct display *d = open_display(&dcfg, 16);
    for (int frame = 0; frame < 3; frame++) {
        assert_true(lightmaps_update(&light, &cfg, renderer, &stats));
        assert_true(display_update(d, frame * 0.1));
        assert_true(display_draw(d, renderer, &settings));
    }
    assert_int_equal(display_view_count(d), 12);
    assert_int_equal(stats.light_builds, 1);
    cfg.light.elevation_deg = 20.0;
    scene_render_settings(&cfg, &settings);
    for (int frame = 0; frame < 2; frame++) {
        assert_true(lightmaps_update(&light, &cfg, renderer, &stats));
        assert_true(display_draw(d, renderer, &settings));
    }
    assert_int_equal(stats.light_builds, 2);
    display_destroy(d);
    renderer_set_light(renderer, NULL);
    lightmaps_finish(&light);
}

/* A headless display with one horizontal screen 0.1 tracker m above (UP) or below the head at
 * height HEAD_Y; 1 tracker m = 1 km; the world point (5, 5, ORIGIN_Z) km at the tracker
 * origin. */
static void box_display(struct display_config *cfg, bool up, double head_y, double origin_z)
{
    display_config_defaults(cfg);
    cfg->type = DISPLAY_TYPE_HEADLESS;
    cfg->near_m = 1e-4; /* 0.1 m in the world */
    cfg->far_m = 100.0;
    cfg->head.position[0] = cfg->head.position[2] = 0.0;
    cfg->head.position[1] = head_y;
    cfg->navigation = (struct display_navigation){.scale = 1e-3, .origin_km = {5, 5, origin_z}};
    struct display_wall *w = &cfg->walls[0];
    double y = head_y + (up ? 0.1 : -0.1), s = up ? 1.0 : -1.0;
    /* Seen from the head: x to the right, the far edge up the image. */
    double ll[3] = {-0.1, y, -0.1 * s}, lr[3] = {0.1, y, -0.1 * s}, ul[3] = {-0.1, y, 0.1 * s};
    memcpy(w->lower_left, ll, sizeof(ll));
    memcpy(w->lower_right, lr, sizeof(lr));
    memcpy(w->upper_left, ul, sizeof(ul));
    w->size[0] = w->size[1] = 33;
    w->stereo = DISPLAY_STEREO_MONO;
}

static void render_one(const struct display_config *cfg, struct image *img)
{
    struct display *d = open_display(cfg, 33);
    assert_int_equal(display_view_count(d), 1);
    assert_true(display_view(d, 0)->visible);
    assert_true(display_draw(d, renderer, &settings));
    read_tex(&display_view(d, 0)->target, img);
    display_destroy(d);
}

static void test_eye_inside_box_sees_to_far_face(void **state)
{
    /* 10 x 10 x 1 km, tau 2 vertically: beta = 0.002 / m.  No sun, no ground, sky 1: a pixel
     * is the transmittance along its ray. */
    const char *sets[] = {"scene.kind=slab", "scene.size=[16,16,8]", "scene.extent=[10,10,1]",
                          "scene.tau=2", "light.intensity=0", "render.ground_on=false",
                          "render.sky=[1,1,1]"};
    scene(sets, 7);
    const double beta = 2.0 / 1000.0;
    struct display_config cfg;
    box_display(&cfg, true, 0.0, 0.5); /* eye at 500 m, in the middle, looking up */
    struct image img;
    render_one(&cfg, &img);
    /* From the near plane (0.1 m above the eye) to the top face, along each ray. */
    for (int k = 0; k < 2; k++) {
        int x = k == 0 ? 16 : 0, y = k == 0 ? 16 : 0;
        double nx = ((x + 0.5) / 33.0 * 2.0 - 1.0) * 0.1, nz = ((y + 0.5) / 33.0 * 2.0 - 1.0) * 0.1;
        double cosang = 0.1 / sqrt(nx * nx + 0.01 + nz * nz);
        double expect = exp(-beta * (500.0 - 0.1) / cosang);
        double got = px(&img, x, y)[1];
        if (fabs(got - expect) > 1e-3 * expect)
            fail_msg("pixel (%d, %d): %g, expected exp(-beta d) = %g", x, y, got, expect);
        /* Not the whole box's transmittance (what starting at the box entry would give). */
        assert_true(got > 2.0 * exp(-beta * 1000.0 / cosang));
    }
    image_finish(&img);
}

static void test_no_popping_across_a_face(void **state)
{
    /* Sun on: scattering and transmittance both change smoothly as the eye crosses the top
     * face at 1 km, looking down into the box. */
    const char *sets[] = {"scene.kind=slab", "scene.size=[16,16,8]", "scene.extent=[10,10,1]",
                          "scene.tau=2", "render.sky=[0.3,0.45,0.75]"};
    scene(sets, 5);
    struct display_config cfg;
    struct image outside, inside, deep;
    box_display(&cfg, false, 0.002, 1.0); /* 2 m above the top face */
    render_one(&cfg, &outside);
    box_display(&cfg, false, -0.002, 1.0); /* 2 m below it */
    render_one(&cfg, &inside);
    box_display(&cfg, false, -0.5, 1.0); /* 500 m below: must differ, or the test is blind */
    render_one(&cfg, &deep);
    double max_rel = 0.0, deep_rel = 0.0;
    for (int i = 0; i < outside.width * outside.height; i++) {
        for (int c = 0; c < 3; c++) {
            double a = outside.rgba[4 * i + c], b = inside.rgba[4 * i + c];
            double e = deep.rgba[4 * i + c];
            assert_true(a > 0.0);
            max_rel = fmax(max_rel, fabs(a - b) / a);
            deep_rel = fmax(deep_rel, fabs(a - e) / a);
        }
    }
    if (max_rel > 0.01)
        fail_msg("crossing the face changes a pixel by %.1f%%", 100.0 * max_rel);
    if (deep_rel < 0.05)
        fail_msg("500 m deeper changes the image by only %.1f%%", 100.0 * deep_rel);
    image_finish(&outside);
    image_finish(&inside);
    image_finish(&deep);
}

int main(void)
{
    log_set_level(LOG_WARN);
    ctx = test_gl_context_or_skip();
    renderer = renderer_create();
    if (!renderer)
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_null_hmd_both_eyes_through_warp),
        cmocka_unit_test(test_twelve_views_draw_only),
        cmocka_unit_test(test_light_map_builds_once_for_12_views),
        cmocka_unit_test(test_eye_inside_box_sees_to_far_face),
        cmocka_unit_test(test_no_popping_across_a_face),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return rc;
}
