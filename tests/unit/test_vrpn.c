/* The VRPN parser and writers: golden messages written out byte by byte from the protocol
 * (cookie, descriptions, Pos_Quat, Button Change, Analog Channel), a stream read whole, a byte
 * at a time and in odd chunks with the same result, unknown types skipped by their length,
 * malformed bodies skipped and counted, broken framing refused. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "input/tracker.h"

/* Byte-exact expectations, written from the wire format (not from the writer). */
static const uint8_t cookie_bytes[24] = {'v', 'r', 'p', 'n', ':', ' ', 'v', 'e', 'r', '.', ' ', '0',
                                         '7', '.', '3', '5', ' ', ' ', '0', 0,   0,   0,   0,   0};

/* Sender 0 is "Tracker0", at t = 12.5 s: length 24 + 4 + 9 = 37, padded body 16. */
static const uint8_t sender_bytes[40] = {
    0x00, 0x00, 0x00, 0x25, 0x00, 0x00, 0x00, 0x0c, 0x00, 0x07, 0xa1, 0x20, /* 37, 12 s, 0.5 s */
    0x00, 0x00, 0x00, 0x00, 0xff, 0xff, 0xff, 0xff, 0x00, 0x00, 0x00, 0x00, /* id 0, type -1 */
    0x00, 0x00, 0x00, 0x09, 'T',  'r',  'a',  'c',  'k',  'e',  'r',  '0',
    0x00, 0x00, 0x00, 0x00,
};

/* Type 3 is "vrpn_Tracker Pos_Quat" (21 characters and the NUL: 24 + 4 + 22 = 50). */
static const char pos_quat_name[] = "vrpn_Tracker Pos_Quat";

/* Sender 0, type 3, t = 1 s: sensor 2, position (1, -2, 0.5), quat (0, 0, 0, 1). */
static const uint8_t pose_bytes[88] = {
    0x00, 0x00, 0x00, 0x58, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, /* 88, 1 s, 0 us */
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x00, /* sender 0, type 3 */
    0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00,                         /* sensor 2, pad */
    0x3f, 0xf0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                         /* 1.0 */
    0xc0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                         /* -2.0 */
    0x3f, 0xe0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                         /* 0.5 */
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                         /* x 0 */
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                         /* y 0 */
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                         /* z 0 */
    0x3f, 0xf0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                         /* w 1 */
};

/* Sender 1, type 4, t = 2.25 s: button 3 pressed. */
static const uint8_t button_bytes[32] = {
    0x00, 0x00, 0x00, 0x20, 0x00, 0x00, 0x00, 0x02, 0x00, 0x03, 0xd0, 0x90, /* 32, 2 s, 250000 */
    0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x04, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x01,
};

/* Sender 1, type 5, t = 0: two channels, 0.25 and -1. */
static const uint8_t analog_bytes[48] = {
    0x00, 0x00, 0x00, 0x30, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x05, 0x00, 0x00, 0x00, 0x00,
    0x40, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, /* count 2.0 */
    0x3f, 0xd0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, /* 0.25 */
    0xbf, 0xf0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, /* -1.0 */
};

static void test_golden_writes(void **state)
{
    uint8_t out[256];
    assert_int_equal(vrpn_write_cookie(out, sizeof(out)), 24);
    assert_memory_equal(out, cookie_bytes, 24);
    assert_int_equal(vrpn_write_description(out, sizeof(out), VRPN_SENDER_DESCRIPTION, 0,
                                            "Tracker0", 12.5),
                     sizeof(sender_bytes));
    assert_memory_equal(out, sender_bytes, sizeof(sender_bytes));
    assert_int_equal(vrpn_write_pose(out, sizeof(out), 0, 3, 1.0, 2, (double[]){1.0, -2.0, 0.5},
                                     (double[]){0, 0, 0, 1}),
                     sizeof(pose_bytes));
    assert_memory_equal(out, pose_bytes, sizeof(pose_bytes));
    assert_int_equal(vrpn_write_button(out, sizeof(out), 1, 4, 2.25, 3, 1), sizeof(button_bytes));
    assert_memory_equal(out, button_bytes, sizeof(button_bytes));
    assert_int_equal(vrpn_write_analog(out, sizeof(out), 1, 5, 0.0, (double[]){0.25, -1.0}, 2),
                     sizeof(analog_bytes));
    assert_memory_equal(out, analog_bytes, sizeof(analog_bytes));
    assert_int_equal(vrpn_write_pose(out, 87, 0, 3, 1.0, 2, (double[]){0, 0, 0},
                                     (double[]){0, 0, 0, 1}),
                     0); /* does not fit */
}

