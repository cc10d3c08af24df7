/* The frame state as bytes: every field survives the round trip, the layout is fixed and
 * little-endian, and bytes that are not a frame state are refused. */
#include <math.h>
#include <string.h>

#include "testutil.h"

#include "common/log.h"
#include "session/frame.h"

static void sample(struct frame_state *f)
{
    memset(f, 0, sizeof(*f));
    f->frame = 0x0102030405060708ull;
    f->time_s = 12.25;
    f->dt_s = 1.0 / 30.0;
    const double pos[3] = {0.1, 1.6, 0.5}, hpr[3] = {30.0, -10.0, 5.0};
    display_pose_from_euler(pos, hpr, &f->head);
    f->nav = (struct display_navigation){.scale = 1e-4,
                                         .origin_km = {30.0, 31.0, 0.5},
                                         .position = {0.0, -0.2, -2.0},
                                         .orientation_deg = {45.0, 3.0, -1.0}};
    f->camera = (struct display_camera){.eye = {2000.0, -14000.0, 4000.0},
                                        .target = {30000.0, 30000.0, 7000.0},
                                        .up = {0.0, 0.0, 1.0},
                                        .fov_deg = 50.0,
                                        .near_m = 10.0,
                                        .far_m = 2e6};
    f->wand_valid = true;
    const float wp[3] = {0.2f, 1.2f, -0.3f}, wd[3] = {0.0f, -0.6f, -0.8f};
    memcpy(f->wand_position, wp, sizeof(wp));
    memcpy(f->wand_direction, wd, sizeof(wd));
    f->time_step = 7;
    f->step_fraction = 0.375f;
    f->playing = true;
    f->sun_azimuth_deg = 210.0;
    f->sun_elevation_deg = 35.5;
    f->menu_visible = true;
    f->settings_revision = 42;
    f->probe_valid = true;
    const double probe[3] = {12345.5, -678.25, 4321.125};
    memcpy(f->probe_point, probe, sizeof(probe));
}

static void assert_same(const struct frame_state *a, const struct frame_state *b)
{
    assert_true(a->frame == b->frame);
    assert_memory_equal(&a->time_s, &b->time_s, sizeof(double));
    assert_memory_equal(&a->dt_s, &b->dt_s, sizeof(double));
    assert_memory_equal(&a->head, &b->head, sizeof(a->head));
    assert_memory_equal(&a->nav, &b->nav, sizeof(a->nav));
    assert_memory_equal(&a->camera, &b->camera, sizeof(a->camera));
    assert_int_equal(a->wand_valid, b->wand_valid);
    assert_memory_equal(a->wand_position, b->wand_position, sizeof(a->wand_position));
    assert_memory_equal(a->wand_direction, b->wand_direction, sizeof(a->wand_direction));
    assert_int_equal(a->time_step, b->time_step);
    assert_memory_equal(&a->step_fraction, &b->step_fraction, sizeof(float));
    assert_int_equal(a->playing, b->playing);
    assert_memory_equal(&a->sun_azimuth_deg, &b->sun_azimuth_deg, sizeof(double));
    assert_memory_equal(&a->sun_elevation_deg, &b->sun_elevation_deg, sizeof(double));
    assert_int_equal(a->menu_visible, b->menu_visible);
    assert_int_equal(a->settings_revision, b->settings_revision);
    assert_int_equal(a->probe_valid, b->probe_valid);
    assert_memory_equal(a->probe_point, b->probe_point, sizeof(a->probe_point));
}

static void test_round_trip(void **state)
{
    struct frame_state f, g;
    sample(&f);
    uint8_t buf[FRAME_STATE_BYTES];
    assert_int_equal(frame_state_write(&f, buf), FRAME_STATE_BYTES);
    assert_true(frame_state_read(buf, sizeof(buf), &g));
    assert_same(&f, &g);
    /* Flags off survive too. */
    f.wand_valid = f.playing = f.menu_visible = f.probe_valid = false;
    frame_state_write(&f, buf);
    assert_true(frame_state_read(buf, sizeof(buf), &g));
    assert_same(&f, &g);
}

