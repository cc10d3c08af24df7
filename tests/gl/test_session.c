/* One session, one frame loop: a session driven by a script produces frame states; a second
 * session fed the same states, through bytes, draws the same pictures, frame after frame, on
 * the orbit camera and on a CAVE; and the pictures did change on the way (the sun, the camera,
 * the navigation and the time step moved). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "session/frame.h"
#include "session/scene.h"
#include "session/session.h"

static struct gpu_context *ctx;
static char series_cfg[1024];

static void read_view(struct display *d, int i, struct image *img)
{
    assert_true(renderer_read(&display_view(d, i)->target, img));
}

static struct session *make(const struct config *cfg, const struct display_config *dcfg,
                            struct display *d, const char *script)
{
    struct render_view views[DISPLAY_MAX_VIEWS];
    int n = display_view_count(d);
    for (int i = 0; i < n; i++)
        views[i] = display_view(d, i)->rv;
    int rc;
    struct session *s = session_create(cfg,
                                       &(struct session_desc){
                                           .command = "render",
                                           .display = dcfg,
                                           .views = views,
                                           .view_count = n,
                                           .playback = true,
                                           .menu = script != NULL,
                                           .script = script,
                                           .time_views = true,
                                       },
                                       &rc);
    assert_non_null(s);
    return s;
}

static struct display *open_display(const struct config *cfg, const struct display_config *dcfg)
{
    struct display_desc dd = {.offscreen = true, .context = ctx, .height = cfg->render.height};
    scene_camera(cfg, &dd.camera);
    struct display *d = display_create(dcfg, &dd);
    assert_non_null(d);
    assert_true(display_update(d, 0.0));
    return d;
}

/* Runs SCRIPT on session A and feeds B A's frame states as bytes; every view of every frame
 * must match bit for bit.  Returns how many frames changed A's first view. */
static int run_pair(const struct display_config *dcfg, const char *script_text)
{
    struct config cfg;
    test_config_file(&cfg, series_cfg,
                     (const char *[]){"render.width=48", "render.height=36",
                                      "lightmap.resolution=[24,24,24]"},
                     3);
    const char *script = test_write_file("script.txt", script_text);
    struct display *da = open_display(&cfg, dcfg), *db = open_display(&cfg, dcfg);
    struct session *a = make(&cfg, dcfg, da, script), *b = make(&cfg, dcfg, db, NULL);
    struct image prev = {0};
    int changed = 0, frames = 0, last_step = 0;
    for (; !session_script_done(a) && frames < 200; frames++) {
        struct frame_state fa, fb;
        bool redraw;
        assert_true(session_update(a, NULL, session_script_dt(a), 0.0, &fa, &redraw));
        uint8_t bytes[FRAME_STATE_BYTES];
        frame_state_write(&fa, bytes);
        assert_true(frame_state_read(bytes, sizeof(bytes), &fb));
        assert_true(session_apply(a, &fa, NULL) && session_light(a) &&
                    display_sample_head(da, fa.time_s, &fa.head) && session_draw(a, da, &fa));
        fb.head = fa.head;
        assert_true(session_apply(b, &fb, NULL) && session_light(b) &&
                    session_draw(b, db, &fb));
        assert_int_equal(display_view_count(da), display_view_count(db));
        for (int i = 0; i < display_view_count(da); i++) {
            if (!display_view(da, i)->visible)
                continue;
            struct image ia, ib;
            read_view(da, i, &ia);
            read_view(db, i, &ib);
            assert_int_equal(ia.width, ib.width);
            size_t bytes_n = sizeof(float) * 4 * (size_t)ia.width * (size_t)ia.height;
            if (memcmp(ia.rgba, ib.rgba, bytes_n) != 0)
                fail_msg("frame %d, view %s: the second session drew another picture", frames,
                         display_view(da, i)->name);
            if (i == 0) {
                if (prev.rgba && memcmp(prev.rgba, ia.rgba, bytes_n) != 0)
                    changed++;
                image_finish(&prev);
                prev = ia;
            } else {
                image_finish(&ia);
            }
            image_finish(&ib);
        }
        last_step = fa.time_step;
        assert_int_equal(session_step_shown(a), session_step_shown(b));
    }
    assert_true(session_script_done(a));
    assert_true(last_step >= 2); /* time played */
    image_finish(&prev);
    session_destroy(a);
    session_destroy(b);
    display_destroy(da);
    display_destroy(db);
    return changed;
}

static const char script_text[] = "fps 10\n"
                                  "1 key sun-left\n"
                                  "2 key sun-up\n"
                                  "3 key move-forward\n"
                                  "4 key turn-left\n"
                                  "5 key zoom-in\n"
                                  "6 key play\n"
                                  "10 key play\n"
                                  "11 key turn-up\n";

static void test_orbit_pair(void **state)
{
    struct display_config dcfg;
    display_config_defaults(&dcfg);
    dcfg.type = DISPLAY_TYPE_ORBIT;
    dcfg.window_size[0] = 48;
    dcfg.window_size[1] = 36;
    assert_true(run_pair(&dcfg, script_text) >= 6);
}

static void test_cave_pair(void **state)
{
    struct display_config dcfg;
    assert_true(display_config_load(ANVIL_SOURCE_DIR "/displays/cave4.cfg", &dcfg));
    /* The placement cave4.cfg used to give, about the small series' centre. */
    dcfg.navigation = (struct display_navigation){
        .scale = 1e-4, .origin_km = {8.0, 8.0, 0.0}, .position = {0.0, 0.0, -2.0}, .given = true};
    assert_true(run_pair(&dcfg, script_text) >= 6);
}

static int setup(void **state)
{
    ctx = test_gl_context_or_skip();
    const char *bin = getenv("ANVIL_BIN");
    if (!bin)
        return 0;
    char cmd[2048];
    snprintf(cmd, sizeof(cmd), "'%s' --quiet synth -o '%s' --steps 4 --size 16x16x8 --extent 16x16x8",
             bin, test_tmp_path("series.nc"));
    if (system(cmd) != 0)
        return -1;
    snprintf(series_cfg, sizeof(series_cfg), "%s",
             test_write_file("series.cfg",
                             "scene = { kind = \"data\"; };\n"
                             "data = { format = \"wrf\"; files = [\"series.nc\"]; };\n"
                             "playback = { speed = 5.0; loop = false; };\n"
                             "camera = { position = [-6.0, -10.0, 6.0]; target = [8.0, 8.0, 3.0]; };\n"));
    return 0;
}

static int teardown(void **state)
{
    gpu_context_destroy(ctx);
    return 0;
}

int main(void)
{
    log_set_level(LOG_WARN);
    if (!getenv("ANVIL_BIN")) {
        fprintf(stderr, "ANVIL_BIN is not set: the synthetic series cannot be written\n");
        return TEST_SKIP;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_orbit_pair),
        cmocka_unit_test(test_cave_pair),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
