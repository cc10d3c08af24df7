/* Trackers on loopback: the calibration into the room (closed forms, the display's Euler
 * convention), a DTrack stream (a head body and a Flystick sharing one port, an untracked body
 * reported once and keeping its pose, dropped frames, malformed datagrams refused with a
 * warning), and a fake VRPN server (descriptions, poses, buttons and analogs split and
 * coalesced, the wand's events, a malformed message, a server that goes away and comes back,
 * broken framing). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include "fake_tracker.h"
#include "testutil.h"

#include "common/log.h"
#include "display/display.h"
#include "input/input.h"
#include "input/tracker.h"

#define TIMEOUT_S 5.0

static void quat_equal(const double *a, const double *b, double tol)
{
    /* q and -q are the same rotation */
    double d = 0.0, e = 0.0;
    for (int i = 0; i < 4; i++) {
        d = fmax(d, fabs(a[i] - b[i]));
        e = fmax(e, fabs(a[i] + b[i]));
    }
    if (fmin(d, e) > tol)
        fail_msg("quaternions differ: (%g %g %g %g) (%g %g %g %g)", a[0], a[1], a[2], a[3], b[0],
                 b[1], b[2], b[3]);
}

static void test_calibration(void **state)
{
    struct tracker_calibration c;
    tracker_calibration_identity(&c);
    double p[3], q[4];
    const double id[4] = {0, 0, 0, 1};
    tracker_calibrate(&c, (double[]){1, 2, 3}, id, p, q);
    assert_float_equal(p[0], 1, 0);
    assert_float_equal(p[2], 3, 0);
    quat_equal(q, id, 0);

    /* A z-up tracker in mm, its origin 0.5 m right and 0.25 m forward, turned 90 degrees. */
    c.scale = 1e-3;
    c.axes[0] = 1, c.axes[1] = 3, c.axes[2] = -2;
    c.offset[0] = 0.5, c.offset[2] = -0.25;
    c.rotation_deg[0] = 90;
    tracker_calibrate(&c, (double[]){1000, 2000, 500}, id, p, q);
    /* (1, 2, 0.5) m -> axes (x, z, -y) = (1, 0.5, -2) -> Ry(90) = (-2, 0.5, -1) -> + offset */
    assert_float_equal(p[0], -1.5, 1e-12);
    assert_float_equal(p[1], 0.5, 1e-12);
    assert_float_equal(p[2], -1.25, 1e-12);
    /* The body at rest looks along the tracker's +y: room -z, turned by the rotation. */
    const double s = sqrt(0.5);
    quat_equal(q, (double[]){0, s, 0, s}, 1e-12);
    /* Yawed 90 degrees about the tracker's up (z): about the room's y, before the rotation. */
    tracker_calibrate(&c, (double[]){0, 0, 0}, (double[]){0, 0, s, s}, p, q);
    quat_equal(q, (double[]){0, 1, 0, 0}, 1e-12);

    /* The rotation is the display's heading, pitch, roll. */
    tracker_calibration_identity(&c);
    const double hpr[3] = {30, -20, 10};
    memcpy(c.rotation_deg, hpr, sizeof(hpr));
    tracker_calibrate(&c, (double[]){0, 0, 0}, id, p, q);
    struct display_pose pose;
    display_pose_from_euler((double[]){0, 0, 0}, hpr, &pose);
    double want[4] = {pose.rotation[0], pose.rotation[1], pose.rotation[2], pose.rotation[3]};
    quat_equal(q, want, 1e-6);

    /* Matrix to quaternion and back, for rotations near each of the four branches. */
    const double qs[][4] = {{0.1, 0.2, 0.3, 0.9},
                            {0.9, 0.1, -0.2, 0.1},
                            {0.1, -0.95, 0.2, 0.05},
                            {-0.2, 0.1, 0.97, 0.05}};
    for (int k = 0; k < 4; k++) {
        double u[4];
        double len = 0;
        for (int i = 0; i < 4; i++)
            len += qs[k][i] * qs[k][i];
        for (int i = 0; i < 4; i++)
            u[i] = qs[k][i] / sqrt(len);
        double x = u[0], y = u[1], z = u[2], w = u[3];
        double m[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + w * z),     2 * (x * z - w * y),
                       2 * (x * y - w * z),     1 - 2 * (x * x + z * z), 2 * (y * z + w * x),
                       2 * (x * z + w * y),     2 * (y * z - w * x),     1 - 2 * (x * x + y * y)};
        double back[4];
        tracker_quat_from_matrix(m, back);
        quat_equal(back, u, 1e-12);
    }
}

