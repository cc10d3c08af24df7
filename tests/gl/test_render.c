/* Eye pass on EGL/llvmpipe: exact background, Beer-Lambert through a slab, a finite storm. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "session/lightmaps.h"
#include "session/scene.h"
#include "session/stats.h"
#include "common/log.h"
#include "common/progress.h"
#include "gpu/gpu.h"
#include "render/render.h"

static struct gpu_context *ctx;
static struct renderer *renderer;

/* Renders CFG (after the --set strings) into IMG. */
static void render_config(struct config *cfg, const char **sets, int n, struct image *img)
{
    config_defaults(cfg);
    for (int i = 0; i < n; i++)
        assert_true(config_set(cfg, sets[i]));
    assert_true(config_validate(cfg));
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(cfg, &vol));
    assert_true(renderer_set_volume(renderer, &vol));
    assert_true(renderer_set_optics(renderer, &cfg->optics.params));
    ext_volume_finish(&vol);
    struct render_settings s;
    scene_render_settings(cfg, &s);
    struct render_view view;
    scene_camera_view(cfg, cfg->render.width, cfg->render.height, &view);
    struct gpu_texture out = {0};
    assert_true(renderer_draw(renderer, &s, &view, &out));
    assert_true(renderer_read(&out, img));
    gpu_texture_finish(&out);
}

static void test_empty_scene_is_background(void **state)
{
    struct config cfg;
    struct image img;
    const char *sets[] = {"scene.kind=empty", "scene.size=[16,16,8]", "render.width=64",
                          "render.height=48", "render.ground_on=false",
                          "render.sky=[0.25,0.5,0.75]"};
    render_config(&cfg, sets, 6, &img);
    for (int i = 0; i < img.width * img.height; i++) {
        assert_true(img.rgba[4 * i] == 0.25f);
        assert_true(img.rgba[4 * i + 1] == 0.5f);
        assert_true(img.rgba[4 * i + 2] == 0.75f);
        assert_true(img.rgba[4 * i + 3] == 1.0f);
    }
    image_finish(&img);

    /* With the ground: below the horizon each pixel is albedo (4 sun sin(elevation) + sky),
     * a Lambertian surface under a sun of irradiance 4 pi sun and a uniform sky. */
    const char *sets2[] = {"scene.kind=empty", "scene.size=[16,16,8]", "render.width=64",
                           "render.height=48", "render.sky=[0.25,0.5,0.75]",
                           "render.ground=[0.5,0.5,0.5]", "light.elevation=30",
                           "light.color=[1,1,1]", "light.intensity=2"};
    render_config(&cfg, sets2, 9, &img);
    float ground = 0.5f * (4.0f * 2.0f * sinf(30.0f * (float)M_PI / 180.0f) + 0.25f);
    int bottom = 2 * 4; /* lower-left pixel looks at the ground from the default camera */
    assert_float_equal(img.rgba[bottom], ground, 1e-5);
    /* Top row looks at the sky. */
    int top = 4 * (img.width * (img.height - 1) + img.width / 2);
    assert_float_equal(img.rgba[top], 0.25f, 0.0f);
    image_finish(&img);
}

static void test_slab_transmits_exp_minus_tau(void **state)
{
    /* Looking straight down through a 10 x 10 x 1 km slab of optical depth 2 onto the sky
     * (no ground, no sun): the background arrives attenuated by exp(-tau / cos(angle)). */
    struct config cfg;
    struct image img;
    const char *sets[] = {"scene.kind=slab", "scene.size=[16,16,8]",
                          "scene.extent=[10,10,1]", "scene.tau=2", "light.intensity=0",
                          "render.ground_on=false", "render.sky=[1,1,1]",
                          "camera.position=[5,5,3]", "camera.target=[5,5,0]",
                          "camera.up=[0,1,0]", "camera.fov=30", "render.width=64",
                          "render.height=64"};
    render_config(&cfg, sets, 13, &img);
    /* The four centre pixels straddle the axis; their rays are 0.33 degrees off vertical. */
    double half = 30.0 * M_PI / 360.0;
    for (int dy = 31; dy <= 32; dy++) {
        for (int dx = 31; dx <= 32; dx++) {
            double nx = (dx + 0.5) / 32.0 - 1.0, ny = (dy + 0.5) / 32.0 - 1.0;
            double tx = nx * tan(half), ty = ny * tan(half);
            double cosang = 1.0 / sqrt(1.0 + tx * tx + ty * ty);
            double expect = exp(-2.0 / cosang);
            float got = img.rgba[4 * (dy * 64 + dx)];
            assert_true(fabs(got - expect) / expect < 1e-3);
        }
    }
    /* A corner pixel: a slanted ray, a longer path (tests anisotropy and path length). */
    {
        double nx = 0.5 / 32.0 - 1.0, ny = 0.5 / 32.0 - 1.0;
        double tx = nx * tan(half), ty = ny * tan(half);
        double cosang = 1.0 / sqrt(1.0 + tx * tx + ty * ty);
        double expect = exp(-2.0 / cosang);
        float got = img.rgba[0];
        assert_true(fabs(got - expect) / expect < 1e-3);
        assert_true(got < exp(-2.0) * 0.99);
    }
    image_finish(&img);
}

