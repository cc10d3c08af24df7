/*
 * The VRPN byte stream (vrpn_Connection.C, VRPN's protocol notes): after a 24-byte cookie
 * ("vrpn: ver. 07.35  0", NUL-padded; only the major version must match), messages of a
 * 24-byte big-endian header — length (header plus the unpadded body), seconds,
 * microseconds, sender id, type id, four bytes of padding — and a body padded to 8 bytes.
 * Senders and types are numbers the peer chooses; description messages (type -1 for a sender,
 * -2 for a type, the id in the header's sender field, the body a 32-bit length counting the
 * NUL and then the name) say which names they stand for.  Bodies (vrpn_Tracker.C,
 * vrpn_Button.C, vrpn_Analog.C):
 *
 *   "vrpn_Tracker Pos_Quat"  sensor (i32), padding (i32), position (3 f64), quat x y z w (4 f64)
 *   "vrpn_Button Change"     button (i32), state (i32)
 *   "vrpn_Button States"     count (i32), count states (i32)
 *   "vrpn_Analog Channel"    count (f64), count channels (f64)
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "input/tracker.h"

#define MAGIC "vrpn: ver. 07.35"
#define MAJOR "vrpn: ver. 07."
#define LENGTH_MAX (1u << 30)
#define ANALOG_CHANNELS_MAX 128 /* vrpn_CHANNEL_MAX */

enum stage { STAGE_COOKIE, STAGE_HEADER, STAGE_BODY, STAGE_SKIP };
enum kind { KIND_NONE, KIND_POSE, KIND_BUTTON, KIND_BUTTONS, KIND_ANALOG };

static const struct {
    const char *name;
    enum kind kind;
} kinds[] = {
    {"vrpn_Tracker Pos_Quat", KIND_POSE},
    {"vrpn_Button Change", KIND_BUTTON},
    {"vrpn_Button States", KIND_BUTTONS},
    {"vrpn_Analog Channel", KIND_ANALOG},
};

/* ---- big-endian fields ------------------------------------------------------------------- */

static uint32_t get_u32(const uint8_t *b)
{
    return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | (uint32_t)b[3];
}

static int32_t get_i32(const uint8_t *b)
{
    uint32_t u = get_u32(b);
    int32_t v;
    memcpy(&v, &u, sizeof(v));
    return v;
}

static double get_f64(const uint8_t *b)
{
    uint64_t u = (uint64_t)get_u32(b) << 32 | get_u32(b + 4);
    double v;
    memcpy(&v, &u, sizeof(v));
    return v;
}

static void put_u32(uint8_t *b, uint32_t v)
{
    b[0] = (uint8_t)(v >> 24);
    b[1] = (uint8_t)(v >> 16);
    b[2] = (uint8_t)(v >> 8);
    b[3] = (uint8_t)v;
}

static void put_i32(uint8_t *b, int32_t v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof(u));
    put_u32(b, u);
}

static void put_f64(uint8_t *b, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof(u));
    put_u32(b, (uint32_t)(u >> 32));
    put_u32(b + 4, (uint32_t)u);
}

static size_t padded(size_t n)
{
    return (n + 7) & ~(size_t)7;
}

/* ---- the parser ------------------------------------------------------------------------- */

void vrpn_parser_init(struct vrpn_parser *p)
{
    memset(p, 0, sizeof(*p));
    p->stage = STAGE_COOKIE;
    p->need = VRPN_COOKIE_BYTES;
}

/* A name from the wire: up to the first NUL, printable ASCII kept, the rest as '?'. */
static void copy_name(char *out, size_t size, const uint8_t *in, size_t n)
{
    size_t k = 0;
    for (size_t i = 0; i < n && in[i] && k + 1 < size; i++)
        out[k++] = in[i] >= 0x20 && in[i] < 0x7f ? (char)in[i] : '?';
    out[k] = '\0';
}

static enum vrpn_event_type skipped(struct vrpn_event *ev, bool malformed, const char *why)
{
    ev->type = VRPN_SKIPPED;
    ev->malformed = malformed;
    snprintf(ev->why, sizeof(ev->why), "%s", why ? why : "");
    return ev->type;
}

static enum vrpn_event_type error(struct vrpn_parser *p, struct vrpn_event *ev, const char *why)
{
    p->stage = STAGE_SKIP;
    p->skip = UINT64_MAX; /* nothing more is read */
    ev->type = VRPN_ERROR;
    snprintf(ev->why, sizeof(ev->why), "%.127s", why);
    return ev->type;
}