/* The layout does not depend on the platform: magic "AVNF", version 2, then the time step,
 * the flags and the frame number, all little-endian. */
static void test_layout(void **state)
{
    struct frame_state f;
    sample(&f);
    uint8_t buf[FRAME_STATE_BYTES];
    frame_state_write(&f, buf);
    const uint8_t head[] = {'A', 'V', 'N', 'F', 2, 0, 0, 0, 7, 0, 0, 0, 15, 0, 0, 0,
                            8, 7, 6, 5, 4, 3, 2, 1};
    assert_memory_equal(buf, head, sizeof(head));
    double t;
    memcpy(&t, buf + sizeof(head), sizeof(t)); /* on a little-endian machine */
    assert_true(t == 12.25);
}

static void expect_refused(uint8_t *buf, size_t len, const char *what)
{
    struct frame_state g;
    log_set_level(LOG_NONE);
    bool ok = frame_state_read(buf, len, &g);
    log_set_level(LOG_INFO);
    if (ok)
        fail_msg("accepted %s", what);
}

static void test_refuses_bad_bytes(void **state)
{
    struct frame_state f;
    sample(&f);
    uint8_t good[FRAME_STATE_BYTES], buf[FRAME_STATE_BYTES];
    frame_state_write(&f, good);
    expect_refused(good, FRAME_STATE_BYTES - 1, "a short buffer");

    memcpy(buf, good, sizeof(buf));
    buf[0] ^= 1;
    expect_refused(buf, sizeof(buf), "a wrong magic number");
    memcpy(buf, good, sizeof(buf));
    buf[4] = 1;
    expect_refused(buf, sizeof(buf), "another version");
    memcpy(buf, good, sizeof(buf));
    buf[12] |= 0x80;
    expect_refused(buf, sizeof(buf), "unknown flags");
    memcpy(buf, good, sizeof(buf));
    buf[FRAME_STATE_BYTES - 1] = 1;
    expect_refused(buf, sizeof(buf), "bytes past the fields");

    struct frame_state bad = f;
    bad.sun_elevation_deg = NAN;
    frame_state_write(&bad, buf);
    expect_refused(buf, sizeof(buf), "a NaN");
    bad = f;
    bad.camera.eye[1] = INFINITY;
    frame_state_write(&bad, buf);
    expect_refused(buf, sizeof(buf), "an infinite camera");
    bad = f;
    bad.head.rotation[3] *= 2.0f;
    frame_state_write(&bad, buf);
    expect_refused(buf, sizeof(buf), "a head rotation that is no unit quaternion");
    bad = f;
    bad.step_fraction = 1.5f;
    frame_state_write(&bad, buf);
    expect_refused(buf, sizeof(buf), "a fraction past 1");
    bad = f;
    bad.time_step = -1;
    frame_state_write(&bad, buf);
    expect_refused(buf, sizeof(buf), "a negative time step");
    bad = f;
    bad.nav.scale = 0.0;
    frame_state_write(&bad, buf);
    expect_refused(buf, sizeof(buf), "a navigation scale of 0");
    bad = f;
    bad.probe_point[2] = NAN;
    frame_state_write(&bad, buf);
    expect_refused(buf, sizeof(buf), "a probe point that is not finite");

    /* Every single flipped bit of the header is caught or read back as written. */
    for (int byte = 0; byte < 16; byte++) {
        for (int bit = 0; bit < 8; bit++) {
            memcpy(buf, good, sizeof(buf));
            buf[byte] ^= (uint8_t)(1u << bit);
            struct frame_state g;
            log_set_level(LOG_NONE);
            bool ok = frame_state_read(buf, sizeof(buf), &g);
            log_set_level(LOG_INFO);
            /* Accepted only where any value is one: the time step, the four flags. */
            if (ok)
                assert_true((byte >= 8 && byte < 12) || (byte == 12 && bit < 4));
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_layout),
        cmocka_unit_test(test_refuses_bad_bytes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
