/*
 * input/tracker: six-degree-of-freedom trackers on the network, the head and the wand of a
 * CAVE.  Two protocols, each with a parser that is a pure function over bytes (unit tests and
 * fuzzers call them directly) and a client that runs on its own thread:
 *
 *   ART DTrack2/DTrack3: one UDP datagram of ASCII lines per frame ("fr", "ts"/"ts2",
 *     "6dcal", "6d" bodies, "6df2" Flysticks; other record types are skipped), unicast or to a
 *     multicast group (ART, "DTrack2 Technical Appendix", output format);
 *   VRPN: a TCP stream to a VRPN server (Vicon Tracker, OptiTrack Motive and most others
 *     serve it): the 24-byte version cookie, then big-endian messages of a 24-byte header and
 *     a body padded to 8 bytes; sender and type names arrive as description messages
 *     (VRPN's vrpn_Connection.C and its protocol notes).
 *
 * A link (one UDP port, or one VRPN server) is shared by everything that reads from it — the
 * head and the wand usually come from one stream — and its thread keeps the latest state of
 * every body it has seen; readers copy that state without waiting (a frame never waits on the
 * network).  A tracker is one reader: a body or sensor on a link, calibrated from tracker
 * coordinates into the room (tracker space of display/, metres, y up), with its buttons and
 * analog channels.
 *
 * Must not know: GL, windows, the menu, the session, config files (callers fill the descs).
 */
#ifndef ANVIL_INPUT_TRACKER_H
#define ANVIL_INPUT_TRACKER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "input/input.h"

#define TRACKER_BUTTONS_MAX 64 /* buttons of one device that anvil reads */
#define TRACKER_AXES_MAX 16    /* analog channels (joystick values) of one device */
#define TRACKER_NAME_MAX 64    /* a VRPN sender name, with its NUL */
#define TRACKER_HOST_MAX 128

/* ---- DTrack: parsing one datagram ------------------------------------------------------ */

#define DTRACK_ITEMS_MAX 32 /* bodies (and Flysticks) kept from one datagram */
#define DTRACK_DATAGRAM_MAX 65536

/* A body ("6d") or a Flystick ("6df2") as DTrack reports it. */
struct dtrack_item {
    int id;             /* DTrack's id: the number in its user interface minus one */
    double quality;     /* [0, 1]; below 0 (DTrack sends -1): not tracked, pose meaningless */
    double position[3]; /* mm, in DTrack's room calibration */
    double rotation[9]; /* body -> room, column-major: b0 b1 b2 is the first column */
    int button_count;   /* 6df2: buttons, bit n of the n / 32-th button word */
    bool buttons[TRACKER_BUTTONS_MAX];
    int axis_count; /* 6df2: joystick values, each in [-1, 1] */
    double axes[TRACKER_AXES_MAX];
};

struct dtrack_frame {
    bool have_counter;
    uint32_t counter; /* fr: the frame counter */
    bool have_time;
    double time_s;       /* ts: seconds since midnight (UTC); ts2: since 1970 */
    int calibrated;      /* 6dcal: calibrated bodies; -1 when the line is absent */
    bool have_bodies;    /* a 6d line came (even with no body in it) */
    bool have_flysticks; /* a 6df2 line came */
    int body_count, flystick_count;
    struct dtrack_item bodies[DTRACK_ITEMS_MAX];
    struct dtrack_item flysticks[DTRACK_ITEMS_MAX];
    int skipped_lines; /* record types anvil does not use (3d, 6di, gl, 6dmt2, ...) */
};

/* Parses one DTrack datagram of LEN bytes (no NUL needed; at most DTRACK_DATAGRAM_MAX).
 * Lines end in "\n" or "\r\n"; unknown record types are skipped.  Returns false when a line
 * anvil reads is malformed — truncated, a count that disagrees with the blocks that follow, a
 * number that is not one or not finite, a rotation that is not one, more items than
 * DTRACK_ITEMS_MAX — with WHY (WHY_SIZE bytes, may be 0) saying which line and what was
 * expected; OUT is then not to be used.  Pure: no I/O, no allocation, no logging. */