static enum vrpn_event_type cookie(struct vrpn_parser *p, struct vrpn_event *ev)
{
    copy_name(ev->name, sizeof(ev->name), p->buf, 16);
    if (memcmp(p->buf, MAJOR, strlen(MAJOR)) != 0) {
        char why[160];
        snprintf(why, sizeof(why),
                 "the peer's cookie is \"%.24s\": expected a VRPN 07 "
                 "server (\"" MAJOR "xx\")",
                 ev->name);
        return error(p, ev, why);
    }
    p->stage = STAGE_HEADER;
    p->need = VRPN_HEADER_BYTES;
    p->have = 0;
    ev->type = VRPN_COOKIE;
    return ev->type;
}

static enum kind kind_of(const char *name)
{
    for (size_t i = 0; i < sizeof(kinds) / sizeof(kinds[0]); i++) {
        if (strcmp(name, kinds[i].name) == 0)
            return kinds[i].kind;
    }
    return KIND_NONE;
}

static enum vrpn_event_type description(struct vrpn_parser *p, struct vrpn_event *ev,
                                        const uint8_t *b, size_t n)
{
    if (n < 4)
        return skipped(ev, true, "a description shorter than its length field");
    int32_t len = get_i32(b);
    if (len < 1 || (size_t)len > n - 4)
        return skipped(ev, true, "a description whose name length disagrees with its body");
    ev->id = p->sender;
    copy_name(ev->name, sizeof(ev->name), b + 4, (size_t)len);
    bool sender = p->type == VRPN_SENDER_DESCRIPTION;
    if (ev->id >= 0 && ev->id < VRPN_IDS_MAX) {
        if (sender)
            snprintf(p->senders[ev->id], sizeof(p->senders[ev->id]), "%s", ev->name);
        else
            p->kinds[ev->id] = kind_of(ev->name);
    }
    ev->type = sender ? VRPN_SENDER : VRPN_TYPE;
    return ev->type;
}

static bool finite_all(const double *v, int n)
{
    for (int i = 0; i < n; i++) {
        if (!isfinite(v[i]))
            return false;
    }
    return true;
}

static enum vrpn_event_type body(struct vrpn_parser *p, struct vrpn_event *ev)
{
    const uint8_t *b = p->buf;
    size_t n = (size_t)p->length - VRPN_HEADER_BYTES;
    if (p->type == VRPN_SENDER_DESCRIPTION || p->type == VRPN_TYPE_DESCRIPTION)
        return description(p, ev, b, n);
    switch ((enum kind)p->kinds[p->type]) {
    case KIND_POSE:
        if (n < 64)
            return skipped(ev, true, "a Pos_Quat body shorter than 64 bytes");
        ev->sensor = get_i32(b);
        for (int i = 0; i < 3; i++)
            ev->position[i] = get_f64(b + 8 + 8 * i);
        for (int i = 0; i < 4; i++)
            ev->quat[i] = get_f64(b + 32 + 8 * i);
        if (!finite_all(ev->position, 3) || !finite_all(ev->quat, 4))
            return skipped(ev, true, "a Pos_Quat with a number that is not finite");
        if (ev->sensor < 0)
            return skipped(ev, true, "a Pos_Quat of a negative sensor");
        double len = sqrt(ev->quat[0] * ev->quat[0] + ev->quat[1] * ev->quat[1] +
                          ev->quat[2] * ev->quat[2] + ev->quat[3] * ev->quat[3]);
        if (fabs(len - 1.0) > 1e-3)
            return skipped(ev, true, "a Pos_Quat whose quaternion is not a unit one");
        if (fabs(ev->position[0]) > 1e6 || fabs(ev->position[1]) > 1e6 ||
            fabs(ev->position[2]) > 1e6)
            return skipped(ev, true, "a Pos_Quat position beyond 1000 km");
        ev->type = VRPN_POSE;
        return ev->type;
    case KIND_BUTTON:
        if (n < 8)
            return skipped(ev, true, "a Button Change body shorter than 8 bytes");
        ev->button = get_i32(b);
        ev->state = get_i32(b + 4);
        if (ev->button < 0)
            return skipped(ev, true, "a Button Change of a negative button");
        ev->type = VRPN_BUTTON;
        return ev->type;
    case KIND_BUTTONS: {
        if (n < 4)
            return skipped(ev, true, "a Button States body shorter than its count");
        int32_t count = get_i32(b);
        if (count < 0 || (size_t)count > (n - 4) / 4)
            return skipped(ev, true, "a Button States count that disagrees with its body");
        ev->count = count;
        for (int i = 0; i < count && i < TRACKER_BUTTONS_MAX; i++)
            ev->states[i] = get_i32(b + 4 + 4 * (size_t)i);
        ev->type = VRPN_BUTTONS;
        return ev->type;
    }
    case KIND_ANALOG: {
        if (n < 8)
            return skipped(ev, true, "an Analog Channel body shorter than its count");
        double count = get_f64(b);
        if (!(count >= 0.0 && count <= ANALOG_CHANNELS_MAX) || count != floor(count) ||
            (size_t)count > (n - 8) / 8)
            return skipped(ev, true, "an Analog Channel count that disagrees with its body");
        ev->count = (int)count;
        for (int i = 0; i < ev->count; i++) {
            double v = get_f64(b + 8 + 8 * (size_t)i);
            if (!isfinite(v))
                return skipped(ev, true, "an Analog Channel value that is not finite");
            if (i < TRACKER_AXES_MAX)
                ev->channels[i] = v;
        }
        ev->type = VRPN_ANALOG;
        return ev->type;
    }
    case KIND_NONE:
        break;
    }
    return skipped(ev, false, NULL);
}

