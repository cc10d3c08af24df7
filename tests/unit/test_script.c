/* input: scripted input files, the limits: frames up to INPUT_SCRIPT_FRAMES_MAX, and every
 * aimed-at widget checked against the menu's names before the first frame. */
#include "testutil.h"

#include <stdio.h>
#include <string.h>

#include "common/log.h"
#include "input/input.h"

static struct input_source *open_text(const char *name, const char *text)
{
    return input_script_open(test_write_file(name, text));
}

static void test_frame_limit(void **state)
{
    /* Frame 9e18 was taken: the render then played for hours. */
    unsigned errors = log_error_count();
    assert_null(open_text("far.txt", "0 key play\n9000000000000000000 key quit\n"));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "far.txt:2: expected a frame number from 0 to "
                                             "1000000 first, got \"9000000000000000000\""));
    assert_null(open_text("over.txt", "1000001 key quit\n"));
    assert_non_null(strstr(log_last_error(), "over.txt:1:"));
    struct input_source *s = open_text("last.txt", "1000000 key quit\n");
    assert_non_null(s);
    assert_int_equal(input_script_last_frame(s), INPUT_SCRIPT_FRAMES_MAX);
    input_source_destroy(s);
}

static bool known(const char *name, void *user)
{
    (*(int *)user)++;
    return strcmp(name, "time.play") == 0 || strcmp(name, "light.azimuth") == 0;
}

static void test_aims_checked(void **state)
{
    struct input_source *s =
        open_text("aim.txt", "fps 10\n0 aim time.play\n# a comment\n3 aim light.azimuth 0.5 0.5\n"
                             "4 button trigger down\n7 aim time.paly\n");
    assert_non_null(s);
    int asked = 0;
    unsigned errors = log_error_count();
    assert_false(input_script_check_aims(s, known, &asked));
    assert_int_equal(asked, 3);
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "aim.txt:6: expected a widget of the menu"));
    assert_non_null(strstr(log_last_error(), "\"time.paly\""));
    input_source_destroy(s);
    s = open_text("good.txt", "0 aim time.play\n1 aim light.azimuth\n");
    assert_true(input_script_check_aims(s, known, &asked));
    input_source_destroy(s);
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frame_limit),
        cmocka_unit_test(test_aims_checked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