static void test_tiny_step_is_bounded_and_exact(void **state)
{
    /* A millimetre step through a kilometre of slab would be a million steps a pixel: the
     * renderer caps the count, and equal steps keep the optical depth exact. */
    struct config cfg;
    struct image img;
    const char *sets[] = {"scene.kind=slab", "scene.size=[8,8,4]", "scene.extent=[10,10,1]",
                          "scene.tau=2", "light.intensity=0", "render.ground_on=false",
                          "render.sky=[1,1,1]", "camera.position=[5,5,3]",
                          "camera.target=[5,5,0]", "camera.up=[0,1,0]", "camera.fov=2",
                          "render.width=8", "render.height=8", "render.step=0.001"};
    double start = time_now_ms();
    render_config(&cfg, sets, 14, &img);
    print_message("1 mm step: %.0f ms\n", time_now_ms() - start);
    float got = img.rgba[4 * (4 * 8 + 4)];
    assert_true(fabs(got - exp(-2.0)) / exp(-2.0) < 1e-3);
    image_finish(&img);
}

static void test_storm_is_finite_and_not_blank(void **state)
{
    struct config cfg;
    struct image img;
    const char *sets[] = {"scene.size=[64,64,32]", "render.width=96", "render.height=72"};
    render_config(&cfg, sets, 3, &img);
    assert_int_equal(image_count_nonfinite(&img), 0);
    /* The storm hides part of the background: some pixels' transmittance is far below 1,
     * and the image is not flat. */
    int covered = 0;
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < img.width * img.height; i++) {
        if (img.rgba[4 * i + 3] < 0.5f)
            covered++;
        lo = fminf(lo, img.rgba[4 * i]);
        hi = fmaxf(hi, img.rgba[4 * i]);
    }
    assert_true(covered > img.width * img.height / 50);
    assert_true(hi - lo > 0.05f);
    image_finish(&img);
}

static void test_sun_along_axis_is_finite(void **state)
{
    struct config cfg;
    struct image img;
    const char *sets[] = {"scene.kind=sphere", "scene.size=[16,16,16]",
                          "scene.extent=[10,10,10]", "light.elevation=90",
                          "light.azimuth=0", "camera.position=[5,-20,5]",
                          "camera.target=[5,5,5]", "render.width=32", "render.height=32"};
    render_config(&cfg, sets, 9, &img);
    assert_int_equal(image_count_nonfinite(&img), 0);
    image_finish(&img);
}

/* A view drawn in bands of rows (with a progress to count them) is the view drawn at once, bit
 * for bit, and the rows are all counted. */
/* The tone map on the GPU for files (renderer_tonemap_read) gives image_tonemap's bytes, every
 * one: on a ramp of radiance over six decades at both exposures; NaN, infinities and negative
 * values as the CPU takes them; the non-finite pixels counted as image_count_nonfinite counts
 * them.  (Before the steps, the shader's own pow put about 0.1 % of the ramp's values one
 * step off.) */
static void test_gpu_tonemap_matches_cpu(void **state)
{
    const int w = 256, h = 64;
    struct image img;
    assert_true(image_init(&img, w, h));
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *p = img.rgba + 4 * ((size_t)y * w + x);
            float l = 1e-4f * powf(10.0f, 6.0f * (float)x / (float)(w - 1));
            p[0] = l;
            p[1] = l * (0.5f + (float)y / (float)h);
            p[2] = l * 0.01f;
            p[3] = 1.0f;
        }
    const float special[] = {NAN, INFINITY, -INFINITY, -1.0f, 0.0f, 3.4e38f};
    for (int i = 0; i < 6; i++)
        img.rgba[4 * i + 1] = special[i]; /* the first six pixels of the bottom row */
    struct gpu_texture tex = {0};
    int size[3] = {w, h, 1};
    assert_true(gpu_texture_init(&tex, 2, size, GPU_RGBA32F, img.rgba));
    uint8_t *gpu = malloc((size_t)w * h * 4);
    assert_non_null(gpu);
    const float exposures[] = {1.0f, 7.5f};
    for (int e = 0; e < 2; e++) {
        size_t nonfinite = 99;
        assert_true(renderer_tonemap_read(renderer, &tex, exposures[e], gpu, &nonfinite));
        assert_int_equal(nonfinite, image_count_nonfinite(&img));
        assert_int_equal(nonfinite, 3);
        int differ = 0, worst = 0;
        for (size_t i = 0; i < (size_t)w * h; i++) {
            for (int c = 0; c < 3; c++) {
                int cpu = image_tonemap(img.rgba[4 * i + c], exposures[e]);
                int d = abs(cpu - gpu[4 * i + c]);
                worst = d > worst ? d : worst;
                differ += d != 0;
            }
            assert_int_equal(gpu[4 * i + 3], 255);
        }
        for (int i = 0; i < 6; i++)
            assert_int_equal(gpu[4 * i + 1], image_tonemap(special[i], exposures[e]));
        if (differ)
            print_message("exposure %g: %d of %d values differ from the CPU's, by at most %d\n",
                          exposures[e], differ, w * h * 3, worst);
        assert_int_equal(differ, 0);
    }
    free(gpu);
    gpu_texture_finish(&tex);
    image_finish(&img);
}