/* ---- DTrack ----------------------------------------------------------------------------- */

struct wait_poses {
    struct tracker *t;
    uint64_t poses, untracked;
};

static bool got_poses(void *user)
{
    struct wait_poses *w = user;
    struct tracker_sample s;
    tracker_sample(w->t, &s);
    return s.poses >= w->poses && s.untracked >= w->untracked;
}

static void wait_for(struct tracker *t, uint64_t poses, uint64_t untracked)
{
    struct wait_poses w = {t, poses, untracked};
    if (!fake_wait(got_poses, &w, TIMEOUT_S))
        fail_msg("%s: waited for %llu poses and %llu untracked frames", tracker_describe(t),
                 (unsigned long long)poses, (unsigned long long)untracked);
}

struct wait_stats {
    struct tracker *t;
    uint64_t frames, malformed;
};

static bool got_frames(void *user)
{
    struct wait_stats *w = user;
    struct tracker_link_stats s;
    tracker_link_stats(w->t, &s);
    return s.frames >= w->frames && s.malformed >= w->malformed;
}

static void wait_frames(struct tracker *t, uint64_t frames, uint64_t malformed)
{
    struct wait_stats w = {t, frames, malformed};
    assert_true(fake_wait(got_frames, &w, TIMEOUT_S));
}

static struct tracker_desc dtrack_desc(int port, bool flystick, int id)
{
    struct tracker_desc d = {
        .what = flystick ? "wand" : "head", .flystick = flystick, .sensor = id};
    d.address.protocol = TRACKER_DTRACK;
    d.address.port = port;
    tracker_calibration_identity(&d.calibration);
    d.calibration.scale = 1e-3;
    return d;
}

