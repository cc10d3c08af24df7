/* Recordings: every kind of event and a frame's clock, head and cursor written and read back
 * to the same bits; the script ends only after its last recorded frame; a recording is a head
 * path too; bad recording lines are refused with FILE:LINE; a recording that cannot be
 * written says so.  And outputs by name or place, chosen without a monitor in sight. */
#include <glob.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "common/log.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "input/input.h"

static const struct input_event events[] = {
    {.type = INPUT_BUTTON, .button = INPUT_BUTTON_GRAB, .down = true},
    {.type = INPUT_POSE,
     .space = INPUT_SPACE_TRACKER,
     .position = {0.1f, 1.2345678f, -0.3f},
     .direction = {0.26726124f, 0.53452248f, -0.80178373f}},
    {.type = INPUT_POSE,
     .space = INPUT_SPACE_WORLD,
     .position = {30000.5f, -1e-7f, 12.25f},
     .direction = {0.0f, -1.0f, 0.0f}},
    {.type = INPUT_AXIS, .axis = INPUT_AXIS_TURN, .value = -0.33333334f},
    {.type = INPUT_KEY, .key = INPUT_KEY_SUN_UP},
    {.type = INPUT_AIM, .target = "time.play", .u = 0.1f, .v = 0.9f},
    {.type = INPUT_DRAG, .u = 3.0f, .v = -7.5f},
    {.type = INPUT_SCROLL, .value = -2.0f},
};
#define EVENT_COUNT ((int)(sizeof(events) / sizeof(events[0])))

static void same_event(const struct input_event *a, const struct input_event *b)
{
    assert_int_equal(a->type, b->type);
    switch (a->type) {
    case INPUT_BUTTON:
        assert_int_equal(a->button, b->button);
        assert_int_equal(a->down, b->down);
        break;
    case INPUT_POSE:
        assert_int_equal(a->space, b->space);
        assert_memory_equal(a->position, b->position, sizeof(a->position));
        assert_memory_equal(a->direction, b->direction, sizeof(a->direction));
        break;
    case INPUT_AXIS:
    case INPUT_SCROLL:
        assert_int_equal(a->axis, b->axis);
        assert_memory_equal(&a->value, &b->value, sizeof(a->value));
        break;
    case INPUT_KEY:
        assert_int_equal(a->key, b->key);
        break;
    case INPUT_AIM:
    case INPUT_DRAG:
        assert_string_equal(a->target, b->target);
        assert_memory_equal(&a->u, &b->u, sizeof(a->u));
        assert_memory_equal(&a->v, &b->v, sizeof(a->v));
        break;
    }
}

/* How many files match PATTERN. */
static size_t temporaries(const char *pattern)
{
    glob_t g;
    size_t n = glob(pattern, 0, NULL, &g) == 0 ? g.gl_pathc : 0;
    globfree(&g);
    return n;
}

