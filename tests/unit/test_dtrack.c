/* The DTrack ASCII parser: a full frame read to the digit, the record types it skips, DTrack 1
 * and DTrack 3 variants, and every kind of malformed datagram refused with a reason. */
#include <string.h>

#include "testutil.h"

#include "input/tracker.h"

static struct dtrack_frame frame;
static char why[256];

static bool parse(const char *text)
{
    return dtrack_parse(text, strlen(text), &frame, why, sizeof(why));
}

static void test_full_frame(void **state)
{
    const char *text =
        "fr 21753\r\n"
        "ts 39596.024831\r\n"
        "6dcal 3\r\n"
        "3d 1 [1 1.000][100.0 200.0 300.0]\r\n"
        "6d 2 [0 1.000][326.848 -187.216 109.503][1 0 0 0 1 0 0 0 1] "
        "[2 -1.000][0 0 0][0 0 0 0 0 0 0 0 0]\r\n"
        "6df2 2 1 [0 0.875 6 2][10.5 20.25 -30.125][0 -1 0 1 0 0 0 0 1][5 0.5 -1.0]\r\n"
        "6di 0\r\n";
    assert_true(parse(text));
    assert_true(frame.have_counter);
    assert_int_equal(frame.counter, 21753);
    assert_true(frame.have_time);
    assert_float_equal(frame.time_s, 39596.024831, 1e-9);
    assert_int_equal(frame.calibrated, 3);
    assert_int_equal(frame.skipped_lines, 2); /* 3d and 6di */
    assert_true(frame.have_bodies);
    assert_int_equal(frame.body_count, 2);
    assert_int_equal(frame.bodies[0].id, 0);
    assert_float_equal(frame.bodies[0].quality, 1.0, 0);
    assert_float_equal(frame.bodies[0].position[0], 326.848, 1e-12);
    assert_float_equal(frame.bodies[0].position[1], -187.216, 1e-12);
    assert_float_equal(frame.bodies[0].position[2], 109.503, 1e-12);
    assert_float_equal(frame.bodies[0].rotation[4], 1.0, 0);
    assert_int_equal(frame.bodies[1].id, 2);
    assert_true(frame.bodies[1].quality < 0.0); /* untracked: zeros are no rotation, accepted */
    assert_true(frame.have_flysticks);
    assert_int_equal(frame.flystick_count, 1);
    const struct dtrack_item *f = &frame.flysticks[0];
    assert_int_equal(f->id, 0);
    assert_float_equal(f->quality, 0.875, 0);
    assert_float_equal(f->position[2], -30.125, 0);
    assert_float_equal(f->rotation[1], -1.0, 0); /* column-major: b1 is row 1 of column 0 */
    assert_int_equal(f->button_count, 6);
    bool want[6] = {true, false, true, false, false, false}; /* 5 = bits 0 and 2 */
    for (int b = 0; b < 6; b++)
        assert_int_equal(f->buttons[b], want[b]);
    assert_int_equal(f->axis_count, 2);
    assert_float_equal(f->axes[0], 0.5, 0);
    assert_float_equal(f->axes[1], -1.0, 0);
}

static void test_variants(void **state)
{
    /* DTrack 3's ts2 (seconds, microseconds, latency); LF endings; no NUL after the bytes. */
    char buf[64] = "ts2 1700000000 250000 1200\n6d 0\nXXXX";
    assert_true(dtrack_parse(buf, strlen(buf) - 4, &frame, why, sizeof(why)));
    assert_float_equal(frame.time_s, 1700000000.25, 1e-6);
    assert_true(frame.have_bodies);
    assert_int_equal(frame.body_count, 0);
    assert_false(frame.have_counter);
    /* DTrack 1 puts three Euler angles after the position. */
    assert_true(parse("fr 7\n6d 1 [4 0.5][1 2 3 10 20 30][1 0 0 0 1 0 0 0 1]\n"));
    assert_int_equal(frame.bodies[0].id, 4);
    assert_float_equal(frame.bodies[0].position[2], 3.0, 0);
    /* Button words beyond the first: 40 buttons, bit 3 of the second word is button 35. */
    assert_true(parse("6df2 1 1 [0 1.0 40 0][0 0 0][1 0 0 0 1 0 0 0 1][0 8]\n"));
    assert_int_equal(frame.flysticks[0].button_count, 40);
    for (int b = 0; b < 40; b++)
        assert_int_equal(frame.flysticks[0].buttons[b], b == 35);
    /* A NUL after the text (a sender that counts its C string's terminator) is no line. */
    assert_true(dtrack_parse("fr 9\r\n6d 0\r\n\0\0", 14, &frame, why, sizeof(why)));
    assert_int_equal(frame.counter, 9);
    /* Only record types anvil skips: a valid, empty frame. */
    assert_true(parse("3d 0\ngl 0\n"));
    assert_int_equal(frame.skipped_lines, 2);
    assert_false(frame.have_bodies);
}

/* Each malformed datagram is refused, and WHY names the problem. */
static void refused(const char *text, const char *reason)
{
    memset(why, 0, sizeof(why));
    if (parse(text))
        fail_msg("accepted: \"%s\"", text);
    if (!strstr(why, reason))
        fail_msg("\"%s\": the reason \"%s\" lacks \"%s\"", text, why, reason);
}

static void test_malformed(void **state)
{
    refused("", "empty");
    refused("\r\n\r\n", "empty");
    refused("fr 12\n6d 1 [0 1.000][326.848 -187.216", "line 2");       /* truncated */
    refused("fr 12\n6d 2 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\n", "'['"); /* wrong count */
    refused("6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1] [1 1.0]\n", "end of the");
    refused("6d 1 [0 1.0][nan 2 3][1 0 0 0 1 0 0 0 1]\n", "position");
    refused("6d 1 [0 1.0][1e400 2 3][1 0 0 0 1 0 0 0 1]\n", "finite");
    refused("6d 1 [0 1.0][1 2 3][2 0 0 0 1 0 0 0 1]\n", "rotation matrix");
    refused("6d 1 [0 1.0][1 2 3][-1 0 0 0 1 0 0 0 1]\n", "rotation matrix"); /* a mirror */
    refused("6d 2 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1][0 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\n", "twice");
    refused("6d 33\n", "body count");
    refused("6d -1\n", "body count");
    refused("6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0 0]\n", "rotation matrix");
    refused("6df2 1 1 [0 1.0 65 0][0 0 0][1 0 0 0 1 0 0 0 1][0 0 0]\n", "button count");
    refused("6df2 1 1 [0 1.0 2 1][0 0 0][1 0 0 0 1 0 0 0 1][3 1.5]\n", "joystick value");
    refused("6df2 1 1 [0 1.0 2 1][0 0 0][1 0 0 0 1 0 0 0 1][3]\n", "joystick value");
    refused("6df2 1 1 [0 1.0 2 0][0 0 0][1 0 0 0 1 0 0 0 1][4294967296]\n", "button word");
    refused("fr 1\nfr 2\n", "second");
    refused("fr -3\n", "frame counter");
    refused("fr 12abc\n", "end of the");
    refused("\x01\x02garbage\xff\n", "record type");
    refused("6D 0\n", "record type");
    refused("ts2 10 1000000\n", "microseconds");
    char long_number[200] = "fr ";
    memset(long_number + 3, '1', 150);
    refused(long_number, "frame counter");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_frame),
        cmocka_unit_test(test_variants),
        cmocka_unit_test(test_malformed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
