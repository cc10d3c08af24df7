/* The model's own vertical levels on the GPU: the ray caster's transmittance straight down
 * through a thin cloud layer at 100-200 m of a synthetic WRF file (data.vertical = native) is
 * e^-tau of the file's layer to 1e-3; on 439 m uniform levels it is not; and the layer shows at
 * its height, seen edge on. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "thin_layer.h"

#include "common/log.h"
#include "config/config.h"
#include "render/render.h"
#include "session/scene.h"

static struct gpu_context *ctx;
static struct renderer *renderer;
static char path[1024];

/* Renders the layer file on VERTICAL levels from the camera SETS; IMG gets the image, VOL the
 * volume's grid and *TAU the optical depth of the layer straight up (from the voxels of level
 * 2, native only). */
static void render_layer(const char *vertical, const char *const *sets, int n, struct image *img,
                         struct grid3 *grid)
{
    char files[1100], vert[64];
    snprintf(files, sizeof(files), "data.files=[\"%s\"]", path);
    snprintf(vert, sizeof(vert), "%s", vertical);
    const char *all[24] = {"scene.kind=data", files, vert, "light.intensity=0",
                           "render.ground_on=false", "render.sky=[1,1,1]",
                           "effects.shadows=off"};
    int m = 7;
    for (int i = 0; i < n; i++)
        all[m++] = sets[i];
    struct config cfg;
    log_set_level(LOG_ERROR);
    test_config_from(&cfg, all, m);
    struct ext_volume vol = {0};
    test_upload_scene(renderer, &cfg, &vol);
    log_set_level(LOG_INFO);
    *grid = vol.grid;
    ext_volume_finish(&vol);
    struct render_settings s;
    scene_render_settings(&cfg, &s);
    struct render_view view;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &view);
    struct gpu_texture out = {0};
    assert_true(renderer_draw(renderer, &s, &view, &out));
    assert_true(renderer_read(&out, img));
    gpu_texture_finish(&out);
}

/* The file's layer optical depth: level 2's extinction over its 100 m (the CPU's own volume). */
static double layer_tau(void)
{
    char files[1100];
    snprintf(files, sizeof(files), "data.files=[\"%s\"]", path);
    const char *sets[] = {"scene.kind=data", files, "data.vertical=native"};
    struct config cfg;
    test_config_from(&cfg, sets, 3);
    struct ext_volume vol = {0};
    log_set_level(LOG_ERROR);
    assert_true(scene_build_volume(&cfg, &vol));
    log_set_level(LOG_INFO);
    size_t v = 36 * THIN_LAYER_LEVEL + 14;
    double tau = (vol.beta[2 * v] + vol.beta[2 * v + 1]) * (THIN_LAYER_TOP_M - THIN_LAYER_BOTTOM_M);
    ext_volume_finish(&vol);
    return tau;
}

static void test_transmittance_through_the_layer(void **state)
{
    (void)state;
    double tau = layer_tau();
    assert_true(tau > 0.5 && tau < 4.0);
    /* Straight down from 8 km over the domain's centre (3, 3 km), a narrow view. */
    const char *cam[] = {"camera.position=[3,3,8]", "camera.target=[3,3,0]",
                         "camera.up=[0,1,0]", "camera.fov=2", "render.width=16",
                         "render.height=16"};
    struct image img;
    struct grid3 g;
    render_layer("data.vertical=native", cam, 6, &img, &g);
    assert_true(grid3_stretched(&g));
    double worst = 0.0;
    for (int p = 0; p < 16 * 16; p++) { /* rays within 1.4 degrees of vertical */
        int x = p % 16, y = p / 16;
        double half = 2.0 * M_PI / 360.0;
        double tx = ((x + 0.5) / 8.0 - 1.0) * tan(half), ty = ((y + 0.5) / 8.0 - 1.0) * tan(half);
        double expect = exp(-tau * sqrt(1.0 + tx * tx + ty * ty));
        worst = fmax(worst, fabs(img.rgba[4 * p] - expect));
    }
    print_message("native: tau %.4f, e^-tau %.5f, centre pixel %.5f, worst |T - e^-tau| %.2e\n",
                  tau, exp(-tau), (double)img.rgba[4 * (8 * 16 + 8)], worst);
    assert_true(worst < 1e-3);
    image_finish(&img);

    /* 14 uniform levels of 439 m: the lowest cell smears the layer over twice its depth. */
    render_layer("data.levels=14", cam, 6, &img, &g);
    assert_false(grid3_stretched(&g));
    double t = img.rgba[4 * (8 * 16 + 8)];
    print_message("uniform 439 m: centre pixel %.5f (e^-tau %.5f)\n", t, exp(-tau));
    assert_true(fabs(t - exp(-tau)) > 0.05);
    image_finish(&img);
}

static void test_layer_at_its_height(void **state)
{
    (void)state;
    /* Edge on, from outside the domain's west side at 150 m, looking east along the layer: the
     * rows looking through 100-200 m are dimmed, rows well above (at 400 m and more, the next
     * level centres' hat ends at 275 m) are clear.  On 439 m levels cloud reaches far above. */
    const char *cam[] = {"camera.position=[-20,3,0.15]", "camera.target=[3,3,0.15]",
                         "camera.up=[0,0,1]", "camera.fov=4", "render.width=8",
                         "render.height=64"};
    double height[2][64];
    float trans[2][64];
    for (int mode = 0; mode < 2; mode++) {
        struct image img;
        struct grid3 g;
        render_layer(mode ? "data.levels=14" : "data.vertical=native", cam, 6, &img, &g);
        double half = 4.0 * M_PI / 360.0;
        for (int y = 0; y < 64; y++) {
            /* The row's ray reaches the domain's west edge (x = 0) at this height. */
            double ty = ((y + 0.5) / 32.0 - 1.0) * tan(half);
            height[mode][y] = 150.0 + 20000.0 * ty;
            trans[mode][y] = img.rgba[4 * (y * 8 + 4)];
        }
        image_finish(&img);
    }
    bool dim_in = false, clear_above = true, uniform_above = false;
    for (int y = 0; y < 64; y++) {
        if (fabs(height[0][y] - 150.0) < 20.0 && trans[0][y] < 0.5f)
            dim_in = true;
        if (height[0][y] > 400.0 && trans[0][y] < 0.999f)
            clear_above = false;
        if (height[1][y] > 400.0 && trans[1][y] < 0.9f)
            uniform_above = true;
    }
    for (int y = 0; y < 64; y += 4)
        print_message("%6.0f m: native %.4f uniform %.4f\n", height[0][y], (double)trans[0][y],
                      (double)trans[1][y]);
    assert_true(dim_in);
    assert_true(clear_above);
    assert_true(uniform_above);
}

static int setup(void **state)
{
    (void)state;
    snprintf(path, sizeof(path), "%s", test_tmp_path("thin.nc"));
    assert_true(thin_layer_write(path));
    ctx = test_gl_context_or_skip();
    renderer = renderer_create();
    assert_non_null(renderer);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_transmittance_through_the_layer),
        cmocka_unit_test(test_layer_at_its_height),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
