/* The overlay in a picture: the date it shows is the file's Times of the step on screen, and
 * the legend's colours, read off the rendered image where the legend shows known values, are
 * the transfer function's colours there. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "common/log.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "menu/overlay.h"
#include "render/image.h"
#include "session/scene.h"
#include "session/session.h"

static struct gpu_context *ctx;

struct scene {
    struct display *d;
    struct session *s;
};

static void open_scene(struct scene *sc, const char **sets, int n)
{
    struct config cfg;
    test_config_file(&cfg, ANVIL_SOURCE_DIR "/configs/katrina.cfg", sets, n);
    struct display_config dcfg;
    display_config_defaults(&dcfg);
    dcfg.type = DISPLAY_TYPE_ORBIT;
    dcfg.window_size[0] = cfg.render.width;
    dcfg.window_size[1] = cfg.render.height;
    struct display_desc dd = {.offscreen = true, .context = ctx, .height = cfg.render.height};
    scene_camera(&cfg, &dd.camera);
    sc->d = display_create(&dcfg, &dd);
    assert_non_null(sc->d);
    assert_true(display_update(sc->d, 0.0));
    int rc;
    sc->s = session_create(&cfg, &(struct session_desc){.command = "render", .display = &dcfg},
                           &rc);
    assert_non_null(sc->s);
}

static void draw(struct scene *sc)
{
    struct frame_state f;
    bool redraw;
    assert_true(session_update(sc->s, NULL, 0.0, 0.0, &f, &redraw));
    assert_true(session_apply(sc->s, &f, NULL) && session_light(sc->s));
    assert_true(display_sample_head(sc->d, 0.0, &f.head) && session_draw(sc->s, sc->d, &f));
}

static void close_scene(struct scene *sc)
{
    session_destroy(sc->s);
    display_destroy(sc->d);
}

static void test_date_is_the_files(void **state)
{
    if (access(test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"), R_OK) != 0)
        skip();
    /* The sample's steps are 3 hours apart from 2005-08-28 12:00. */
    const char *when[] = {"2005-08-28 12:00 UTC, step 1 of 4", "2005-08-28 18:00 UTC, step 3 of 4"};
    for (int k = 0; k < 2; k++) {
        char step[32];
        snprintf(step, sizeof(step), "data.step=%d", 2 * k);
        const char *sets[] = {"overlay.when=always", "render.width=96", "render.height=72",
                              step};
        struct scene sc;
        open_scene(&sc, sets, 4);
        draw(&sc);
        const struct overlay_model *m = session_overlay(sc.s);
        assert_non_null(m);
        assert_string_equal(m->date_text, when[k]);
        close_scene(&sc);
    }
    /* overlay.when = "run" (the default) leaves a render without one. */
    const char *sets[] = {"render.width=32", "render.height=24"};
    struct scene sc;
    open_scene(&sc, sets, 2);
    draw(&sc);
    assert_null(session_overlay(sc.s));
    close_scene(&sc);
}

/* Legend LEGEND's bar on the picture IMG of view V shows TF's colours at eight points. */
static void check_legend(struct scene *sc, const struct view *v, const struct image *img,
                         float exposure, int legend, const struct transfer_function *tf)
{
    for (int i = 1; i < 8; i++) {
        float x = i / 8.0f;
        double p[3];
        assert_true(session_legend_point(sc->s, legend, x, p));
        /* World -> pixel through the view's matrices (column-major). */
        double e[4], c[4];
        for (int r = 0; r < 4; r++)
            e[r] = v->rv.view[r] * p[0] + v->rv.view[4 + r] * p[1] + v->rv.view[8 + r] * p[2] +
                   v->rv.view[12 + r];
        for (int r = 0; r < 4; r++)
            c[r] = v->rv.proj[r] * e[0] + v->rv.proj[4 + r] * e[1] + v->rv.proj[8 + r] * e[2] +
                   v->rv.proj[12 + r] * e[3];
        int px = (int)floor((c[0] / c[3] * 0.5 + 0.5) * img->width);
        int py = (int)floor((c[1] / c[3] * 0.5 + 0.5) * img->height); /* row 0 at the bottom */
        assert_true(px >= 0 && px < img->width && py >= 0 && py < img->height);
        const float *rgb = &img->rgba[4 * ((size_t)py * img->width + px)];
        for (int ch = 0; ch < 3; ch++) {
            int got = image_tonemap(rgb[ch], exposure);
            float want = transfer_eval(tf, (enum transfer_channel)ch, x);
            int want8 = (int)lroundf(fminf(fmaxf(want, 0.0f), 1.0f) * 255.0f);
            if (abs(got - want8) > 4)
                fail_msg("legend %d at %.3f (pixel %d, %d), channel %d: %d on screen, the "
                         "function %d",
                         legend, x, px, py, ch, got, want8);
        }
    }
}