/* A whole session's bytes: cookie, descriptions, messages, one unknown type among them. */
static size_t stream(uint8_t *out, size_t cap)
{
    size_t n = 0;
    memcpy(out, cookie_bytes, 24);
    n += 24;
    memcpy(out + n, sender_bytes, sizeof(sender_bytes));
    n += sizeof(sender_bytes);
    n += vrpn_write_description(out + n, cap - n, VRPN_SENDER_DESCRIPTION, 1, "Wand", 0);
    n += vrpn_write_description(out + n, cap - n, VRPN_TYPE_DESCRIPTION, 3, pos_quat_name, 0);
    n += vrpn_write_description(out + n, cap - n, VRPN_TYPE_DESCRIPTION, 4, "vrpn_Button Change",
                                0);
    n += vrpn_write_description(out + n, cap - n, VRPN_TYPE_DESCRIPTION, 5,
                                "vrpn_Analog Channel", 0);
    n += vrpn_write_description(out + n, cap - n, VRPN_TYPE_DESCRIPTION, 6,
                                "vrpn_Tracker Velocity", 0);
    /* An unknown type with a body of 10000 bytes: more than any anvil decodes. */
    static uint8_t big[10000];
    memset(big, 0xab, sizeof(big));
    n += vrpn_write_message(out + n, cap - n, 0, 6, 0.0, big, sizeof(big));
    memcpy(out + n, pose_bytes, sizeof(pose_bytes));
    n += sizeof(pose_bytes);
    memcpy(out + n, button_bytes, sizeof(button_bytes));
    n += sizeof(button_bytes);
    memcpy(out + n, analog_bytes, sizeof(analog_bytes));
    n += sizeof(analog_bytes);
    return n;
}

struct summary {
    int events[VRPN_ERROR + 1];
    char version[64];
    double pose[7];
    int sensor;
    char pose_sender[TRACKER_NAME_MAX], button_sender[TRACKER_NAME_MAX];
    int button, state;
    double channels[2];
    int channel_count;
};

/* Parses DATA fed in chunks of CHUNK bytes (0: all at once). */
static void parse_chunks(const uint8_t *data, size_t n, size_t chunk, struct summary *s)
{
    struct vrpn_parser *p = malloc(sizeof(*p));
    assert_non_null(p);
    vrpn_parser_init(p);
    memset(s, 0, sizeof(*s));
    struct vrpn_event ev;
    for (size_t at = 0; at < n;) {
        size_t len = chunk ? (n - at < chunk ? n - at : chunk) : n;
        size_t pos = 0;
        enum vrpn_event_type t;
        while ((t = vrpn_parse(p, data + at, len, &pos, &ev)) != VRPN_NONE) {
            assert_int_equal(t, ev.type);
            s->events[t]++;
            if (t == VRPN_COOKIE)
                snprintf(s->version, sizeof(s->version), "%s", ev.name);
            if (t == VRPN_POSE) {
                memcpy(s->pose, ev.position, sizeof(ev.position));
                memcpy(s->pose + 3, ev.quat, sizeof(ev.quat));
                s->sensor = ev.sensor;
                snprintf(s->pose_sender, sizeof(s->pose_sender), "%s", ev.sender);
            }
            if (t == VRPN_BUTTON) {
                s->button = ev.button;
                s->state = ev.state;
                snprintf(s->button_sender, sizeof(s->button_sender), "%s", ev.sender);
            }
            if (t == VRPN_ANALOG) {
                s->channel_count = ev.count;
                memcpy(s->channels, ev.channels, sizeof(s->channels));
            }
        }
        assert_int_equal(pos, len);
        at += len;
    }
    free(p);
}