static void test_round_trip(void **state)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s", test_tmp_path("rec.txt"));
    struct input_recorder *r = input_recorder_open(path, "run", true);
    assert_non_null(r);
    struct input_queue *q = calloc(1, sizeof(*q));
    const double times[3] = {12.000123456789, 12.016789, 12.05};
    const float quat[4] = {0.0f, 0.38268343f, 0.0f, 0.92387953f};
    /* A runtime's eyes relative to the head, with the rounding a turned head leaves in them:
     * the smallest numbers and a rotation a hair from identity must come back bit for bit. */
    const float eye_p[2][3] = {{-0.0319999754f, 1.1920929e-07f, 0.0f},
                               {0.0320000052f, 0.0f, -1.49011612e-08f}};
    const float eye_q[2][4] = {{0.0f, 5.00585884e-09f, 0.0f, 1.0f},
                               {-2.32830671e-10f, -2.88127944e-09f, 0.0f, 1.0f}};
    for (int f = 0; f < 3; f++) {
        input_queue_clear(q);
        for (int i = 0; i < EVENT_COUNT && f == 1; i++)
            input_queue_push(q, &events[i]);
        struct input_record_frame fr = {.frame = f,
                                        .time_s = times[f],
                                        .dt_s = f ? times[f] - times[f - 1] : 0.0,
                                        .have_head = f != 0,
                                        .head_position = {0.1f * f, 1.6f, 0.5f - 0.1f * f},
                                        .step = f,
                                        .step_acc = 1.0 / 3.0,
                                        .playing = f == 2};
        memcpy(fr.head_rotation, quat, sizeof(quat));
        fr.have_eyes = f == 2; /* frame 1: a head without eyes (a CAVE's, an HMD's) */
        memcpy(fr.eye_position, eye_p, sizeof(eye_p));
        memcpy(fr.eye_rotation, eye_q, sizeof(eye_q));
        input_recorder_frame(r, &fr, q);
    }
    assert_int_equal(temporaries(test_tmp_path("rec.txt.tmp*")), 1); /* written beside it */
    assert_true(input_recorder_close(r));
    assert_int_equal(temporaries(test_tmp_path("rec.txt.tmp*")), 0);

    struct input_source *s = input_script_open(path);
    assert_non_null(s);
    bool from_run;
    int menu;
    assert_true(input_script_recorded(s, &from_run, &menu));
    assert_true(from_run);
    assert_int_equal(menu, 1);
    assert_true(input_script_has_head(s));
    assert_int_equal(input_script_last_frame(s), 2);
    for (int f = 0; f < 3; f++) {
        assert_false(input_source_finished(s));
        input_queue_clear(q);
        assert_true(input_source_poll(s, &(struct input_frame){.frame = f}, q));
        assert_int_equal(q->count, f == 1 ? EVENT_COUNT : 0);
        for (int i = 0; i < q->count; i++)
            same_event(&q->events[i], &events[i]);
        struct input_script_frame info;
        assert_true(input_script_frame(s, f, &info));
        assert_true(info.have_time && info.have_cursor);
        assert_memory_equal(&info.time_s, &times[f], sizeof(double));
        double dt = f ? times[f] - times[f - 1] : 0.0;
        assert_memory_equal(&info.dt_s, &dt, sizeof(double));
        assert_int_equal(info.have_head, f != 0);
        if (f) {
            float p[3] = {0.1f * f, 1.6f, 0.5f - 0.1f * f};
            assert_memory_equal(info.head_position, p, sizeof(p));
            assert_memory_equal(info.head_rotation, quat, sizeof(quat));
        }
        assert_int_equal(info.have_eyes, f == 2);
        if (f == 2) {
            assert_memory_equal(info.eye_position, eye_p, sizeof(eye_p));
            assert_memory_equal(info.eye_rotation, eye_q, sizeof(eye_q));
        }
        double acc = 1.0 / 3.0;
        assert_int_equal(info.step, f);
        assert_memory_equal(&info.step_acc, &acc, sizeof(acc));
        assert_int_equal(info.playing, f == 2);
    }
    assert_true(input_source_finished(s));
    struct input_script_frame none;
    assert_false(input_script_frame(s, 3, &none));
    input_source_destroy(s);

    /* The same file as a head path: frames 1 and 2 at the steps' sums. */
    struct display_path hp;
    assert_true(display_path_load(path, &hp));
    assert_int_equal(hp.count, 2);
    assert_true(fabs(hp.time[0] - (times[1] - times[0])) < 1e-12);
    assert_true(fabs(hp.time[1] - (times[2] - times[0])) < 1e-12);
    assert_float_equal(hp.pose[1].position[0], 0.2f, 0);
    display_path_finish(&hp);
    free(q);
}

static void expect_script_error(const char *name, const char *text, const char *part)
{
    const char *path = test_write_file(name, text);
    unsigned before = log_error_count();
    log_set_level(LOG_NONE);
    assert_null(input_script_open(path));
    log_set_level(LOG_INFO);
    assert_int_equal(log_error_count(), before + 1);
    if (!strstr(log_last_error(), part))
        fail_msg("\"%s\" lacks \"%s\"", log_last_error(), part);
}