/* After a header: where its body goes.  Returns an event when there is one at once. */
static enum vrpn_event_type header(struct vrpn_parser *p, struct vrpn_event *ev)
{
    const uint8_t *b = p->buf;
    uint32_t length = get_u32(b);
    p->time_s = (double)get_u32(b + 4) + 1e-6 * (double)get_u32(b + 8);
    p->sender = get_i32(b + 12);
    p->type = get_i32(b + 16);
    ev->sender_id = p->sender;
    ev->type_id = p->type;
    ev->time_s = p->time_s;
    ev->sender = p->sender >= 0 && p->sender < VRPN_IDS_MAX ? p->senders[p->sender] : "";
    if (length < VRPN_HEADER_BYTES) {
        char why[96];
        snprintf(why, sizeof(why), "a message length of %u bytes, shorter than its header", length);
        return error(p, ev, why);
    }
    if (length > LENGTH_MAX) {
        char why[96];
        snprintf(why, sizeof(why), "a message length of %u bytes (more than 1 GiB)", length);
        return error(p, ev, why);
    }
    p->length = (int32_t)length;
    size_t body_bytes = padded(length - VRPN_HEADER_BYTES);
    bool decoded = p->type == VRPN_SENDER_DESCRIPTION || p->type == VRPN_TYPE_DESCRIPTION ||
                   (p->type >= 0 && p->type < VRPN_IDS_MAX && p->kinds[p->type] != KIND_NONE);
    p->have = 0;
    if (decoded && body_bytes <= VRPN_BODY_MAX) {
        p->stage = STAGE_BODY;
        p->need = body_bytes;
        return VRPN_NONE;
    }
    p->malformed = decoded;
    p->skip_why[0] = '\0';
    if (decoded)
        snprintf(p->skip_why, sizeof(p->skip_why),
                 "a body of %zu bytes, more than anvil reads of its type", body_bytes);
    p->stage = STAGE_SKIP;
    p->skip = body_bytes;
    return VRPN_NONE;
}