static void test_legend_in_the_picture(void **state)
{
    if (access(test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"), R_OK) != 0)
        skip();
    const char *sets[] = {"overlay.when=always", "render.width=480", "render.height=360",
                          "lightmap.resolution=[32,32,32]"};
    struct scene sc;
    open_scene(&sc, sets, 4);
    struct session_settings set;
    session_get_settings(sc.s, &set);
    set.look.layer_count = 1;
    set.look.layers[0] = (struct transfer_layer){.enabled = true, .opacity = 1.0};
    transfer_defaults(&set.look.layers[0].tf, TRANSFER_FIELD_TEMPERATURE);
    set.revision++;
    session_set_settings(sc.s, &set);
    assert_true(session_settle(sc.s));
    draw(&sc);
    const struct view *v = display_view(sc.d, 0);
    struct image img;
    assert_true(renderer_read(&v->target, &img));
    float exposure = (float)session_config(sc.s)->render.exposure;
    check_legend(&sc, v, &img, exposure, 0, &set.look.layers[0].tf);
    image_finish(&img);
    close_scene(&sc);
}

/* Two layers and a slice: three bars, each in its own function's colours, the second layer's
 * (relative humidity) a function of our own. */
static void test_legend_per_layer(void **state)
{
    if (access(test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"), R_OK) != 0)
        skip();
    const char *sets[] = {"overlay.when=always", "render.width=480", "render.height=360",
                          "lightmap.resolution=[32,32,32]"};
    struct scene sc;
    open_scene(&sc, sets, 4);
    struct session_settings set;
    session_get_settings(sc.s, &set);
    set.look.layer_count = 2;
    set.look.layers[0] = (struct transfer_layer){.enabled = true, .opacity = 1.0};
    transfer_defaults(&set.look.layers[0].tf, TRANSFER_FIELD_TEMPERATURE);
    set.look.layers[1] = (struct transfer_layer){.enabled = true, .opacity = 0.5,
                                                 .mode = TRANSFER_LAYER_TINT};
    struct transfer_function *rh = &set.look.layers[1].tf;
    transfer_defaults(rh, TRANSFER_FIELD_RH);
    rh->count[TRANSFER_RED] = 2;
    rh->points[TRANSFER_RED][0] = (struct transfer_point){0.0f, 1.0f};
    rh->points[TRANSFER_RED][1] = (struct transfer_point){1.0f, 0.0f};
    set.look.slice_count = 1;
    set.look.slices[0] = (struct transfer_slice){
        .enabled = true, .point = {0, 0, 3000}, .normal = {0, 0, 1}, .opacity = 1.0};
    transfer_defaults(&set.look.slices[0].tf, TRANSFER_FIELD_WIND);
    set.revision++;
    session_set_settings(sc.s, &set);
    assert_true(session_settle(sc.s));
    draw(&sc);
    const struct overlay_model *m = session_overlay(sc.s);
    assert_non_null(m);
    assert_int_equal(m->legend_count, 3);
    const struct view *v = display_view(sc.d, 0);
    struct image img;
    assert_true(renderer_read(&v->target, &img));
    float exposure = (float)session_config(sc.s)->render.exposure;
    check_legend(&sc, v, &img, exposure, 0, &set.look.layers[0].tf);
    check_legend(&sc, v, &img, exposure, 1, rh);
    check_legend(&sc, v, &img, exposure, 2, &set.look.slices[0].tf);
    double p[3];
    assert_false(session_legend_point(sc.s, 3, 0.5f, p));
    image_finish(&img);

    /* The largest look (four layers and four slices, every channel full of points) fits the
     * 96 KiB that Save view gives it (src/app/loop.c). */
    set.look.layer_count = TRANSFER_LAYER_MAX;
    set.look.slice_count = TRANSFER_SLICE_MAX;
    for (int i = 0; i < TRANSFER_LAYER_MAX + TRANSFER_SLICE_MAX; i++) {
        struct transfer_function *tf = i < TRANSFER_LAYER_MAX ? &set.look.layers[i].tf
                                                              : &set.look.slices[i - 4].tf;
        if (i >= TRANSFER_LAYER_MAX)
            set.look.slices[i - 4] = set.look.slices[0];
        else
            set.look.layers[i] = set.look.layers[0];
        for (int c = 0; c < TRANSFER_CHANNELS; c++) {
            tf->count[c] = TRANSFER_MAX_POINTS;
            for (int k = 0; k < TRANSFER_MAX_POINTS; k++)
                tf->points[c][k] = (struct transfer_point){k / 31.0f * 0.999f, 0.123456789f};
        }
        memset(tf->name, 'n', sizeof(tf->name) - 1);
        tf->name[sizeof(tf->name) - 1] = '\0';
    }
    set.revision++;
    session_set_settings(sc.s, &set);
    static char text[98304];
    session_look_text(sc.s, text, sizeof(text));
    assert_non_null(strstr(text, "slices = ("));
    assert_null(strstr(text, "is longer than"));
    assert_true(strlen(text) > 16384); /* more than Save view once gave a look */
    close_scene(&sc);
}

int main(void)
{
    log_set_level(LOG_WARN);
    ctx = test_gl_context_or_skip();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_date_is_the_files),
        cmocka_unit_test(test_legend_in_the_picture),
        cmocka_unit_test(test_legend_per_layer),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    gpu_context_destroy(ctx);
    return rc;
}
