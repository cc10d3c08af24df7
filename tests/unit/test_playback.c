/* Playback: a script drives the menu (play for N frames advances the time step as the speed
 * says; pause stops it), and playback through the time series cache with a slow reader never
 * blocks a frame. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "session/player.h"
#include "common/log.h"
#include "input/input.h"
#include "menu/menu.h"

static bool always(void *user, int step)
{
    return true;
}

static struct menu *make_menu(int steps, double speed)
{
    struct menu_model model = {.speed = speed, .step_count = steps, .light_resolution = 128,
                               .epsilon = 0.01};
    transfer_defaults(&model.transfer, TRANSFER_FIELD_QVAPOR);
    struct menu *m = menu_create(NULL, &model);
    assert_non_null(m);
    const float c[3] = {0, 1.2f, -0.5f}, r[3] = {1, 0, 0}, u[3] = {0, 1, 0};
    menu_set_pose(m, c, r, u, 0.6f);
    return m;
}

/* Runs FRAMES frames of the script at fps 10 through the menu into PB; returns the step at
 * each frame in STEPS. */
static void run_script(struct input_source *src, struct menu *m, struct playback *pb,
                       int frames, int *steps)
{
    struct input_queue q;
    for (int f = 0; f < frames; f++) {
        input_queue_clear(&q);
        struct input_frame in = {.frame = f};
        assert_true(input_source_poll(src, &in, &q));
        for (int i = 0; i < q.count; i++)
            menu_handle(m, &q.events[i]);
        unsigned ch = menu_take_changes(m);
        struct menu_model *md = menu_model(m);
        if (ch & MENU_CHANGE_PLAYBACK) {
            pb->playing = md->playing;
            pb->speed = md->speed;
        }
        playback_tick(pb, 1.0 / input_script_fps(src), always, NULL);
        md->step = pb->step;
        steps[f] = pb->step;
    }
}

static void test_script_play_pause(void **state)
{
    /* Play is pressed (released) at frame 2, pause at frame 42: 40 frames of 0.1 s at 2
     * steps per second are 8 steps. */
    const char *path = test_write_file("play.txt",
                                       "# play, wait, pause\n"
                                       "fps 10\n"
                                       "0 aim time.play\n"
                                       "1 button trigger down\n"
                                       "2 button trigger up\n"
                                       "\n"
                                       "41 button trigger down   # still aimed at the button\n"
                                       "42 button trigger up\n");
    struct input_source *src = input_script_open(path);
    assert_non_null(src);
    assert_float_equal(input_script_fps(src), 10.0, 0);
    assert_int_equal(input_script_last_frame(src), 42);
    struct menu *m = make_menu(100, 2.0);
    struct playback pb;
    playback_init(&pb, 100, 0, 2.0, false);
    int steps[80];
    run_script(src, m, &pb, 80, steps);
    assert_int_equal(steps[1], 0);
    assert_false(pb.playing);
    /* Frames 2 (the release, ticked in the same frame) to 41 advance: 40 ticks of 0.2 step. */
    assert_int_equal(steps[41], 8);
    assert_int_equal(steps[42], 8); /* paused in the frame it was released */
    assert_int_equal(steps[79], 8);
    assert_true(input_source_finished(src));
    input_source_destroy(src);
    menu_destroy(m);
}

static void test_script_speed_and_end(void **state)
{
    /* Speed slider dragged to its maximum (10 steps/s), then play: the 6 steps run out after
     * half a second and playback stops on the last one. */
    const char *path = test_write_file("speed.txt",
                                       "0 aim time.speed 0.0 0.8\n"
                                       "1 button trigger down\n"
                                       "2 aim time.speed 1.0 0.8\n"
                                       "3 button trigger up\n"
                                       "4 key play\n");
    struct input_source *src = input_script_open(path);
    assert_non_null(src);
    struct menu *m = make_menu(6, 2.0);
    struct playback pb;
    playback_init(&pb, 6, 0, 2.0, false);
    int steps[40];
    run_script(src, m, &pb, 40, steps);
    assert_float_equal(menu_model(m)->speed, 10.0, 1e-9);
    /* At 30 fps (the default) and 10 steps/s, a third of a step per frame, counting the
     * frame of the key: 14 frames make 4.67 steps, 16 make 5.33 (the end). */
    assert_int_equal(steps[4 + 13], 4);
    assert_int_equal(steps[4 + 15], 5);
    assert_int_equal(steps[39], 5);
    assert_false(pb.playing);
    input_source_destroy(src);
    menu_destroy(m);
}

static void test_script_errors(void **state)
{
    log_set_level(LOG_NONE);
    assert_null(input_script_open(test_write_file("bad1.txt", "0 key play\n\n3 jump\n")));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "bad1.txt:3: expected an event"));
    log_set_level(LOG_NONE);
    assert_null(input_script_open(test_write_file("bad2.txt", "5 key play\n2 key play\n")));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "bad2.txt:2: frame 2 comes before frame 5"));
    log_set_level(LOG_NONE);
    assert_null(input_script_open(test_write_file("bad3.txt", "1 button trigger sideways\n")));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "bad3.txt:1:"));
}

/* The player over a synthetic WRF series whose reader sleeps 80 ms per step: playing faster
 * than that, frames take no longer than a few milliseconds, never wait on a load, and the
 * cursor moves only onto loaded steps. */
static void test_slow_reader_never_blocks(void **state)
{
    const char *bin = getenv("ANVIL_BIN");
    if (!bin)
        skip();
    char nc[512], cmd[1200];
    snprintf(nc, sizeof(nc), "%s", test_tmp_path("series.nc"));
    snprintf(cmd, sizeof(cmd), "'%s' synth -o '%s' --steps 6 --size 16x16x8 2>/dev/null", bin,
             nc);
    assert_int_equal(system(cmd), 0);
    struct config *cfg = calloc(1, sizeof(*cfg));
    config_defaults(cfg);
    cfg->scene.kind = SCENE_DATA;
    cfg->data.file_count = 1;
    snprintf(cfg->data.files[0], sizeof(cfg->data.files[0]), "%s", nc);
    cfg->data.prefetch = 2;
    struct player *p = player_create(cfg, &(struct player_desc){.delay_ms = 80.0});
    assert_non_null(p);
    assert_int_equal(player_step_count(p), 6);
    struct playback pb;
    playback_init(&pb, 6, 0, 50.0, false); /* 50 steps/s: far faster than the reader */
    pb.playing = true;
    double worst = 0.0;
    int shown = 0, uploads = 0;
    for (int f = 0; f < 400 && (pb.playing || shown != pb.step); f++) {
        double t0 = time_now_ms();
        playback_tick(&pb, 0.01, (bool (*)(void *, int))player_ready, p);
        if (player_poll(p, pb.step, &shown))
            uploads++;
        double ms = time_now_ms() - t0;
        worst = ms > worst ? ms : worst;
        usleep(10000);
    }
    struct session_stats st = {0};
    player_stats(p, &st);
    assert_true(worst < 40.0); /* a load takes 80 ms: no frame waited for one */
    assert_int_equal(st.frames_waited, 0);
    assert_int_equal(shown, 5);
    assert_int_equal(pb.step, 5);
    assert_true(pb.stalls > 0);   /* it did outrun the reader */
    assert_true(uploads >= 5);    /* every step was shown on the way */
    assert_true(st.load_ms >= 80.0 * 5);
    player_destroy(p);
    free(cfg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_script_play_pause),
        cmocka_unit_test(test_script_speed_and_end),
        cmocka_unit_test(test_script_errors),
        cmocka_unit_test(test_slow_reader_never_blocks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