static void test_bad_lines(void **state)
{
    expect_script_error("q.txt", "recorded run\n0 time 0 0\n1 head 0 1 0 0 0 0 2\n",
                        "q.txt:3: expected \"head X Y Z QX QY QZ QW\"");
    expect_script_error("far.txt", "0 head 1e5 0 0 0 0 0 1\n", "far.txt:1: expected \"head");
    expect_script_error("t.txt", "0 time 1 -0.5\n", "t.txt:1: expected \"time SECONDS DT\"");
    expect_script_error("e.txt", "0 eyes -0.03 0 0 0 0 0 1 0.03 0 0 0 0 0\n",
                        "e.txt:1: expected \"eyes X Y Z QX QY QZ QW X Y Z");
    expect_script_error("e2.txt", "0 eyes -0.03 0 0 0 0 0 1 0.03 0 0 0 0 0 0.5\n",
                        "e2.txt:1: expected \"eyes"); /* not a unit quaternion */
    expect_script_error("e3.txt", "0 eyes -3 0 0 0 0 0 1 0.03 0 0 0 0 0 1\n",
                        "e3.txt:1: expected \"eyes"); /* 3 m from the head */
    expect_script_error("e4.txt", "0 eyes -0.03 0 0 0 0 0 1 0.03 0 0 0 0 0 1 2\n",
                        "e4.txt:1: expected \"eyes"); /* a word too many */
    expect_script_error("c.txt", "0 cursor 2 1.5 1\n", "c.txt:1: expected \"cursor STEP");
    expect_script_error("c2.txt", "0 cursor 2 0.5 yes\n", "c2.txt:1: expected \"cursor STEP");
    expect_script_error("r.txt", "recorded today\n", "r.txt:1: expected \"recorded run\"");
    expect_script_error("m.txt", "menu maybe\n", "m.txt:1: expected \"menu shown\"");
    expect_script_error("d.txt", "0 drag 1\n", "d.txt:1: expected \"drag DX DY\"");
    /* A recording needs head lines to be a path. */
    const char *nohead = test_write_file("nohead.txt", "recorded render\n0 time 0 0.1\n");
    struct display_path hp;
    log_set_level(LOG_NONE);
    assert_false(display_path_load(nohead, &hp));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "expected a recording with head lines"));
    /* A recording that cannot be made. */
    log_set_level(LOG_NONE);
    assert_null(input_recorder_open(test_tmp_path("no/such/folder/rec.txt"), "run", false));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "cannot write"));
}

static void test_outputs(void **state)
{
    const struct gpu_output outs[] = {
        {"DP-1", {0, 0, 1920, 1080}},
        {"DP-2", {1920, 0, 1920, 1080}},
        {"HDMI-0", {0, 1080, 1400, 1050}},
    };
    assert_int_equal(gpu_output_by_name(outs, 3, "DP-2"), 1);
    assert_int_equal(gpu_output_by_name(outs, 3, "hdmi-0"), 2); /* case aside */
    assert_int_equal(gpu_output_by_name(outs, 3, "DP-3"), -1);
    assert_int_equal(gpu_output_by_rect(outs, 3, (int[]){1920, 0, 1920, 1080}), 1);
    assert_int_equal(gpu_output_by_rect(outs, 3, (int[]){1920, 0, 1920, 1200}), -1);
    char list[256];
    gpu_output_list(outs, 2, list, sizeof(list));
    assert_string_equal(list, "DP-1 at 0,0 1920x1080; DP-2 at 1920,0 1920x1080");
    gpu_output_list(outs, 0, list, sizeof(list));
    assert_string_equal(list, "none");

    bool borderless;
    struct gpu_context_desc d = {.monitor = 0, .output = "DP-2", .title = "front"};
    assert_int_equal(gpu_output_choose(&d, outs, 3, &borderless), 1); /* the name first */
    assert_false(borderless);
    d.output = "DP-9";
    unsigned warnings = log_warn_count();
    log_set_level(LOG_ERROR);
    assert_int_equal(gpu_output_choose(&d, outs, 3, &borderless), -1);
    assert_int_equal(log_warn_count(), warnings + 1);
    d.output = NULL;
    d.rect_set = true;
    memcpy(d.rect, (int[]){0, 1080, 1400, 1050}, sizeof(d.rect));
    assert_int_equal(gpu_output_choose(&d, outs, 3, &borderless), 2);
    assert_false(borderless);
    d.rect[0] = 100; /* a part of a screen: a borderless window there */
    assert_int_equal(gpu_output_choose(&d, outs, 3, &borderless), -1);
    assert_true(borderless);
    d.rect_set = false;
    d.monitor = 2;
    assert_int_equal(gpu_output_choose(&d, outs, 3, &borderless), 2);
    d.monitor = 5;
    assert_int_equal(gpu_output_choose(&d, outs, 3, &borderless), -1);
    assert_int_equal(log_warn_count(), warnings + 2);
    log_set_level(LOG_INFO);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_bad_lines),
        cmocka_unit_test(test_outputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