bool dtrack_parse(const char *data, size_t len, struct dtrack_frame *out, char *why,
                  size_t why_size);

/* ---- VRPN: parsing and writing the byte stream -------------------------------------------- */

#define VRPN_COOKIE_BYTES 24 /* "vrpn: ver. 07.35  0" padded with NULs */
#define VRPN_HEADER_BYTES 24 /* length, seconds, microseconds, sender, type, padding */
#define VRPN_BODY_MAX 4096   /* the largest body of a type anvil decodes (bigger: skipped) */
#define VRPN_IDS_MAX 256     /* sender and type ids anvil keeps names for */
#define VRPN_DEFAULT_PORT 3883

/* System message types (negative type ids). */
enum {
    VRPN_SENDER_DESCRIPTION = -1,
    VRPN_TYPE_DESCRIPTION = -2,
    VRPN_UDP_DESCRIPTION = -3,
    VRPN_LOG_DESCRIPTION = -4,
    VRPN_DISCONNECT_MESSAGE = -5,
};

enum vrpn_event_type {
    VRPN_NONE,    /* every byte given is consumed: more are needed */
    VRPN_COOKIE,  /* the peer's cookie: version */
    VRPN_SENDER,  /* a sender description: id, name */
    VRPN_TYPE,    /* a type description: id, name */
    VRPN_POSE,    /* "vrpn_Tracker Pos_Quat": sensor, position, quat */
    VRPN_BUTTON,  /* "vrpn_Button Change": button, state */
    VRPN_BUTTONS, /* "vrpn_Button States": count buttons in states */
    VRPN_ANALOG,  /* "vrpn_Analog Channel": count channels (the first TRACKER_AXES_MAX kept) */
    VRPN_SKIPPED, /* a message of another type, skipped by its length (malformed: one of
                     anvil's types whose body is wrong, WHY says how) */
    VRPN_ERROR,   /* the stream cannot be read on (WHY): the connection must be closed */
};

struct vrpn_event {
    enum vrpn_event_type type;
    int32_t sender_id, type_id;  /* the message's header */
    const char *sender;          /* the sender's name, "" until described; valid until the
                                    parser is fed again */
    double time_s;               /* the header's time stamp */
    char name[TRACKER_NAME_MAX]; /* VRPN_SENDER, VRPN_TYPE: the name; VRPN_COOKIE: the
                                    version text ("vrpn: ver. 07.35") */
    int32_t id;                  /* VRPN_SENDER, VRPN_TYPE: the id described */
    int32_t sensor;
    double position[3];
    double quat[4]; /* x, y, z, w */
    int32_t button, state;
    int count; /* VRPN_BUTTONS, VRPN_ANALOG: in the message */
    int32_t states[TRACKER_BUTTONS_MAX];
    double channels[TRACKER_AXES_MAX];
    bool malformed; /* VRPN_SKIPPED: one of anvil's types with a bad body */
    char why[128];  /* VRPN_SKIPPED (malformed), VRPN_ERROR */
};

/* The reading side of one VRPN connection: it buffers a message split across reads and keeps
 * the names the peer described.  Plain data: zero it with vrpn_parser_init, copy it freely. */
struct vrpn_parser {
    int stage;      /* cookie, header, body, skip */
    bool malformed; /* the body being skipped belongs to one of anvil's types */
    uint8_t buf[VRPN_HEADER_BYTES + VRPN_BODY_MAX];
    size_t have;   /* bytes of the current cookie, header or body in BUF */
    size_t need;   /* bytes the current stage needs */
    uint64_t skip; /* bytes left to skip */
    int32_t length, sender, type;
    double time_s;
    char senders[VRPN_IDS_MAX][TRACKER_NAME_MAX];
    int kinds[VRPN_IDS_MAX]; /* type id -> what anvil decodes (0: nothing) */
    char skip_why[128];
};