static void test_dtrack_stream(void **state)
{
    struct tracker_desc hd = dtrack_desc(0, false, 1);
    struct tracker *head = tracker_open(&hd);
    assert_non_null(head);
    struct tracker_link_stats st;
    tracker_link_stats(head, &st);
    int port = st.port;
    assert_true(port > 0);
    /* The wand on the same port shares the link. */
    struct tracker_desc wd = dtrack_desc(port, true, 0);
    struct tracker *wand = tracker_open(&wd);
    assert_non_null(wand);
    assert_int_equal(tracker_links_open(), 1);
    int fd = fake_udp_socket();
    assert_true(fd >= 0);

    struct tracker_sample s;
    tracker_sample(head, &s);
    assert_false(s.seen);
    assert_true(fake_udp_send_text(
        fd, port,
        "fr 100\r\nts 10.5\r\n6dcal 2\r\n"
        "6d 2 [0 1.000][0 0 0][1 0 0 0 1 0 0 0 1] "
        "[1 0.950][120.5 1650.25 -300.0][0 0 -1 0 1 0 1 0 0]\r\n"
        "6df2 1 1 [0 1.000 6 2][400 1200 -500][1 0 0 0 1 0 0 0 1][9 0.25 -0.75]\r\n"));
    wait_for(head, 1, 0);
    tracker_sample(head, &s);
    assert_true(s.seen && s.tracked);
    assert_float_equal(s.position[0], 0.1205, 1e-12);
    assert_float_equal(s.position[1], 1.65025, 1e-12);
    assert_float_equal(s.position[2], -0.3, 1e-12);
    /* The matrix (columns x -> -z, y -> y, z -> x) turns 90 degrees about y. */
    quat_equal(s.rotation, (double[]){0, sqrt(0.5), 0, sqrt(0.5)}, 1e-12);
    tracker_sample(wand, &s);
    assert_true(s.tracked);
    assert_int_equal(s.button_count, 6);
    assert_true(s.buttons[0] && !s.buttons[1] && !s.buttons[2] && s.buttons[3]); /* 9 */
    assert_int_equal(s.axis_count, 2);
    assert_float_equal(s.axes[1], -0.75, 0);

    /* Body 1 not tracked for five frames: one warning, the last pose kept. */
    unsigned warnings = log_warn_count();
    for (int f = 0; f < 5; f++) {
        char text[256];
        snprintf(text, sizeof(text), "fr %d\n6d 1 [1 -1.000][0 0 0][0 0 0 0 0 0 0 0 0]\n", 101 + f);
        assert_true(fake_udp_send_text(fd, port, text));
        wait_for(head, 1, (uint64_t)f + 1);
    }
    tracker_sample(head, &s);
    assert_false(s.tracked);
    assert_int_equal(s.untracked, 5);
    assert_float_equal(s.position[1], 1.65025, 1e-12);
    assert_int_equal(log_warn_count(), warnings + 1);
    /* Absent from a frame (DTrack lists only tracked bodies): not tracked either. */
    assert_true(fake_udp_send_text(fd, port, "fr 106\n6d 1 [0 1.0][0 0 0][1 0 0 0 1 0 0 0 1]\n"));
    wait_for(head, 1, 6);
    /* Back, with a frame counter that skipped three frames. */
    assert_true(
        fake_udp_send_text(fd, port, "fr 110\n6d 1 [1 1.0][10 20 30][1 0 0 0 1 0 0 0 1]\n"));
    wait_for(head, 2, 6);
    tracker_sample(head, &s);
    assert_true(s.tracked);
    assert_float_equal(s.position[2], 0.03, 1e-12);
    assert_int_equal(log_warn_count(), warnings + 1);
    tracker_link_stats(head, &st);
    assert_int_equal(st.dropped, 3);
    assert_int_equal(st.frames, 8);
    assert_non_null(strstr(st.seen, "bodies 0 1"));
    assert_non_null(strstr(st.seen, "Flysticks 0"));

    /* Malformed datagrams: refused, counted, warned about (once per few seconds), no harm. */
    warnings = log_warn_count();
    log_set_level(LOG_ERROR);
    assert_true(fake_udp_send_text(fd, port, "fr 111\n6d 2 [1 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\n"));
    assert_true(fake_udp_send(fd, port, "\xff\x00\x17garbage", 10));
    assert_true(fake_udp_send_text(fd, port, "fr 112\n6d 1 [1 1.0][5 6"));
    wait_frames(head, 8, 3);
    log_set_level(LOG_INFO);
    assert_int_equal(log_warn_count(), warnings + 1);
    assert_true(
        fake_udp_send_text(fd, port, "fr 113\n6d 1 [1 1.0][-10 20 30][1 0 0 0 1 0 0 0 1]\n"));
    wait_for(head, 3, 6);
    tracker_sample(head, &s);
    assert_float_equal(s.position[0], -0.01, 1e-12);

    close(fd);
    tracker_close(wand);
    assert_int_equal(tracker_links_open(), 1);
    tracker_close(head);
    assert_int_equal(tracker_links_open(), 0);
}

/* The port is taken by another program, or the address is no IPv4 one: a clear error each,
 * no link left behind. */
static void test_dtrack_port_taken(void **state)
{
    int other = socket(AF_INET, SOCK_DGRAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof(a);
    assert_int_equal(bind(other, (struct sockaddr *)&a, sizeof(a)), 0);
    assert_int_equal(getsockname(other, (struct sockaddr *)&a, &len), 0);
    struct tracker_desc d = dtrack_desc(ntohs(a.sin_port), false, 0);
    log_set_level(LOG_NONE);
    unsigned errors = log_error_count();
    assert_null(tracker_open(&d));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "cannot listen on UDP port"));
    snprintf(d.address.host, sizeof(d.address.host), "not-an-address");
    assert_null(tracker_open(&d));
    assert_int_equal(log_error_count(), errors + 2);
    assert_non_null(strstr(log_last_error(), "not an IPv4 address"));
    log_set_level(LOG_INFO);
    close(other);
    assert_int_equal(tracker_links_open(), 0);
}