static void test_stream_any_split(void **state)
{
    static uint8_t data[20000];
    size_t n = stream(data, sizeof(data));
    struct summary whole, part;
    parse_chunks(data, n, 0, &whole);
    assert_int_equal(whole.events[VRPN_COOKIE], 1);
    assert_string_equal(whole.version, "vrpn: ver. 07.35");
    assert_int_equal(whole.events[VRPN_SENDER], 2);
    assert_int_equal(whole.events[VRPN_TYPE], 4);
    assert_int_equal(whole.events[VRPN_SKIPPED], 1); /* the velocity, by its length */
    assert_int_equal(whole.events[VRPN_POSE], 1);
    assert_int_equal(whole.events[VRPN_ERROR], 0);
    assert_int_equal(whole.sensor, 2);
    assert_string_equal(whole.pose_sender, "Tracker0");
    const double want[7] = {1.0, -2.0, 0.5, 0, 0, 0, 1};
    assert_memory_equal(whole.pose, want, sizeof(want));
    assert_int_equal(whole.events[VRPN_BUTTON], 1);
    assert_string_equal(whole.button_sender, "Wand");
    assert_int_equal(whole.button, 3);
    assert_int_equal(whole.state, 1);
    assert_int_equal(whole.channel_count, 2);
    assert_float_equal(whole.channels[0], 0.25, 0);
    assert_float_equal(whole.channels[1], -1.0, 0);
    /* A byte at a time, and odd chunks: the same events. */
    const size_t chunks[] = {1, 3, 7, 23, 24, 25, 1000};
    for (size_t c = 0; c < sizeof(chunks) / sizeof(chunks[0]); c++) {
        parse_chunks(data, n, chunks[c], &part);
        assert_memory_equal(part.events, whole.events, sizeof(whole.events));
        assert_memory_equal(part.pose, whole.pose, sizeof(whole.pose));
        assert_int_equal(part.button, whole.button);
        assert_memory_equal(part.channels, whole.channels, sizeof(whole.channels));
    }
}

static void test_malformed_and_broken(void **state)
{
    struct vrpn_parser *p = malloc(sizeof(*p));
    assert_non_null(p);
    uint8_t data[512];
    size_t n = 0, pos = 0;
    struct vrpn_event ev;
    /* A short Pos_Quat body is skipped as malformed; the next message still reads. */
    vrpn_parser_init(p);
    memcpy(data, cookie_bytes, 24);
    n = 24;
    n += vrpn_write_description(data + n, sizeof(data) - n, VRPN_TYPE_DESCRIPTION, 3,
                                pos_quat_name, 0);
    n += vrpn_write_message(data + n, sizeof(data) - n, 0, 3, 0, (const uint8_t *)"12345678", 8);
    n += vrpn_write_pose(data + n, sizeof(data) - n, 0, 3, 0, 1, (double[]){0, 0, 0},
                         (double[]){0, 0, 2, 0}); /* not a unit quaternion */
    memcpy(data + n, pose_bytes, sizeof(pose_bytes));
    n += sizeof(pose_bytes);
    assert_int_equal(vrpn_parse(p, data, n, &pos, &ev), VRPN_COOKIE);
    assert_int_equal(vrpn_parse(p, data, n, &pos, &ev), VRPN_TYPE);
    assert_int_equal(vrpn_parse(p, data, n, &pos, &ev), VRPN_SKIPPED);
    assert_true(ev.malformed);
    assert_non_null(strstr(ev.why, "shorter"));
    assert_int_equal(vrpn_parse(p, data, n, &pos, &ev), VRPN_SKIPPED);
    assert_true(ev.malformed);
    assert_non_null(strstr(ev.why, "unit"));
    assert_int_equal(vrpn_parse(p, data, n, &pos, &ev), VRPN_POSE);
    assert_int_equal(ev.sensor, 2);
    assert_string_equal(ev.sender, ""); /* never described */
    assert_int_equal(vrpn_parse(p, data, n, &pos, &ev), VRPN_NONE);

    /* Another major version: an error, and nothing more is read. */
    vrpn_parser_init(p);
    memcpy(data, "vrpn: ver. 06.01  0\0\0\0\0\0", 24);
    memcpy(data + 24, pose_bytes, sizeof(pose_bytes));
    pos = 0;
    assert_int_equal(vrpn_parse(p, data, 24 + sizeof(pose_bytes), &pos, &ev), VRPN_ERROR);
    assert_non_null(strstr(ev.why, "06.01"));
    assert_int_equal(vrpn_parse(p, data, 24 + sizeof(pose_bytes), &pos, &ev), VRPN_NONE);
    /* A length shorter than the header: the framing is lost. */
    vrpn_parser_init(p);
    memcpy(data, cookie_bytes, 24);
    memcpy(data + 24, pose_bytes, sizeof(pose_bytes));
    data[24 + 3] = 0x10;
    pos = 0;
    assert_int_equal(vrpn_parse(p, data, 24 + sizeof(pose_bytes), &pos, &ev), VRPN_COOKIE);
    assert_int_equal(vrpn_parse(p, data, 24 + sizeof(pose_bytes), &pos, &ev), VRPN_ERROR);
    assert_non_null(strstr(ev.why, "shorter than its header"));
    free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_golden_writes),
        cmocka_unit_test(test_stream_any_split),
        cmocka_unit_test(test_malformed_and_broken),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