/* Starts a connection's reading: the peer's cookie first. */
void vrpn_parser_init(struct vrpn_parser *p);

/* Reads the next event from DATA[*POS .. LEN), advancing *POS past the bytes it took, and
 * returns its type (also in EV->type); VRPN_NONE once *POS reaches LEN with no event complete
 * (the partial one is kept for the next call).  Messages may be split across calls anyhow and
 * several may come in one; every header's length is checked, bodies of unknown types are
 * skipped by it, and a known type with a wrong body is skipped as malformed.  VRPN_ERROR (a
 * cookie of another major version than 07, a length shorter than the header or beyond 1 GiB)
 * leaves the parser useless until vrpn_parser_init.  Pure: no I/O, no allocation, no
 * logging. */
enum vrpn_event_type vrpn_parse(struct vrpn_parser *p, const uint8_t *data, size_t len, size_t *pos,
                                struct vrpn_event *ev);

/* Writers, for the client's own cookie and for test servers.  Each returns the bytes written
 * to OUT (room for CAP), or 0 when they do not fit. */
size_t vrpn_write_cookie(uint8_t *out, size_t cap);
/* One message: header (time T seconds) and BODY of LEN bytes, padded to 8. */
size_t vrpn_write_message(uint8_t *out, size_t cap, int32_t sender, int32_t type, double t,
                          const uint8_t *body, size_t len);
/* A sender (KIND VRPN_SENDER_DESCRIPTION) or type (VRPN_TYPE_DESCRIPTION) description. */
size_t vrpn_write_description(uint8_t *out, size_t cap, int32_t kind, int32_t id, const char *name,
                              double t);
size_t vrpn_write_pose(uint8_t *out, size_t cap, int32_t sender, int32_t type, double t,
                       int32_t sensor, const double position[3], const double quat[4]);
size_t vrpn_write_button(uint8_t *out, size_t cap, int32_t sender, int32_t type, double t,
                         int32_t button, int32_t state);
size_t vrpn_write_analog(uint8_t *out, size_t cap, int32_t sender, int32_t type, double t,
                         const double *channels, int count);

/* ---- calibration: tracker coordinates -> the room ------------------------------------------ */

/* p_room = offset + R (A (scale p)) and, for the orientation, R A M A^T with M the body's
 * rotation in tracker axes: A maps tracker axes to room axes (room axis i is tracker axis
 * |axes[i]| - 1, negated when axes[i] < 0; a rotation, never a mirror), R turns them by
 * heading, pitch and roll (as display_pose_from_euler).  So a body whose axes the tracker
 * calibrated parallel to its own (DTrack: "due to room") looks along room -z, y up, when it
 * looks along the tracker's axis that A maps to -z. */
struct tracker_calibration {
    double scale;           /* room metres per tracker unit (DTrack's mm: 0.001) */
    int axes[3];            /* +-1, +-2, +-3: tracker x, y, z */
    double offset[3];       /* room metres */
    double rotation_deg[3]; /* heading, pitch, roll */
};

/* The identity: metres, x y z, no offset or rotation. */
void tracker_calibration_identity(struct tracker_calibration *c);
/* Tracker position POS and rotation QUAT (x, y, z, w) -> the room's. */
void tracker_calibrate(const struct tracker_calibration *c, const double pos[3],
                       const double quat[4], double room_pos[3], double room_quat[4]);
/* A column-major rotation matrix -> a unit quaternion (x, y, z, w). */
void tracker_quat_from_matrix(const double m[9], double q[4]);

/* ---- trackers: one body on a link ------------------------------------------------------------ */

enum tracker_protocol { TRACKER_DTRACK, TRACKER_VRPN };

struct tracker_address {
    enum tracker_protocol protocol;
    char host[TRACKER_HOST_MAX];   /* DTrack: a multicast group to join, a local address to
                                      listen on, or "" (every address); VRPN: the server */
    int port;                      /* DTrack: the UDP port (0: any free one, for tests);
                                      VRPN: the server's TCP port */
    char device[TRACKER_NAME_MAX]; /* VRPN: the sender ("Tracker0" of "Tracker0@host") */
};

