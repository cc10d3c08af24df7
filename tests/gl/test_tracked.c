/* A tracked CAVE through the one frame loop, with the tracker on loopback: the head pose the
 * loop samples is the DTrack body's after calibration (to 1e-6 m and 1e-6 rad); moving it 0.3 m
 * to the left changes every wall's projection as Kooima's frustum says; an untracked body keeps
 * the last pose; a Flystick pointing at the menu's Play and pressing its trigger starts
 * playback; a VRPN head follows, and while its server is away the loop keeps drawing. */
#include <arpa/inet.h>
#include <math.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fake_tracker.h"
#include "testutil.h"

#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "menu/menu.h"
#include "session/frame.h"
#include "session/scene.h"
#include "session/session.h"

#define TIMEOUT_MS 5000.0

static struct gpu_context *ctx;
static char series_cfg[1024];

static int free_udp_port(void)
{
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof(a);
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof(a)), 0);
    assert_int_equal(getsockname(fd, (struct sockaddr *)&a, &len), 0);
    close(fd);
    return ntohs(a.sin_port);
}

/* cave4-dtrack.cfg (or cave4-vrpn.cfg) with its tracker on PORT of this machine. */
static void tracked_cave(const char *file, int port, bool wand, struct display_config *dcfg)
{
    char path[1024], set[160];
    snprintf(path, sizeof(path), "%s/displays/%s", ANVIL_SOURCE_DIR, file);
    assert_true(display_config_load(path, dcfg));
    bool vrpn = strstr(file, "vrpn") != NULL;
    snprintf(set, sizeof(set), vrpn ? "head.address=Head@127.0.0.1:%d" : "head.address=%d", port);
    assert_true(display_config_set(dcfg, set));
    snprintf(set, sizeof(set), vrpn ? "wand.address=Wand@127.0.0.1:%d" : "wand.address=%d", port);
    assert_true(display_config_set(dcfg, set));
    if (vrpn) {
        snprintf(set, sizeof(set), "wand.controls=Wand@127.0.0.1:%d", port);
        assert_true(display_config_set(dcfg, set));
    }
    if (!wand)
        assert_true(display_config_set(dcfg, "wand.source=none"));
    assert_true(display_config_validate(dcfg));
}

struct rig {
    struct config cfg;
    struct display *d;
    struct session *s;
    struct frame_state f;
    long frames;
};

static void rig_open(struct rig *r, const struct display_config *dcfg, bool series, bool menu)
{
    memset(r, 0, sizeof(*r));
    if (series)
        test_config_file(&r->cfg, series_cfg,
                         (const char *[]){"render.height=24", "lightmap.resolution=[16,16,16]"}, 2);
    else
        test_config_from(&r->cfg,
                         (const char *[]){"scene.size=[16,16,8]", "render.height=24",
                                          "lightmap.resolution=[16,16,16]"},
                         3);
    struct display_desc dd = {.offscreen = true, .context = ctx, .height = 24};
    scene_camera(&r->cfg, &dd.camera);
    r->d = display_create(dcfg, &dd);
    assert_non_null(r->d);
    int rc;
    r->s = session_create(&r->cfg,
                          &(struct session_desc){.command = "render",
                                                 .display = dcfg,
                                                 .views_move = true,
                                                 .playback = series,
                                                 .menu = menu,
                                                 .show_menu = menu},
                          &rc);
    assert_non_null(r->s);
}

/* One frame of the loop, in its order: the head sampled last. */
static void rig_frame(struct rig *r)
{
    bool redraw;
    assert_true(session_update(r->s, NULL, 0.1, 0.0, &r->f, &redraw));
    assert_true(session_apply(r->s, &r->f, NULL));
    assert_true(session_light(r->s));
    assert_true(display_sample_head(r->d, r->f.time_s, &r->f.head));
    assert_true(session_draw(r->s, r->d, &r->f));
    r->frames++;
}

static void rig_close(struct rig *r)
{
    session_destroy(r->s);
    display_destroy(r->d);
}

