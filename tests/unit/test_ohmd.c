/* One OpenHMD context per process: the HMD, a head tracker on the same device and the wand
 * share it and the devices; it goes with the last device closed.  And the keys: every key a
 * window can send has a name for scripts and a line in the help. */
#include <string.h>

#include <openhmd.h>

#include "testutil.h"

#include "common/log.h"
#include "input/input.h"
#include "session/session.h"

static void test_one_context(void **state)
{
    assert_int_equal(input_ohmd_contexts(), 0);
    struct ohmd_device *hmd = input_ohmd_open("null", OHMD_DEVICE_CLASS_HMD);
    assert_non_null(hmd);
    assert_int_equal(input_ohmd_contexts(), 1);
    /* A head tracker on "null" of any class finds the same Null HMD. */
    struct ohmd_device *head = input_ohmd_open("null", -1);
    assert_ptr_equal(head, hmd);
    struct input_source *wand = input_ohmd_create("null", NULL);
    assert_non_null(wand);
    assert_int_equal(input_ohmd_contexts(), 1);
    log_set_level(LOG_NONE);
    assert_null(input_ohmd_open("no such headset", OHMD_DEVICE_CLASS_HMD));
    log_set_level(LOG_INFO);
    assert_int_equal(input_ohmd_contexts(), 1);
    input_ohmd_update();
    input_ohmd_close(head);
    assert_int_equal(input_ohmd_contexts(), 1); /* still the HMD's and the wand's */
    input_source_destroy(wand);
    input_ohmd_close(hmd);
    assert_int_equal(input_ohmd_contexts(), 0);
    /* Opened again after all that: a fresh context. */
    hmd = input_ohmd_open("null", OHMD_DEVICE_CLASS_HMD);
    assert_non_null(hmd);
    input_ohmd_close(hmd);
    assert_int_equal(input_ohmd_contexts(), 0);
}

/* The Null controller's controls stand still, its menu control held: polled frame after
 * frame the wand sends its pose and no button, so a script's first "key menu" shows the menu
 * (before, the first poll sent "menu down" and the menu was up before any key). */
static void test_held_control_is_no_press(void **state)
{
    struct input_source *wand = input_ohmd_create("null", NULL);
    assert_non_null(wand);
    struct input_queue q;
    int poses = 0;
    for (long f = 0; f < 5; f++) {
        input_queue_clear(&q);
        input_ohmd_update();
        assert_true(input_source_poll(wand, &(struct input_frame){.frame = f}, &q));
        for (int i = 0; i < q.count; i++) {
            assert_int_not_equal(q.events[i].type, INPUT_BUTTON);
            poses += q.events[i].type == INPUT_POSE;
        }
    }
    assert_true(poses >= 1); /* the first frame's pose at least */
    input_source_destroy(wand);
    assert_int_equal(input_ohmd_contexts(), 0);
}

static int help_lines;
static bool seen[INPUT_KEY_COUNT];

static void count_key(const char *keys, enum input_key key, void *user)
{
    assert_true(key > INPUT_KEY_NONE && key < INPUT_KEY_COUNT);
    assert_false(seen[key]); /* each meaning once, its keys joined */
    seen[key] = true;
    assert_true(strlen(keys) > 0);
}

static void count_help(const char *keys, const char *what, void *user)
{
    assert_true(strlen(keys) > 0 && strlen(what) > 0);
    help_lines++;
}

static void test_keys_named_and_explained(void **state)
{
    display_list_keys(count_key, NULL);
    int table = 0;
    for (int k = INPUT_KEY_NONE + 1; k < INPUT_KEY_COUNT; k++) {
        /* Every key has a script name that reads back as itself. */
        enum input_key back = INPUT_KEY_NONE;
        const char *name = input_key_name((enum input_key)k);
        assert_string_not_equal(name, "?");
        assert_true(input_key_from_name(name, &back));
        assert_int_equal(back, k);
        /* ... and a window key. */
        if (!seen[k])
            fail_msg("key \"%s\" has no window key in the display's table", name);
        table++;
    }
    session_list_keys(count_help, NULL);
    assert_true(help_lines >= table + 2); /* every key, Home and the mouse */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_context),
        cmocka_unit_test(test_held_control_is_no_press),
        cmocka_unit_test(test_keys_named_and_explained),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
