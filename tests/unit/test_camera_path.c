/* Camera paths: files read and written, every key met exactly at its time, a smooth flight
 * between (continuous, no kinks at the keys), holds before and after, bad files refused. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "common/log.h"
#include "config/camera_path.h"
#include "session/camera_path.h"

static const char three_keys[] =
    "camera_path = {\n"
    "  keys = (\n"
    "    { time = 0.0; position = [2.0, -14.0, 4.0]; target = [30.0, 30.0, 7.0]; step = 0.0; },\n"
    "    { time = 4.0; position = [40.0, -10.0, 8.0]; target = [30.0, 30.0, 5.0];\n"
    "      fov = 40.0; step = 2.0; },\n"
    "    { time = 10.0; position = [70.0, 40.0, 12.0]; target = [30.0, 25.0, 0.0];\n"
    "      up = [0.0, 0.0, 1.0]; fov = 60; step = 3.0; }\n"
    "  );\n"
    "};\n";

static const struct display_camera base = {.near_m = 10.0, .far_m = 2e6};

static void load(const char *text, struct camera_path *p)
{
    assert_true(camera_path_load(test_write_file("path.cfg", text), p));
}

static double dist(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

static void test_keys_met_exactly(void **state)
{
    struct camera_path p;
    load(three_keys, &p);
    assert_int_equal(p.count, 3);
    assert_true(p.has_steps);
    assert_true(camera_path_duration(&p) == 10.0);
    for (int i = 0; i < p.count; i++) {
        struct display_camera c;
        double step = -1.0;
        camera_path_eval(&p, p.keys[i].time_s, &base, &c, &step);
        for (int a = 0; a < 3; a++) {
            assert_true(c.eye[a] == p.keys[i].position_km[a] * 1000.0);
            assert_true(c.target[a] == p.keys[i].target_km[a] * 1000.0);
        }
        assert_true(c.fov_deg == p.keys[i].fov_deg);
        assert_true(step == p.keys[i].step);
        assert_true(c.near_m == 10.0 && c.far_m == 2e6);
    }
    /* Defaults: fov 50, up z. */
    assert_true(p.keys[0].fov_deg == 50.0 && p.keys[0].up[2] == 1.0);
}

static void test_smooth_between(void **state)
{
    struct camera_path p;
    load(three_keys, &p);
    /* Continuous: a small step in time moves the eye a little, at and away from the keys,
     * and the velocity has no jump at the middle key (Catmull-Rom is C1). */
    const double h = 1e-4;
    struct display_camera a, b, c;
    for (double t = 0.05; t < 9.95; t += 0.05) {
        camera_path_eval(&p, t - h, &base, &a, NULL);
        camera_path_eval(&p, t, &base, &b, NULL);
        camera_path_eval(&p, t + h, &base, &c, NULL);
        double v1 = dist(a.eye, b.eye) / h, v2 = dist(b.eye, c.eye) / h;
        assert_true(fabs(v1 - v2) < 0.01 * fmax(v1, v2) + 1.0); /* no kink anywhere */
        assert_true(dist(a.eye, b.eye) < 40.0); /* m in 0.1 ms: no teleport */
        /* The view keeps looking at a point about as far as its keys' targets. */
        double d = dist(b.eye, b.target);
        assert_true(d > 1000.0 && d < 80000.0);
    }
    camera_path_eval(&p, 4.0 - h, &base, &a, NULL);
    camera_path_eval(&p, 4.0, &base, &b, NULL);
    camera_path_eval(&p, 4.0 + h, &base, &c, NULL);
    double before = dist(a.eye, b.eye) / h, after = dist(b.eye, c.eye) / h;
    assert_true(fabs(before - after) < 0.01 * fmax(before, after) + 1.0);
    /* Linear in fov and step between keys. */
    double step = -1.0;
    camera_path_eval(&p, 2.0, &base, &b, &step);
    assert_float_equal(b.fov_deg, 45.0, 1e-9);
    assert_float_equal(step, 1.0, 1e-9);
    /* Holds before the first and after the last key. */
    camera_path_eval(&p, -5.0, &base, &a, NULL);
    camera_path_eval(&p, 0.0, &base, &b, NULL);
    assert_memory_equal(&a, &b, sizeof(a));
    camera_path_eval(&p, 99.0, &base, &a, NULL);
    camera_path_eval(&p, 10.0, &base, &b, NULL);
    assert_memory_equal(&a, &b, sizeof(a));
}