/* DTrack to a multicast group (its "send to a multicast address" output): joined, received. */
static void test_dtrack_multicast(void **state)
{
    struct tracker_desc d = dtrack_desc(0, false, 0);
    snprintf(d.address.host, sizeof(d.address.host), "239.255.42.99");
    log_set_level(LOG_NONE);
    struct tracker *t = tracker_open(&d);
    log_set_level(LOG_INFO);
    if (!t) {
        fprintf(stderr, "no multicast route here (%s): multicast not tested\n", log_last_error());
        return;
    }
    struct tracker_link_stats st;
    tracker_link_stats(t, &st);
    int fd = fake_udp_socket();
    struct in_addr lo = {.s_addr = htonl(INADDR_LOOPBACK)};
    assert_int_equal(setsockopt(fd, IPPROTO_IP, IP_MULTICAST_IF, &lo, sizeof(lo)), 0);
    struct sockaddr_in g = {.sin_family = AF_INET, .sin_port = htons((uint16_t)st.port)};
    inet_pton(AF_INET, "239.255.42.99", &g.sin_addr);
    const char *text = "fr 1\n6d 1 [0 1.0][1000 2000 3000][1 0 0 0 1 0 0 0 1]\n";
    struct wait_poses w = {t, 1, 0};
    double end = time_now_ms() + 2000.0;
    while (!got_poses(&w) && time_now_ms() < end) {
        sendto(fd, text, strlen(text), 0, (struct sockaddr *)&g, sizeof(g));
        fake_sleep_ms(5);
    }
    assert_true(got_poses(&w)); /* joined on loopback too */
    struct tracker_sample s;
    tracker_sample(t, &s);
    assert_float_equal(s.position[2], 3.0, 1e-12);
    close(fd);
    tracker_close(t);
}

/* ---- VRPN -------------------------------------------------------------------------------- */

static struct tracker_desc vrpn_desc(int port, const char *device, int sensor)
{
    struct tracker_desc d = {.what = "head", .sensor = sensor};
    d.address.protocol = TRACKER_VRPN;
    snprintf(d.address.host, sizeof(d.address.host), "127.0.0.1");
    d.address.port = port;
    snprintf(d.address.device, sizeof(d.address.device), "%s", device);
    tracker_calibration_identity(&d.calibration);
    return d;
}

static bool connected(void *user)
{
    struct tracker_link_stats s;
    tracker_link_stats(user, &s);
    return s.connected;
}

static bool disconnected(void *user)
{
    return !connected(user);
}

/* The server's descriptions: senders 0 Head, 1 Wand; types 0 Pos_Quat, 1 Button Change,
 * 2 Analog Channel, 3 an unknown one. */
static void describe(struct fake_bytes *b)
{
    fake_vrpn_describe(b, VRPN_SENDER_DESCRIPTION, 0, "Head");
    fake_vrpn_describe(b, VRPN_SENDER_DESCRIPTION, 1, "Wand");
    fake_vrpn_describe(b, VRPN_TYPE_DESCRIPTION, 0, "vrpn_Tracker Pos_Quat");
    fake_vrpn_describe(b, VRPN_TYPE_DESCRIPTION, 1, "vrpn_Button Change");
    fake_vrpn_describe(b, VRPN_TYPE_DESCRIPTION, 2, "vrpn_Analog Channel");
    fake_vrpn_describe(b, VRPN_TYPE_DESCRIPTION, 3, "vrpn_Tracker Velocity");
}