enum vrpn_event_type vrpn_parse(struct vrpn_parser *p, const uint8_t *data, size_t len, size_t *pos,
                                struct vrpn_event *ev)
{
    memset(ev, 0, sizeof(*ev));
    ev->sender = "";
    for (;;) {
        if (p->stage == STAGE_SKIP) {
            if (p->skip == UINT64_MAX) { /* after an error */
                *pos = len;
                return VRPN_NONE;
            }
            size_t take = len - *pos < p->skip ? len - *pos : (size_t)p->skip;
            *pos += take;
            p->skip -= take;
            if (p->skip > 0)
                return VRPN_NONE;
            p->stage = STAGE_HEADER;
            p->need = VRPN_HEADER_BYTES;
            p->have = 0;
            ev->sender_id = p->sender;
            ev->type_id = p->type;
            ev->time_s = p->time_s;
            ev->sender = p->sender >= 0 && p->sender < VRPN_IDS_MAX ? p->senders[p->sender] : "";
            return skipped(ev, p->malformed, p->skip_why);
        }
        size_t take = p->need - p->have;
        if (take > len - *pos)
            take = len - *pos;
        memcpy(p->buf + p->have, data + *pos, take);
        p->have += take;
        *pos += take;
        if (p->have < p->need)
            return VRPN_NONE;
        enum vrpn_event_type t = VRPN_NONE;
        switch (p->stage) {
        case STAGE_COOKIE:
            return cookie(p, ev);
        case STAGE_HEADER:
            t = header(p, ev);
            if (t != VRPN_NONE)
                return t;
            break; /* on to the body (or the skip), which may be empty */
        case STAGE_BODY:
            ev->sender_id = p->sender;
            ev->type_id = p->type;
            ev->time_s = p->time_s;
            ev->sender = p->sender >= 0 && p->sender < VRPN_IDS_MAX ? p->senders[p->sender] : "";
            t = body(p, ev);
            p->stage = STAGE_HEADER;
            p->need = VRPN_HEADER_BYTES;
            p->have = 0;
            return t;
        }
    }
}

/* ---- writers ------------------------------------------------------------------------------ */

size_t vrpn_write_cookie(uint8_t *out, size_t cap)
{
    if (cap < VRPN_COOKIE_BYTES)
        return 0;
    memset(out, 0, VRPN_COOKIE_BYTES);
    memcpy(out, MAGIC "  0", strlen(MAGIC "  0"));
    return VRPN_COOKIE_BYTES;
}

size_t vrpn_write_message(uint8_t *out, size_t cap, int32_t sender, int32_t type, double t,
                          const uint8_t *body, size_t len)
{
    size_t total = VRPN_HEADER_BYTES + padded(len);
    if (total > cap || len > LENGTH_MAX || !(t >= 0.0 && t < 4294967296.0))
        return 0;
    memset(out, 0, total);
    double sec = floor(t);
    double usec = floor((t - sec) * 1e6 + 0.5);
    if (usec >= 1e6) {
        sec += 1.0;
        usec -= 1e6;
    }
    put_u32(out, (uint32_t)(VRPN_HEADER_BYTES + len));
    put_u32(out + 4, (uint32_t)sec);
    put_u32(out + 8, (uint32_t)usec);
    put_i32(out + 12, sender);
    put_i32(out + 16, type);
    if (len)
        memcpy(out + VRPN_HEADER_BYTES, body, len);
    return total;
}

size_t vrpn_write_description(uint8_t *out, size_t cap, int32_t kind, int32_t id, const char *name,
                              double t)
{
    uint8_t b[4 + 256];
    size_t n = strlen(name) + 1;
    if (n > 256)
        return 0;
    put_u32(b, (uint32_t)n);
    memcpy(b + 4, name, n);
    return vrpn_write_message(out, cap, id, kind, t, b, 4 + n);
}

size_t vrpn_write_pose(uint8_t *out, size_t cap, int32_t sender, int32_t type, double t,
                       int32_t sensor, const double position[3], const double quat[4])
{
    uint8_t b[64] = {0};
    put_i32(b, sensor);
    for (int i = 0; i < 3; i++)
        put_f64(b + 8 + 8 * i, position[i]);
    for (int i = 0; i < 4; i++)
        put_f64(b + 32 + 8 * i, quat[i]);
    return vrpn_write_message(out, cap, sender, type, t, b, sizeof(b));
}

size_t vrpn_write_button(uint8_t *out, size_t cap, int32_t sender, int32_t type, double t,
                         int32_t button, int32_t state)
{
    uint8_t b[8];
    put_i32(b, button);
    put_i32(b + 4, state);
    return vrpn_write_message(out, cap, sender, type, t, b, sizeof(b));
}

size_t vrpn_write_analog(uint8_t *out, size_t cap, int32_t sender, int32_t type, double t,
                         const double *channels, int count)
{
    uint8_t b[8 * (1 + ANALOG_CHANNELS_MAX)];
    if (count < 0 || count > ANALOG_CHANNELS_MAX)
        return 0;
    put_f64(b, (double)count);
    for (int i = 0; i < count; i++)
        put_f64(b + 8 + 8 * i, channels[i]);
    return vrpn_write_message(out, cap, sender, type, t, b, 8 + 8 * (size_t)count);
}