static double distance(const float a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

/* The angle between two rotations (radians): of conj(B) A, as 2 atan2(|xyz|, |w|), which
 * stays exact for small angles (acos of a dot product would not). */
static double angle(const float a[4], const double b[4])
{
    double x = b[3] * a[0] - b[0] * a[3] - b[1] * a[2] + b[2] * a[1];
    double y = b[3] * a[1] + b[0] * a[2] - b[1] * a[3] - b[2] * a[0];
    double z = b[3] * a[2] - b[0] * a[1] + b[1] * a[0] - b[2] * a[3];
    double w = b[3] * a[3] + b[0] * a[0] + b[1] * a[1] + b[2] * a[2];
    return 2.0 * atan2(sqrt(x * x + y * y + z * z), fabs(w));
}

/* DTrack's datagram for body 0 at P (mm) turned YAW degrees about DTrack's z (up). */
static void body_text(char *out, size_t n, int counter, const double p[3], double yaw,
                      double quality)
{
    double c = cos(yaw * M_PI / 180.0), s = sin(yaw * M_PI / 180.0);
    snprintf(out, n,
             "fr %d\r\nts %d.0\r\n6dcal 1\r\n6d 1 [0 %.3f][%.6f %.6f %.6f]"
             "[%.9f %.9f 0 %.9f %.9f 0 0 0 1]\r\n",
             counter, counter, quality, p[0], p[1], p[2], c, s, -s, c);
}

/* Runs frames, sending TEXT before each, until the loop's head is at WANT (room m) turned
 * YAW about the room's y. */
static void frames_until_head(struct rig *r, int fd, int port, const char *text,
                              const double want[3], double yaw)
{
    double h = yaw * M_PI / 360.0;
    const double q[4] = {0, sin(h), 0, cos(h)};
    double end = time_now_ms() + TIMEOUT_MS;
    do {
        if (fd >= 0)
            assert_true(fake_udp_send_text(fd, port, text));
        rig_frame(r);
        if (distance(r->f.head.position, want) < 1e-6 && angle(r->f.head.rotation, q) < 1e-6)
            return;
        fake_sleep_ms(1);
    } while (time_now_ms() < end);
    fail_msg(
        "the loop's head is at (%g %g %g) rotated (%g %g %g %g), expected (%g %g %g) turned %g",
        r->f.head.position[0], r->f.head.position[1], r->f.head.position[2], r->f.head.rotation[0],
        r->f.head.rotation[1], r->f.head.rotation[2], r->f.head.rotation[3], want[0], want[1],
        want[2], yaw);
}

/* Every view's frustum is the one Kooima's math gives for its eye of HEAD (room m). */
static void views_match(struct rig *r, const double head[3], double yaw, float extents[][4])
{
    const struct display_config *dcfg = display_get_config(r->d);
    struct display_pose pose;
    display_pose_from_euler(head, (double[]){yaw, 0, 0}, &pose);
    float eyes[2][3];
    display_pose_eyes(&pose, dcfg->eye_separation, eyes[0], eyes[1]);
    assert_int_equal(display_view_count(r->d), 8);
    for (int i = 0; i < display_view_count(r->d); i++) {
        const struct view *v = display_view(r->d, i);
        const float *eye = eyes[v->eye == VIEW_EYE_RIGHT ? 1 : 0];
        float view[16], proj[16], ext[4];
        bool visible = display_wall_projection(&dcfg->walls[v->wall], eye, (float)dcfg->near_m,
                                               (float)dcfg->far_m, view, proj, ext);
        assert_int_equal(v->visible, visible);
        for (int k = 0; k < 4; k++)
            assert_float_equal(v->extent[k], ext[k], 1e-5);
        memcpy(extents[i], v->extent, sizeof(v->extent));
    }
}

static void test_head_through_the_loop(void **state)
{
    int port = free_udp_port();
    struct display_config dcfg;
    tracked_cave("cave4-dtrack.cfg", port, false, &dcfg);
    /* DTrack's origin 0.5 m right of the room's and 0.25 m forward, its axes turned a quarter
     * to the left. */
    assert_true(display_config_set(&dcfg, "head.offset=[0.5,0.0,-0.25]"));
    assert_true(display_config_set(&dcfg, "head.rotation=[90,0,0]"));
    assert_true(display_config_validate(&dcfg));
    struct rig r;
    rig_open(&r, &dcfg, false, false);
    int fd = fake_udp_socket();
    char text[512];

    /* Before any datagram: head.position. */
    rig_frame(&r);
    assert_true(distance(r.f.head.position, (double[]){0.0, 1.6, 0.5}) < 1e-6);

    /* DTrack (z up, mm): x 120, y -480, z 1650, turned 30 degrees about its z.  Axes x z -y:
     * (0.12, 1.65, 0.48) m; turned 90 degrees about y: (0.48, 1.65, -0.12); plus the offset:
     * (0.98, 1.65, -0.37), turned 30 + 90 degrees about y. */
    const double yaw = 120.0;
    const double p1[3] = {120.0, -480.0, 1650.0}, room1[3] = {0.98, 1.65, -0.37};
    body_text(text, sizeof(text), 1, p1, 30.0, 1.0);
    frames_until_head(&r, fd, port, text, room1, yaw);
    float before[8][4], after[8][4];
    views_match(&r, room1, yaw, before);

    /* 0.3 m to the left in the room: 300 mm along DTrack's y, which the calibration turns
     * into the room's -x. */
    const double p2[3] = {120.0, -180.0, 1650.0}, room2[3] = {0.68, 1.65, -0.37};
    body_text(text, sizeof(text), 2, p2, 30.0, 1.0);
    frames_until_head(&r, fd, port, text, room2, yaw);
    views_match(&r, room2, yaw, after);
    /* The front wall (z = -1.5, x from -1.5 to 1.5) from an eye at ex, ez: left and right
     * extents (edge - ex) near / (ez + 1.5), so both grow by 0.3 near / d. */
    const struct display_config *c = display_get_config(r.d);
    for (int i = 0; i < 2; i++) {
        const struct view *v = display_view(r.d, i);
        assert_string_equal(c->walls[v->wall].name, "front");
        float eyes[2][3];
        struct display_pose pose;
        display_pose_from_euler(room2, (double[]){yaw, 0, 0}, &pose);
        display_pose_eyes(&pose, c->eye_separation, eyes[0], eyes[1]);
        const float *e = eyes[v->eye == VIEW_EYE_RIGHT ? 1 : 0];
        double d = e[2] + 1.5, k = c->near_m / d;
        assert_float_equal(after[i][0], (-1.5 - e[0]) * k, 1e-6);
        assert_float_equal(after[i][1], (1.5 - e[0]) * k, 1e-6);
        assert_float_equal(after[i][0] - before[i][0], 0.3 * k, 1e-6);
        assert_float_equal(after[i][1] - before[i][1], 0.3 * k, 1e-6);
    }
    /* Every wall changed. */
    for (int i = 0; i < 8; i++)
        assert_true(memcmp(before[i], after[i], sizeof(before[i])) != 0);

    /* Not tracked: the head stays where it was, warned about once. */
    unsigned warnings = log_warn_count();
    log_set_level(LOG_ERROR);
    for (int k = 0; k < 20; k++) {
        body_text(text, sizeof(text), 3 + k, (double[]){900, 900, 900}, 0.0, -1.0);
        assert_true(fake_udp_send_text(fd, port, text));
        rig_frame(&r);
        fake_sleep_ms(2);
        assert_true(distance(r.f.head.position, room2) < 1e-6);
    }
    log_set_level(LOG_WARN);
    assert_int_equal(log_warn_count(), warnings + 1);
    close(fd);
    rig_close(&r);
}

/* The Flystick points at Play and clicks: playback starts, and time moves. */
static void test_wand_plays(void **state)
{
    int port = free_udp_port();
    struct display_config dcfg;
    tracked_cave("cave4-dtrack.cfg", port, true, &dcfg);
    struct rig r;
    rig_open(&r, &dcfg, true, true);
    rig_frame(&r); /* the menu is placed */
    assert_false(r.f.playing);
    float p[3];
    assert_true(menu_widget_point(session_menu(r.s), "time.play", 0.5f, 0.5f, p));
    /* 0.3 m in front of the panel (which faces +z), pointing at it: room -z. */
    double room[3] = {p[0], p[1], p[2] + 0.3};
    double dt[3] = {1000.0 * room[0], -1000.0 * room[2], 1000.0 * room[1]}; /* room -> DTrack */
    int fd = fake_udp_socket();
    char text[512];
    int counter = 1;
    /* Phases: point (released) until the loop's ray is on Play, press for 0.2 s, release. */
    int phase = 0;
    double phase_end = 0.0, end = time_now_ms() + 3 * TIMEOUT_MS;
    while (!r.f.playing && time_now_ms() < end) {
        snprintf(text, sizeof(text),
                 "fr %d\n6df2 1 1 [0 1.000 6 2][%.6f %.6f %.6f][1 0 0 0 1 0 0 0 1][%d 0 0]\n",
                 counter++, dt[0], dt[1], dt[2], phase == 1 ? 1 : 0);
        assert_true(fake_udp_send_text(fd, port, text));
        rig_frame(&r);
        if (phase == 0 && r.f.wand_valid && distance(r.f.wand_position, room) < 1e-5 &&
            fabs(r.f.wand_direction[2] + 1) < 1e-6) {
            phase = 1;
            phase_end = time_now_ms() + 200.0;
        } else if (phase == 1 && time_now_ms() > phase_end) {
            phase = 2;
        }
        fake_sleep_ms(2);
    }
    assert_int_equal(phase, 2);
    assert_true(r.f.playing);
    int step = r.f.time_step;
    for (int k = 0; k < 10; k++)
        rig_frame(&r); /* 1 s at 5 steps a second */
    assert_true(r.f.time_step > step);
    close(fd);
    rig_close(&r);
}

/* One screen (displays/desktop-stereo.cfg): the menu lies on it, inside its rectangle, where
 * the eyes see it (before, placed as in a CAVE below and behind the head, only its tab row
 * was on the screen). */
static void test_menu_on_one_screen(void **state)
{
    struct display_config dcfg;
    assert_true(display_config_load(ANVIL_SOURCE_DIR "/displays/desktop-stereo.cfg", &dcfg));
    struct rig r;
    rig_open(&r, &dcfg, false, true);
    rig_frame(&r); /* the menu is placed */
    float c[4][3];
    menu_corners(session_menu(r.s), c);
    const struct display_wall *w = &dcfg.walls[0];
    for (int k = 0; k < 4; k++) {
        assert_true(c[k][0] >= w->lower_left[0] - 1e-5 && c[k][0] <= w->lower_right[0] + 1e-5);
        assert_true(c[k][1] >= w->lower_left[1] - 1e-5 && c[k][1] <= w->upper_left[1] + 1e-5);
        assert_true(fabsf(c[k][2] - (float)w->lower_left[2]) < 1e-5);
    }
    rig_close(&r);
}

/* A VRPN head through the loop; its server goes away and the loop keeps drawing. */
static void test_vrpn_head(void **state)
{
    int port = 0;
    int lfd = fake_tcp_listen(&port);
    assert_true(lfd >= 0);
    struct display_config dcfg;
    tracked_cave("cave4-vrpn.cfg", port, false, &dcfg);
    struct rig r;
    rig_open(&r, &dcfg, false, false);
    int fd = fake_vrpn_accept(lfd, 5.0);
    assert_true(fd >= 0);
    struct fake_bytes *b = calloc(1, sizeof(*b));
    fake_vrpn_describe(b, VRPN_SENDER_DESCRIPTION, 0, "Head");
    fake_vrpn_describe(b, VRPN_TYPE_DESCRIPTION, 0, "vrpn_Tracker Pos_Quat");
    /* Vicon's axes (z up, m): (0.12, -0.48, 1.65), turned 30 degrees about z. */
    double h = 15.0 * M_PI / 180.0;
    fake_vrpn_pose(b, 0, 0, 0, (double[]){0.12, -0.48, 1.65}, (double[]){0, 0, sin(h), cos(h)});
    assert_true(fake_write_chunks(fd, b->data, b->n, 5));
    frames_until_head(&r, -1, 0, NULL, (double[]){0.12, 1.65, 0.48}, 30.0);

    /* The server goes away: frames go on, the head stays. */
    log_set_level(LOG_ERROR);
    close(fd);
    long frames = r.frames;
    double start = time_now_ms();
    while (time_now_ms() - start < 300.0)
        rig_frame(&r);
    assert_true(r.frames - frames >= 3);
    assert_true(distance(r.f.head.position, (double[]){0.12, 1.65, 0.48}) < 1e-6);
    /* It comes back: the new pose arrives. */
    fd = fake_vrpn_accept(lfd, 5.0);
    assert_true(fd >= 0);
    b->n = 0;
    fake_vrpn_describe(b, VRPN_SENDER_DESCRIPTION, 0, "Head");
    fake_vrpn_describe(b, VRPN_TYPE_DESCRIPTION, 0, "vrpn_Tracker Pos_Quat");
    fake_vrpn_pose(b, 0, 0, 0, (double[]){-0.18, -0.48, 1.65}, (double[]){0, 0, 0, 1});
    assert_true(fake_write_chunks(fd, b->data, b->n, 0));
    frames_until_head(&r, -1, 0, NULL, (double[]){-0.18, 1.65, 0.48}, 0.0);
    log_set_level(LOG_WARN);
    close(fd);
    close(lfd);
    free(b);
    rig_close(&r);
}

static int setup(void **state)
{
    ctx = test_gl_context_or_skip();
    const char *bin = getenv("ANVIL_BIN");
    char cmd[2048];
    snprintf(cmd, sizeof(cmd),
             "'%s' --quiet synth -o '%s' --steps 4 --size 16x16x8 --extent 16x16x8", bin,
             test_tmp_path("series.nc"));
    if (system(cmd) != 0)
        return -1;
    snprintf(series_cfg, sizeof(series_cfg), "%s",
             test_write_file("series.cfg",
                             "scene = { kind = \"data\"; };\n"
                             "data = { format = \"wrf\"; files = [\"series.nc\"]; };\n"
                             "playback = { speed = 5.0; loop = false; };\n"));
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
        cmocka_unit_test(test_head_through_the_loop),
        cmocka_unit_test(test_wand_plays),
        cmocka_unit_test(test_menu_on_one_screen),
        cmocka_unit_test(test_vrpn_head),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