struct tracker_desc {
    const char *what;                /* "head", "wand": the name in messages */
    struct tracker_address address;  /* where the pose comes from */
    bool flystick;                   /* DTrack: a Flystick (6df2) rather than a body (6d) */
    int sensor;                      /* DTrack's body or Flystick id; VRPN's sensor */
    struct tracker_address controls; /* VRPN: the device of the buttons and analog channels
                                        (device "": the pose's) */
    struct tracker_calibration calibration;
};

/* What a tracker holds now. */
struct tracker_sample {
    bool seen;          /* a pose has arrived since the tracker was opened */
    bool tracked;       /* the latest frame had it tracked (and it is recent); else the
                           pose is the last tracked one */
    double position[3]; /* room metres, calibrated */
    double rotation[4]; /* room, x, y, z, w */
    int button_count;
    bool buttons[TRACKER_BUTTONS_MAX];
    int axis_count;
    double axes[TRACKER_AXES_MAX];
    uint64_t poses;     /* tracked poses received */
    uint64_t untracked; /* frames that did not track it */
    double age_ms;      /* since the latest pose (-1: none yet) */
};

/* A link's counters. */
struct tracker_link_stats {
    char name[TRACKER_HOST_MAX + 32]; /* "DTrack port 5000", "VRPN localhost:3883" */
    bool connected;                   /* VRPN: the handshake is done; DTrack: datagrams arrive */
    uint64_t frames;                  /* datagrams (DTrack), messages (VRPN) read */
    uint64_t dropped;                 /* DTrack: frames the counter skipped */
    uint64_t malformed;               /* datagrams or messages refused */
    uint64_t connects;                /* VRPN: handshakes made (a reconnection adds one) */
    int port;                         /* DTrack: the port listened on */
    char seen[128]; /* the ids seen ("bodies 0 1, flysticks 0"; "Tracker0 sensors 0 1") */
};

struct tracker;

/* Opens the tracker D describes (D copied), starting its link's thread if no other tracker
 * uses that link yet.  A DTrack link listens at once (false: the port cannot be had, logged);
 * a VRPN link connects in the background and reconnects with backoff, so a server that is
 * not up yet is not an error.  Close with tracker_close. */
struct tracker *tracker_open(const struct tracker_desc *d);
void tracker_close(struct tracker *t); /* NULL is fine; the link goes with its last tracker */

/* Copies the latest state into OUT, never waiting on the network.  Logs, once each, what an
 * engineer needs to know: the first pose, a body that stops being tracked (it keeps its last
 * pose) and comes back, a body that has not appeared after two seconds (with the ids that
 * did). */
void tracker_sample(struct tracker *t, struct tracker_sample *out);
void tracker_link_stats(const struct tracker *t, struct tracker_link_stats *out);
/* "DTrack body 0 on port 5000", "VRPN Head@localhost:3883 sensor 0". */
const char *tracker_describe(const struct tracker *t);

/* Links open now (for tests: 0 once every tracker is closed). */
int tracker_links_open(void);

/* ---- the wand as an input source ----------------------------------------------------------- */

struct tracker_wand_desc {
    struct tracker_desc tracker;
    int buttons[INPUT_BUTTON_COUNT]; /* the device button of trigger, grab, menu, reset; -1 */
    int axes[INPUT_AXIS_COUNT];      /* the analog channel of fly and turn; -1 */
    double axis_scale[INPUT_AXIS_COUNT];
    double dead_zone; /* |value| below it reads 0 */
};

/* The wand: its ray (tracker space: the room; from the body's position along its -z) when it
 * moves, its mapped buttons when they change, its mapped channels (scaled, clamped to [-1, 1],
 * with the dead zone) when they change.  NULL (logged) when the link cannot be opened. */
struct input_source *tracker_wand_create(const struct tracker_wand_desc *d);

#endif