/* The steps are the tone map's: ascending; about each one (4096 floats on either side of it)
 * and at a million random radiances and exposures the steps at or below exposure x radiance
 * count image_tonemap's value, and that value is the sRGB curve's of x / (1 + x), taken in
 * double, rounded to nearest (the operator's formula, which the steps stand for). */
static unsigned steps_count(const float *steps, float x)
{
    unsigned v = 0;
    while (v < IMAGE_TONEMAP_STEPS && x >= steps[v])
        v++;
    return v;
}

static void test_tonemap_steps_are_the_cpu_values(void **state)
{
    (void)state;
    float steps[IMAGE_TONEMAP_STEPS];
    image_tonemap_steps(steps);
    for (int k = 0; k < IMAGE_TONEMAP_STEPS; k++) {
        if (k > 0)
            assert_true(steps[k] >= steps[k - 1]);
        float lo = steps[k], hi = steps[k];
        for (int i = 0; i < 4096; i++) {
            lo = nextafterf(lo, 0.0f);
            hi = nextafterf(hi, INFINITY);
            assert_int_equal(image_tonemap(lo, 1.0f), steps_count(steps, lo));
            assert_int_equal(image_tonemap(hi, 1.0f), steps_count(steps, hi));
        }
        assert_int_equal(image_tonemap(steps[k], 1.0f), steps_count(steps, steps[k]));
    }
    uint32_t seed = 12345u;
    for (int i = 0; i < 1000000; i++) {
        seed = seed * 1664525u + 1013904223u;
        float l = 1e-6f * powf(10.0f, 9.0f * (float)(seed >> 8) / 16777216.0f);
        seed = seed * 1664525u + 1013904223u;
        float e = 0.01f * powf(10.0f, 3.0f * (float)(seed >> 8) / 16777216.0f);
        float x = e * l;
        assert_int_equal(image_tonemap(l, e), steps_count(steps, x));
        double c = (double)x / (1.0 + (double)x);
        double srgb = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
        assert_int_equal(image_tonemap(l, e), (int)lround(srgb * 255.0));
    }
}

/* At each step, the float below it and the float above it, on the GPU as on the CPU. */
static void test_gpu_tonemap_at_the_steps(void **state)
{
    (void)state;
    float steps[IMAGE_TONEMAP_STEPS];
    image_tonemap_steps(steps);
    const int w = IMAGE_TONEMAP_STEPS, h = 1;
    struct image img;
    assert_true(image_init(&img, w, h));
    for (int k = 0; k < w; k++) {
        float *p = img.rgba + 4 * k;
        p[0] = nextafterf(steps[k], 0.0f);
        p[1] = steps[k];
        p[2] = nextafterf(steps[k], INFINITY);
        p[3] = 1.0f;
    }
    struct gpu_texture tex = {0};
    int size[3] = {w, h, 1};
    assert_true(gpu_texture_init(&tex, 2, size, GPU_RGBA32F, img.rgba));
    uint8_t gpu[4 * IMAGE_TONEMAP_STEPS];
    assert_true(renderer_tonemap_read(renderer, &tex, 1.0f, gpu, NULL));
    for (int k = 0; k < w; k++)
        for (int c = 0; c < 3; c++)
            assert_int_equal(gpu[4 * k + c], image_tonemap(img.rgba[4 * k + c], 1.0f));
    gpu_texture_finish(&tex);
    image_finish(&img);
}

static void test_bands_are_one_view(void **state)
{
    struct config cfg;
    struct image once, banded;
    const char *sets[] = {"scene.size=[32,32,16]", "render.width=72", "render.height=300"};
    render_config(&cfg, sets, 3, &once);
    struct progress pr;
    progress_begin(&pr, "render", "row", 300);
    renderer_set_progress(renderer, &pr);
    render_config(&cfg, sets, 3, &banded);
    renderer_set_progress(renderer, NULL);
    assert_int_equal(pr.done, 300);
    assert_memory_equal(once.rgba, banded.rgba, sizeof(float) * 4 * 72 * 300);
    image_finish(&once);
    image_finish(&banded);
}

int main(void)
{
    log_set_level(LOG_WARN);
    ctx = test_gl_context_or_skip();
    renderer = renderer_create();
    if (!renderer)
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_empty_scene_is_background),
        cmocka_unit_test(test_slab_transmits_exp_minus_tau),
        cmocka_unit_test(test_tiny_step_is_bounded_and_exact),
        cmocka_unit_test(test_storm_is_finite_and_not_blank),
        cmocka_unit_test(test_sun_along_axis_is_finite),
        cmocka_unit_test(test_bands_are_one_view),
        cmocka_unit_test(test_gpu_tonemap_matches_cpu),
        cmocka_unit_test(test_tonemap_steps_are_the_cpu_values),
        cmocka_unit_test(test_gpu_tonemap_at_the_steps),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return rc;
}
