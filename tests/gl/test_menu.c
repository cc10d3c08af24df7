/* The menu in the CAVE: drawn as opaque geometry, it appears in every wall (and eye) that sees
 * it, at one world position: points of the panel projected with each view's matrices land on
 * pixels that show the panel's own texels there. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cglm/cglm.h>

#include "session/menu_view.h"
#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "menu/menu.h"
#include "render/render.h"

/* Whether the panel image is uniform in a (2R+1)^2 block around texel (X, Y). */
static bool uniform_at(const uint8_t *px, int w, int h, int x, int y, int r)
{
    if (x - r < 0 || y - r < 0 || x + r >= w || y + r >= h)
        return false;
    const uint8_t *c = &px[4 * (y * w + x)];
    for (int j = -r; j <= r; j++)
        for (int i = -r; i <= r; i++)
            if (memcmp(&px[4 * ((y + j) * w + x + i)], c, 4) != 0)
                return false;
    return true;
}

static void test_menu_in_cave4(void **state)
{
    struct gpu_context *ctx = test_gl_context_or_skip();
    struct display_config dcfg;
    assert_true(display_config_load(ANVIL_SOURCE_DIR "/displays/cave4.cfg", &dcfg));
    struct display *d = display_create(&dcfg, &(struct display_desc){
        .offscreen = true, .context = ctx, .height = 192});
    assert_non_null(d);
    struct renderer *r = renderer_create();
    assert_non_null(r);
    struct ext_volume vol;
    struct grid3 g = {.n = {4, 4, 4}, .spacing = {1000, 1000, 1000}};
    assert_true(ext_volume_init(&vol, &g)); /* empty: the sky behind the panel */
    assert_true(renderer_set_volume(r, &vol));
    ext_volume_finish(&vol);

    struct menu_model model = {.speed = 2, .step_count = 6, .light_resolution = 64,
                               .epsilon = 0.01};
    transfer_defaults(&model.transfer, TRANSFER_FIELD_QVAPOR);
    struct menu *m = menu_create(NULL, &model);
    assert_non_null(m);
    /* Low in the front-left corner, turned toward the user: front, left and floor walls see
     * parts of it. */
    const float c[3] = {-1.1f, 0.45f, -1.1f};
    const float right[3] = {0.7071068f, 0.0f, -0.7071068f}, up[3] = {0, 1, 0};
    menu_set_pose(m, c, right, up, 0.7f);

    float nav[16];
    mat4 n, to_world;
    display_navigation_matrix(&display_get_config(d)->navigation, nav);
    memcpy(n, nav, sizeof(n));
    glm_mat4_inv(n, to_world);
    struct menu_view *mv = menu_view_create(r);
    assert_non_null(mv);
    assert_true(menu_view_update(mv, m, (const float *)to_world, 1.0f));

    struct render_settings s = {.sun_dir = {0, 0, 1}, .sun_radiance = {1, 1, 1},
                                .sky = {0.3f, 0.45f, 0.75f}, .termination = 0.001f};
    assert_true(display_update(d, 0.0));
    assert_true(display_draw(d, r, &s));

    int pw, ph;
    const uint8_t *px = menu_pixels(m, &pw, &ph, NULL);
    float corners[4][3];
    menu_corners(m, corners);
    bool wall_sees[DISPLAY_MAX_WALLS] = {false};
    int views_seeing = 0, total = 0, matched = 0;
    for (int vi = 0; vi < display_view_count(d); vi++) {
        struct view *v = display_view(d, vi);
        if (!v->visible)
            continue;
        struct image img = {0};
        assert_true(renderer_read(&v->target, &img));
        mat4 vm, pm, vp;
        memcpy(vm, v->rv.view, sizeof(vm));
        memcpy(pm, v->rv.proj, sizeof(pm));
        glm_mat4_mul(pm, vm, vp);
        int seen = 0, ok = 0;
        for (int ty = 9; ty < ph - 9; ty += 6) {
            for (int tx = 9; tx < pw - 9; tx += 6) {
                if (!uniform_at(px, pw, ph, tx, ty, 9)) /* a pixel covers ~6 texels */
                    continue;
                float u = (tx + 0.5f) / pw, w = (ty + 0.5f) / ph;
                vec4 p = {0, 0, 0, 1}, world, clip;
                /* Top edge (image row 0) is corners[3] -> corners[2]. */
                for (int i = 0; i < 3; i++)
                    p[i] = corners[3][i] + u * (corners[2][i] - corners[3][i]) +
                           w * (corners[0][i] - corners[3][i]);
                glm_mat4_mulv(to_world, p, world);
                glm_mat4_mulv(vp, world, clip);
                if (clip[3] <= 0.0f)
                    continue;
                float nx = clip[0] / clip[3], ny = clip[1] / clip[3], nz = clip[2] / clip[3];
                if (fabsf(nx) > 0.97f || fabsf(ny) > 0.97f || fabsf(nz) > 1.0f)
                    continue;
                int ix = (int)((nx + 1.0f) * 0.5f * img.width);
                int iy = (int)((ny + 1.0f) * 0.5f * img.height);
                const float *got = &img.rgba[4 * ((size_t)iy * img.width + ix)];
                float want[3];
                menu_view_texel_radiance(&px[4 * (ty * pw + tx)], 1.0f, want);
                seen++;
                bool same = true;
                for (int k = 0; k < 3; k++)
                    same = same && fabsf(got[k] - want[k]) <= 0.02f * want[k] + 0.01f;
                ok += same;
            }
        }
        image_finish(&img);
        if (seen > 0) {
            wall_sees[v->wall] = true;
            views_seeing++;
            printf("# view %s: %d of %d panel points as projected\n", v->name, ok, seen);
        }
        total += seen;
        matched += ok;
        /* Every view that sees the panel shows it where the projection says. */
        assert_true(ok >= seen - seen / 20);
    }
    int walls = 0;
    for (int w = 0; w < DISPLAY_MAX_WALLS; w++)
        walls += wall_sees[w];
    assert_true(walls >= 2);           /* front, left and/or floor */
    assert_true(views_seeing >= 2 * walls); /* both eyes of each */
    assert_true(total > 50);

    menu_view_destroy(mv, r);
    menu_destroy(m);
    renderer_destroy(r);
    display_destroy(d);
    gpu_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_menu_in_cave4),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