static void test_vrpn_server(void **state)
{
    int port = 0;
    int lfd = fake_tcp_listen(&port);
    assert_true(lfd >= 0);
    struct tracker_desc hd = vrpn_desc(port, "Head", 1);
    struct tracker *head = tracker_open(&hd);
    assert_non_null(head);
    struct tracker_wand_desc wd = {
        .tracker = vrpn_desc(port, "Wand", 0),
        .buttons = {2, 0, -1, -1}, /* trigger: button 2; grab: button 0 */
        .axes = {1, 0},
        .axis_scale = {1.0, -1.0},
        .dead_zone = 0.1,
    };
    wd.tracker.what = "wand";
    struct input_source *wand = tracker_wand_create(&wd);
    assert_non_null(wand);
    assert_int_equal(tracker_links_open(), 1); /* one server, one connection */

    int fd = fake_vrpn_accept(lfd, TIMEOUT_S);
    assert_true(fd >= 0);
    struct fake_bytes *b = calloc(1, sizeof(*b));
    describe(b);
    const double s = sqrt(0.5);
    fake_vrpn_pose(b, 0, 3, 1, (double[]){9, 9, 9}, (double[]){0, 0, 0, 1}); /* velocity */
    fake_vrpn_pose(b, 0, 0, 0, (double[]){7, 7, 7}, (double[]){0, 0, 0, 1}); /* sensor 0 */
    fake_vrpn_pose(b, 0, 0, 1, (double[]){0.25, 1.7, 0.4}, (double[]){0, s, 0, s});
    fake_vrpn_pose(b, 1, 0, 0, (double[]){0.1, 1.2, -0.3}, (double[]){0, 0, 0, 1});
    fake_vrpn_button(b, 1, 1, 2, 1);
    fake_vrpn_analog(b, 1, 2, (double[]){0.05, 0.5, 0.0}, 3);
    assert_true(fake_write_chunks(fd, b->data, b->n, 7)); /* split mid-message, over and over */
    wait_for(head, 1, 0);
    struct tracker_sample smp;
    tracker_sample(head, &smp);
    assert_true(smp.tracked);
    assert_float_equal(smp.position[0], 0.25, 0);
    assert_float_equal(smp.position[1], 1.7, 0);
    assert_float_equal(smp.position[2], 0.4, 0);
    quat_equal(smp.rotation, (double[]){0, s, 0, s}, 1e-15);

    /* The wand's events: its ray, the trigger (button 2), fly (channel 1, reversed). */
    struct input_queue *q = calloc(1, sizeof(*q));
    bool pose = false, trigger = false, fly = false;
    double end = time_now_ms() + TIMEOUT_S * 1000;
    while (!(pose && trigger && fly) && time_now_ms() < end) {
        input_queue_clear(q);
        assert_true(input_source_poll(wand, &(struct input_frame){.frame = 0}, q));
        for (int i = 0; i < q->count; i++) {
            const struct input_event *e = &q->events[i];
            if (e->type == INPUT_POSE) {
                assert_int_equal(e->space, INPUT_SPACE_TRACKER);
                assert_float_equal(e->position[2], -0.3f, 1e-7);
                assert_float_equal(e->direction[2], -1.0f, 1e-7);
                pose = true;
            } else if (e->type == INPUT_BUTTON) {
                assert_int_equal(e->button, INPUT_BUTTON_TRIGGER);
                assert_true(e->down);
                trigger = true;
            } else if (e->type == INPUT_AXIS) {
                assert_int_equal(e->axis, INPUT_AXIS_FLY);
                assert_float_equal(e->value, 0.5f, 0);
                fly = true;
            }
        }
        fake_sleep_ms(1);
    }
    assert_true(pose && trigger && fly);
    /* Nothing changed: no events; turn (channel 0 = 0.05) stays in the dead zone. */
    input_queue_clear(q);
    input_source_poll(wand, &(struct input_frame){.frame = 1}, q);
    assert_int_equal(q->count, 0);

    /* Many messages in one write, a malformed one among them: counted, warned, no harm.  (A
     * fresh pose first, so that no "not tracked" warning of a stale one counts here.) */
    b->n = 0;
    fake_vrpn_pose(b, 0, 0, 1, (double[]){0.4, 1.5, 0.5}, (double[]){0, 0, 0, 1});
    assert_true(fake_write_chunks(fd, b->data, b->n, 0));
    wait_for(head, 2, 0);
    b->n = 0;
    fake_vrpn_pose(b, 0, 0, 1, (double[]){0.5, 1.5, 0.5}, (double[]){0, 0, 0, 1});
    b->n += vrpn_write_message(b->data + b->n, sizeof(b->data) - b->n, 0, 0, 1.0,
                               (const uint8_t *)"short", 5);
    fake_vrpn_pose(b, 0, 0, 1, (double[]){0.6, 1.5, 0.5}, (double[]){0, 0, 0, 1});
    unsigned warnings = log_warn_count();
    log_set_level(LOG_ERROR);
    assert_true(fake_write_chunks(fd, b->data, b->n, 0));
    wait_for(head, 4, 0);
    log_set_level(LOG_INFO);
    assert_int_equal(log_warn_count(), warnings + 1);
    tracker_sample(head, &smp);
    assert_float_equal(smp.position[0], 0.6, 0);
    struct tracker_link_stats st;
    tracker_link_stats(head, &st);
    assert_int_equal(st.malformed, 1);
    assert_int_equal(st.connects, 1);
    assert_non_null(strstr(st.seen, "Head sensors 0 1"));

    /* The server goes away: the pose stays, frames go on; it comes back: a new connection. */
    log_set_level(LOG_ERROR);
    close(fd);
    assert_true(fake_wait(disconnected, head, TIMEOUT_S));
    tracker_sample(head, &smp);
    assert_float_equal(smp.position[0], 0.6, 0);
    fd = fake_vrpn_accept(lfd, TIMEOUT_S);
    assert_true(fd >= 0);
    assert_true(fake_wait(connected, head, TIMEOUT_S));
    b->n = 0;
    describe(b);
    fake_vrpn_pose(b, 0, 0, 1, (double[]){-0.3, 1.6, 0.2}, (double[]){0, 0, 0, 1});
    assert_true(fake_write_chunks(fd, b->data, b->n, 0));
    wait_for(head, 5, 0);
    tracker_sample(head, &smp);
    assert_float_equal(smp.position[0], -0.3, 0);
    tracker_link_stats(head, &st);
    assert_int_equal(st.connects, 2);

    /* Broken framing (a length shorter than a header): the client hangs up and comes back. */
    uint8_t bad[24] = {0, 0, 0, 5};
    assert_true(fake_write_chunks(fd, bad, sizeof(bad), 0));
    int again = fake_vrpn_accept(lfd, TIMEOUT_S);
    assert_true(again >= 0);
    log_set_level(LOG_INFO);
    close(fd);
    close(again);

    free(q);
    free(b);
    input_source_destroy(wand);
    tracker_close(head);
    assert_int_equal(tracker_links_open(), 0);
    close(lfd);
}

/* A VRPN server that is not up: opening is no error, and closing does not wait for it. */
static void test_vrpn_no_server(void **state)
{
    int port = 0;
    int lfd = fake_tcp_listen(&port);
    close(lfd); /* nobody listens there now */
    struct tracker_desc d = vrpn_desc(port, "Head", 0);
    log_set_level(LOG_ERROR);
    struct tracker *t = tracker_open(&d);
    assert_non_null(t);
    fake_sleep_ms(50);
    struct tracker_sample s;
    tracker_sample(t, &s);
    assert_false(s.seen);
    double start = time_now_ms();
    tracker_close(t);
    assert_true(time_now_ms() - start < 1000.0);
    log_set_level(LOG_INFO);
    assert_int_equal(tracker_links_open(), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_calibration),       cmocka_unit_test(test_dtrack_stream),
        cmocka_unit_test(test_dtrack_port_taken), cmocka_unit_test(test_dtrack_multicast),
        cmocka_unit_test(test_vrpn_server),       cmocka_unit_test(test_vrpn_no_server),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
