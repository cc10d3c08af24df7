/* Opaque geometry drawn before the ray cast: rays stop at its depth and see its colour. */
#include <math.h>
#include <string.h>

#include "testutil.h"

#include "session/lightmaps.h"
#include "session/scene.h"
#include "session/stats.h"
#include "common/log.h"
#include "gpu/gpu.h"
#include "render/camera.h"
#include "render/render.h"

static struct gpu_context *ctx;
static struct renderer *renderer;

/* A horizontal quad at height Z (metres) over [X0, X1] x [Y0, Y1] with colour C. */
static struct render_mesh *quad(double x0, double x1, double y0, double y1, double z,
                                const float c[3], bool emissive)
{
    struct render_vertex v[4];
    const double xy[4][2] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    for (int i = 0; i < 4; i++) {
        v[i] = (struct render_vertex){
            .pos = {(float)xy[i][0], (float)xy[i][1], (float)z},
            .normal = {0, 0, 1},
            .color = {c[0], c[1], c[2], 1},
        };
    }
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    return render_mesh_create(v, 4, idx, 6, false, emissive);
}

static void draw(const char **sets, int n, struct image *img)
{
    struct config cfg;
    config_defaults(&cfg);
    for (int i = 0; i < n; i++)
        assert_true(config_set(&cfg, sets[i]));
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    assert_true(renderer_set_volume(renderer, &vol));
    ext_volume_finish(&vol);
    struct render_settings s;
    scene_render_settings(&cfg, &s);
    struct render_view view;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &view);
    renderer_set_light(renderer, NULL);
    struct gpu_texture out = {0};
    assert_true(renderer_draw(renderer, &s, &view, &out));
    assert_true(renderer_read(&out, img));
    gpu_texture_finish(&out);
}

static const char *slab[] = {"scene.kind=slab",        "scene.size=[16,16,8]",
                             "scene.extent=[10,10,2]", "scene.tau=2",
                             "light.intensity=0",      "render.ground_on=false",
                             "render.sky=[0,0,0]",     "camera.position=[5,5,6]",
                             "camera.target=[5,5,0]",  "camera.up=[0,1,0]",
                             "camera.fov=20",          "render.width=32",
                             "render.height=32"};

static void test_quad_inside_slab_is_attenuated_to_its_depth(void **state)
{
    /* An emissive quad half way down the slab: the eye sees it through tau / 2. */
    const float c[3] = {2.0f, 1.0f, 0.5f};
    struct render_mesh *m = quad(1e3, 9e3, 1e3, 9e3, 1e3, c, true);
    assert_non_null(m);
    assert_true(renderer_add_mesh(renderer, m));
    struct image img;
    draw(slab, 13, &img);
    /* Centre pixels: rays 0.3 degrees off vertical. */
    double cosang = 1.0 / sqrt(1.0 + 2.0 * pow(0.5 / 16.0 * tan(10.0 * M_PI / 180.0), 2));
    double t = exp(-1.0 / cosang);
    const float *p = img.rgba + 4 * (16 * 32 + 16);
    for (int ch = 0; ch < 3; ch++)
        assert_true(fabs(p[ch] - c[ch] * t) / (c[ch] * t) < 1e-3);
    image_finish(&img);

    /* Hidden, the slab is seen through whole: the sky is black, so nothing arrives. */
    render_mesh_set_visible(m, false);
    draw(slab, 13, &img);
    assert_true(img.rgba[4 * (16 * 32 + 16)] == 0.0f);
    image_finish(&img);
    renderer_remove_mesh(renderer, m);
    render_mesh_destroy(m);
}

static void test_quad_above_volume_hides_it(void **state)
{
    /* A quad between the eye and the slab: exactly its colour, nothing of the volume. */
    const float c[3] = {0.25f, 0.5f, 0.75f};
    struct render_mesh *m = quad(0, 10e3, 0, 10e3, 3e3, c, true);
    assert_true(renderer_add_mesh(renderer, m));
    struct image img;
    draw(slab, 13, &img);
    for (int i = 0; i < img.width * img.height; i++) {
        assert_true(img.rgba[4 * i] == 0.25f && img.rgba[4 * i + 1] == 0.5f);
        assert_true(img.rgba[4 * i + 3] == 1.0f); /* no volume in front */
    }
    image_finish(&img);
    renderer_remove_mesh(renderer, m);
    render_mesh_destroy(m);
}

static void test_lit_quad_matches_the_ground_model(void **state)
{
    /* A Lambertian quad at z = 0 shades exactly like the built-in ground plane. */
    const char *sets[] = {"scene.kind=empty", "scene.size=[8,8,8]", "render.width=32",
                          "render.height=32", "camera.position=[5,5,20]",
                          "camera.target=[5,5,0]", "camera.up=[0,1,0]", "camera.fov=20",
                          "render.ground=[0.5,0.5,0.5]", "light.elevation=30",
                          "light.color=[1,1,1]", "light.intensity=2", "render.sky=[0.1,0.1,0.1]"};
    struct image ground, mesh;
    draw(sets, 13, &ground);
    const float c[3] = {0.5f, 0.5f, 0.5f};
    struct render_mesh *m = quad(-50e3, 50e3, -50e3, 50e3, 0.0, c, false);
    assert_true(renderer_add_mesh(renderer, m));
    draw(sets, 13, &mesh);
    double expect = 0.5 * (4.0 * 2.0 * 0.5 + 0.1);
    assert_float_equal(ground.rgba[4 * (16 * 32 + 16)], expect, 1e-5);
    assert_float_equal(mesh.rgba[4 * (16 * 32 + 16)], expect, 1e-5);
    image_finish(&ground);
    image_finish(&mesh);
    renderer_remove_mesh(renderer, m);
    render_mesh_destroy(m);
}

int main(void)
{
    log_set_level(LOG_WARN);
    ctx = test_gl_context_or_skip();
    renderer = renderer_create();
    if (!renderer)
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quad_inside_slab_is_attenuated_to_its_depth),
        cmocka_unit_test(test_quad_above_volume_hides_it),
        cmocka_unit_test(test_lit_quad_matches_the_ground_model),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return rc;
}