static void test_save_load(void **state)
{
    struct camera_path p, q;
    load(three_keys, &p);
    const char *path = test_tmp_path("saved.cfg");
    assert_true(camera_path_save(path, &p));
    assert_true(camera_path_load(path, &q));
    assert_int_equal(q.count, p.count);
    assert_int_equal(q.has_steps, p.has_steps);
    for (int i = 0; i < p.count; i++) {
        assert_float_equal(q.keys[i].time_s, p.keys[i].time_s, 1e-6);
        assert_float_equal(q.keys[i].fov_deg, p.keys[i].fov_deg, 1e-6);
        assert_float_equal(q.keys[i].step, p.keys[i].step, 1e-6);
        for (int a = 0; a < 3; a++)
            assert_float_equal(q.keys[i].position_km[a], p.keys[i].position_km[a], 1e-6);
    }
    /* A key made from a camera in metres reads back in km. */
    struct display_camera c = {.eye = {1000, 2000, 3000}, .target = {4000, 5000, 6000},
                               .up = {0, 0, 1}, .fov_deg = 33};
    struct camera_key k;
    camera_path_key(&c, 7.0, 1.5, &k);
    assert_true(k.position_km[1] == 2.0 && k.target_km[2] == 6.0 && k.time_s == 7.0);
}

static void expect_bad(const char *text, const char *says)
{
    struct camera_path p = {.count = 99};
    log_set_level(LOG_NONE);
    bool ok = camera_path_load(test_write_file("bad.cfg", text), &p);
    log_set_level(LOG_INFO);
    assert_false(ok);
    assert_int_equal(p.count, 99); /* untouched */
    if (!strstr(log_last_error(), says))
        fail_msg("message \"%s\" lacks \"%s\"", log_last_error(), says);
}

static void test_bad_files(void **state)
{
    expect_bad("camera_path = { keys = (); };", "1 to 256 key views");
    expect_bad("nothing = 1;", "camera_path.keys");
    expect_bad("camera_path = { keys = ({ position = [0.0,0.0,1.0]; target = [1.0,0.0,1.0]; }); };",
               "missing time");
    expect_bad("camera_path = { keys = ({ time = 0.0; target = [1.0,0.0,1.0]; }); };",
               "camera_path.keys.[0].position: missing");
    expect_bad("camera_path = { keys = ({ time = 1.0; position = [0.0,0.0,1.0]; target = [1.0,0.0,1.0]; },\n"
               "{ time = 1.0; position = [0.0,0.0,1.0]; target = [1.0,0.0,1.0]; }); };",
               "times must increase");
    expect_bad("camera_path = { keys = ({ time = 0.0; position = [0.0,0.0,1.0]; target = [0.0,0.0,1.0]; }); };",
               "target away from the position");
    expect_bad("camera_path = { keys = ({ time = 0.0; position = [0.0,0.0,1.0]; target = [0.0,0.0,5.0]; }); };",
               "not along the view");
    expect_bad("camera_path = { keys = ({ time = 0.0; position = [0.0,0.0,1.0]; target = [1.0,0.0,1.0]; fov = 200.0; }); };",
               "fov: expected a number in [1, 179]");
    expect_bad("camera_path = { keys = ({ time = 0.0; position = [0.0,0.0,1.0]; target = [1.0,0.0,1.0]; step = 1.0; },\n"
               "{ time = 1.0; position = [0.0,0.0,1.0]; target = [1.0,0.0,1.0]; }); };",
               "step on every key or on none");
    expect_bad("camera_path = { keys = ({ time = 0.0; position = [0.0,0.0,1.0]; target = [1.0,0.0,1.0]; zoom = 2.0; }); };",
               "unknown setting");
    expect_bad("camera_path = { keys = ({ time = 0.0; position = [0.0,0.0]; target = [1.0,0.0,1.0]; }); };",
               "three finite numbers");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_keys_met_exactly),
        cmocka_unit_test(test_smooth_between),
        cmocka_unit_test(test_save_load),
        cmocka_unit_test(test_bad_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
