/*
 * Tracker links (one UDP port, one VRPN server), each read by its own thread into a table of
 * the latest state of the bodies its trackers want; trackers copy from it under the link's
 * lock and calibrate into the room; the wand as an input source.
 */
#include "input/tracker.h"

#include <arpa/inet.h>
#include <assert.h>
#include <errno.h>
#include <fcntl.h>
#include <ifaddrs.h>
#include <math.h>
#include <net/if.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "common/log.h"
#include "common/parallel.h"
#include "input/input_impl.h"

#define LINKS_MAX 16
#define ENTRIES_MAX 32
#define SEEN_MAX 8
#define STALE_MS 500.0    /* a pose older than this is not "tracked now" */
#define MISSING_MS 2000.0 /* a body not seen after this is reported */
#define QUIET_MS 5000.0   /* between two warnings about malformed input of one link */
#define BACKOFF_MIN_MS 250.0
#define BACKOFF_MAX_MS 4000.0
#define CONNECT_TIMEOUT_MS 2000

/* ---- calibration ------------------------------------------------------------------------ */

static void quat_mul(const double a[4], const double b[4], double out[4])
{
    double r[4] = {
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    };
    memcpy(out, r, sizeof(r));
}

static void quat_rotate(const double q[4], const double v[3], double out[3])
{
    /* v' = v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z) */
    const double *u = q;
    double w = q[3];
    double t[3] = {2.0 * (u[1] * v[2] - u[2] * v[1]), 2.0 * (u[2] * v[0] - u[0] * v[2]),
                   2.0 * (u[0] * v[1] - u[1] * v[0])};
    double r[3] = {v[0] + w * t[0] + u[1] * t[2] - u[2] * t[1],
                   v[1] + w * t[1] + u[2] * t[0] - u[0] * t[2],
                   v[2] + w * t[2] + u[0] * t[1] - u[1] * t[0]};
    memcpy(out, r, sizeof(r));
}

static void quat_normalize(double q[4])
{
    double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(len > 1e-12)) {
        q[0] = q[1] = q[2] = 0.0;
        q[3] = 1.0;
        return;
    }
    for (int i = 0; i < 4; i++)
        q[i] /= len;
}

void tracker_quat_from_matrix(const double m[9], double q[4])
{
    /* Column-major: m[col * 3 + row]. */
    double m00 = m[0], m10 = m[1], m20 = m[2], m01 = m[3], m11 = m[4], m21 = m[5];
    double m02 = m[6], m12 = m[7], m22 = m[8];
    double tr = m00 + m11 + m22, s;
    if (tr > 0.0) {
        s = 2.0 * sqrt(tr + 1.0);
        q[3] = 0.25 * s;
        q[0] = (m21 - m12) / s;
        q[1] = (m02 - m20) / s;
        q[2] = (m10 - m01) / s;
    } else if (m00 > m11 && m00 > m22) {
        s = 2.0 * sqrt(1.0 + m00 - m11 - m22);
        q[3] = (m21 - m12) / s;
        q[0] = 0.25 * s;
        q[1] = (m01 + m10) / s;
        q[2] = (m02 + m20) / s;
    } else if (m11 > m22) {
        s = 2.0 * sqrt(1.0 + m11 - m00 - m22);
        q[3] = (m02 - m20) / s;
        q[0] = (m01 + m10) / s;
        q[1] = 0.25 * s;
        q[2] = (m12 + m21) / s;
    } else {
        s = 2.0 * sqrt(1.0 + m22 - m00 - m11);
        q[3] = (m10 - m01) / s;
        q[0] = (m02 + m20) / s;
        q[1] = (m12 + m21) / s;
        q[2] = 0.25 * s;
    }
    quat_normalize(q);
    if (q[3] < 0.0) {
        for (int i = 0; i < 4; i++)
            q[i] = -q[i];
    }
}

void tracker_calibration_identity(struct tracker_calibration *c)
{
    memset(c, 0, sizeof(*c));
    c->scale = 1.0;
    c->axes[0] = 1;
    c->axes[1] = 2;
    c->axes[2] = 3;
}

/* The axis map as a rotation matrix (column-major); false when it is not a rotation. */
static bool axes_matrix(const int axes[3], double m[9])
{
    memset(m, 0, sizeof(double) * 9);
    int used = 0;
    for (int row = 0; row < 3; row++) {
        int a = axes[row] < 0 ? -axes[row] : axes[row];
        if (a < 1 || a > 3 || (used & (1 << a)))
            return false;
        used |= 1 << a;
        m[(a - 1) * 3 + row] = axes[row] < 0 ? -1.0 : 1.0;
    }
    double det = m[0] * (m[4] * m[8] - m[7] * m[5]) - m[3] * (m[1] * m[8] - m[7] * m[2]) +
                 m[6] * (m[1] * m[5] - m[4] * m[2]);
    return det > 0.0;
}

static void rotation_quat(const double hpr_deg[3], double q[4])
{
    /* As display_pose_from_euler: heading about y, then pitch about x, then roll about z. */
    const double k = M_PI / 360.0; /* half angles */
    double qh[4] = {0.0, sin(hpr_deg[0] * k), 0.0, cos(hpr_deg[0] * k)};
    double qp[4] = {sin(hpr_deg[1] * k), 0.0, 0.0, cos(hpr_deg[1] * k)};
    double qr[4] = {0.0, 0.0, sin(hpr_deg[2] * k), cos(hpr_deg[2] * k)};
    quat_mul(qh, qp, q);
    quat_mul(q, qr, q);
    quat_normalize(q);
}

void tracker_calibrate(const struct tracker_calibration *c, const double pos[3],
                       const double quat[4], double room_pos[3], double room_quat[4])
{
    double a[9];
    bool ok = axes_matrix(c->axes, a);
    assert(ok && "tracker axes must form a rotation");
    (void)ok;
    double qa[4], qr[4], qt[4], p[3];
    tracker_quat_from_matrix(a, qa);
    rotation_quat(c->rotation_deg, qr);
    for (int row = 0; row < 3; row++) {
        int axis = (c->axes[row] < 0 ? -c->axes[row] : c->axes[row]) - 1;
        p[row] = (c->axes[row] < 0 ? -1.0 : 1.0) * c->scale * pos[axis];
    }
    quat_rotate(qr, p, p);
    for (int i = 0; i < 3; i++)
        room_pos[i] = c->offset[i] + p[i];
    memcpy(qt, quat, sizeof(qt));
    quat_normalize(qt);
    double qa_inv[4] = {-qa[0], -qa[1], -qa[2], qa[3]}, q[4];
    quat_mul(qa, qt, q);
    quat_mul(q, qa_inv, q);
    quat_mul(qr, q, q);
    quat_normalize(q);
    memcpy(room_quat, q, sizeof(q));
}

/* ---- links ------------------------------------------------------------------------------ */

enum entry_kind { ENTRY_BODY, ENTRY_FLYSTICK, ENTRY_SENSOR, ENTRY_CONTROLS };

/* The latest state of one wanted thing on a link, in tracker units. */
struct entry {
    enum entry_kind kind;
    char device[TRACKER_NAME_MAX]; /* VRPN: the sender */
    int id;                        /* body, Flystick or sensor; -1 for VRPN controls */
    bool seen, tracked;
    double position[3], quat[4];
    int button_count;
    bool buttons[TRACKER_BUTTONS_MAX];
    int axis_count;
    double axes[TRACKER_AXES_MAX];
    uint64_t poses, untracked;
    double last_ms;
};

struct link {
    struct tracker_address address;
    char name[TRACKER_HOST_MAX + 32];
    int refs;
    pthread_t thread;
    bool thread_started;
    int wake[2]; /* a byte written to wake[1] stops the thread */
    int fd;      /* DTrack: the socket, opened by tracker_open */
    int port;    /* DTrack: bound */

    pthread_mutex_t lock; /* guards what follows */
    struct entry entries[ENTRIES_MAX];
    int entry_count;
    bool connected;
    uint64_t frames, dropped, malformed, connects;
    double last_frame_ms;
    uint64_t bodies_seen, flysticks_seen; /* DTrack: ids < 64 tracked at least once */
    char senders_seen[SEEN_MAX][TRACKER_NAME_MAX];
    uint64_t sensors_seen[SEEN_MAX];
    int senders_seen_count;

    /* The thread's own. */
    bool have_counter;
    uint32_t counter;
    double quiet_until;
    uint64_t quiet_count;
};

static pthread_mutex_t registry = PTHREAD_MUTEX_INITIALIZER;
static struct link *links[LINKS_MAX];

int tracker_links_open(void)
{
    pthread_mutex_lock(&registry);
    int n = 0;
    for (int i = 0; i < LINKS_MAX; i++)
        n += links[i] != NULL;
    pthread_mutex_unlock(&registry);
    return n;
}

static bool stop_requested(struct link *l, int timeout_ms)
{
    struct pollfd p = {.fd = l->wake[0], .events = POLLIN};
    return poll(&p, 1, timeout_ms) > 0;
}

/* A warning about input the link refuses, at most one per QUIET_MS (the rest counted). */
static void refused(struct link *l, const char *why)
{
    double now = time_now_ms();
    if (now < l->quiet_until) {
        l->quiet_count++;
        return;
    }
    if (l->quiet_count)
        log_warn("%s: ignored a malformed %s (%s); %llu more since the last warning", l->name,
                 l->address.protocol == TRACKER_DTRACK ? "datagram" : "message", why,
                 (unsigned long long)l->quiet_count);
    else
        log_warn("%s: ignored a malformed %s (%s)", l->name,
                 l->address.protocol == TRACKER_DTRACK ? "datagram" : "message", why);
    l->quiet_until = now + QUIET_MS;
    l->quiet_count = 0;
}

static struct entry *find_entry(struct link *l, enum entry_kind kind, const char *device, int id)
{
    for (int i = 0; i < l->entry_count; i++) {
        struct entry *e = &l->entries[i];
        if (e->kind == kind && e->id == id && strcmp(e->device, device) == 0)
            return e;
    }
    return NULL;
}

/* Registers what a tracker wants (under the lock): state is kept only for wanted things. */
static void want_entry(struct link *l, enum entry_kind kind, const char *device, int id)
{
    if (find_entry(l, kind, device, id) || l->entry_count >= ENTRIES_MAX)
        return;
    struct entry *e = &l->entries[l->entry_count++];
    memset(e, 0, sizeof(*e));
    e->kind = kind;
    e->id = id;
    snprintf(e->device, sizeof(e->device), "%s", device);
    e->quat[3] = 1.0;
}

/* ---- DTrack ------------------------------------------------------------------------------ */

static const struct dtrack_item *find_item(const struct dtrack_item *items, int n, int id)
{
    for (int i = 0; i < n; i++) {
        if (items[i].id == id)
            return &items[i];
    }
    return NULL;
}

static void apply_items(struct link *l, enum entry_kind kind, const struct dtrack_item *items,
                        int n, double now)
{
    for (int i = 0; i < l->entry_count; i++) {
        struct entry *e = &l->entries[i];
        if (e->kind != kind)
            continue;
        const struct dtrack_item *it = find_item(items, n, e->id);
        if (it) { /* a Flystick's buttons come by radio, tracked or not */
            e->button_count = it->button_count;
            memcpy(e->buttons, it->buttons, sizeof(e->buttons));
            e->axis_count = it->axis_count;
            memcpy(e->axes, it->axes, sizeof(e->axes));
        }
        if (it && it->quality >= 0.0) {
            memcpy(e->position, it->position, sizeof(e->position));
            tracker_quat_from_matrix(it->rotation, e->quat);
            e->seen = e->tracked = true;
            e->poses++;
            e->last_ms = now;
        } else {
            e->tracked = false;
            e->untracked++;
        }
    }
    for (int i = 0; i < n; i++) {
        if (items[i].id < 64 && items[i].quality >= 0.0)
            *(kind == ENTRY_BODY ? &l->bodies_seen : &l->flysticks_seen) |= 1ull << items[i].id;
    }
}

static void apply_dtrack(struct link *l, const struct dtrack_frame *f, double now)
{
    l->frames++;
    l->connected = true;
    l->last_frame_ms = now;
    if (f->have_counter) {
        if (l->have_counter && f->counter > l->counter && f->counter - l->counter < 1000000u)
            l->dropped += f->counter - l->counter - 1;
        l->counter = f->counter;
        l->have_counter = true;
    }
    if (f->have_bodies)
        apply_items(l, ENTRY_BODY, f->bodies, f->body_count, now);
    if (f->have_flysticks)
        apply_items(l, ENTRY_FLYSTICK, f->flysticks, f->flystick_count, now);
}

static void *dtrack_main(void *arg)
{
    struct link *l = arg;
    parallel_name_thread("anvil-dtrack");
    char *buf = malloc(DTRACK_DATAGRAM_MAX + 1);
    struct dtrack_frame *f = malloc(sizeof(*f));
    if (!buf || !f) {
        log_error("%s: out of memory", l->name);
        goto done;
    }
    for (;;) {
        struct pollfd p[2] = {{.fd = l->fd, .events = POLLIN},
                              {.fd = l->wake[0], .events = POLLIN}};
        int r = poll(p, 2, 1000);
        if (r < 0 && errno != EINTR) {
            log_error("%s: %s", l->name, strerror(errno));
            break;
        }
        if (r > 0 && p[1].revents)
            break;
        if (r <= 0 || !(p[0].revents & POLLIN))
            continue;
        ssize_t n = recv(l->fd, buf, DTRACK_DATAGRAM_MAX + 1, MSG_TRUNC);
        if (n < 0)
            continue;
        char why[160];
        bool ok = n <= DTRACK_DATAGRAM_MAX && dtrack_parse(buf, (size_t)n, f, why, sizeof(why));
        if (n > DTRACK_DATAGRAM_MAX)
            snprintf(why, sizeof(why), "a datagram of %zd bytes, more than %d", n,
                     DTRACK_DATAGRAM_MAX);
        double now = time_now_ms();
        pthread_mutex_lock(&l->lock);
        if (ok)
            apply_dtrack(l, f, now);
        else
            l->malformed++;
        pthread_mutex_unlock(&l->lock);
        if (!ok)
            refused(l, why);
    }
done:
    free(buf);
    free(f);
    return NULL;
}

/* Joins the multicast group HOST on every IPv4 interface that is up (DTrack's output may
 * come in on any of a CAVE machine's networks, or on loopback). */
static bool join_group(struct link *l, struct in_addr host)
{
    struct ifaddrs *ifs = NULL;
    int joined = 0, err = 0;
    if (getifaddrs(&ifs) == 0) {
        for (struct ifaddrs *i = ifs; i; i = i->ifa_next) {
            if (!i->ifa_addr || i->ifa_addr->sa_family != AF_INET || !(i->ifa_flags & IFF_UP))
                continue;
            struct ip_mreq m = {.imr_multiaddr = host};
            m.imr_interface = ((struct sockaddr_in *)i->ifa_addr)->sin_addr;
            if (setsockopt(l->fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &m, sizeof(m)) == 0)
                joined++;
            else
                err = errno;
        }
        freeifaddrs(ifs);
    }
    if (joined == 0) {
        struct ip_mreq m = {.imr_multiaddr = host};
        m.imr_interface.s_addr = htonl(INADDR_ANY);
        if (setsockopt(l->fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &m, sizeof(m)) == 0)
            return true;
        log_error("%s: cannot join the multicast group %s: %s", l->name, l->address.host,
                  strerror(err ? err : errno));
        return false;
    }
    return true;
}

static bool dtrack_listen(struct link *l)
{
    const struct tracker_address *a = &l->address;
    struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)a->port)};
    sa.sin_addr.s_addr = htonl(INADDR_ANY);
    struct in_addr host = {0};
    bool multicast = false;
    if (a->host[0]) {
        if (inet_pton(AF_INET, a->host, &host) != 1) {
            log_error("%s: \"%s\" is not an IPv4 address", l->name, a->host);
            return false;
        }
        multicast = IN_MULTICAST(ntohl(host.s_addr));
        if (!multicast)
            sa.sin_addr = host;
    }
    l->fd = socket(AF_INET, SOCK_DGRAM, 0);
    if (l->fd < 0) {
        log_error("%s: cannot make a UDP socket: %s", l->name, strerror(errno));
        return false;
    }
    fcntl(l->fd, F_SETFD, FD_CLOEXEC);
    int one = 1;
    if (multicast) /* other listeners of the group may share the port */
        setsockopt(l->fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    if (bind(l->fd, (struct sockaddr *)&sa, sizeof(sa)) != 0) {
        log_error("%s: cannot listen on UDP port %d: %s (does another program have it?)", l->name,
                  a->port, strerror(errno));
        return false;
    }
    if (multicast && !join_group(l, host))
        return false;
    struct sockaddr_in bound;
    socklen_t len = sizeof(bound);
    if (getsockname(l->fd, (struct sockaddr *)&bound, &len) == 0)
        l->port = ntohs(bound.sin_port);
    return true;
}

/* ---- VRPN -------------------------------------------------------------------------------- */

static bool send_all(int fd, const uint8_t *b, size_t n)
{
    while (n > 0) {
        ssize_t w = send(fd, b, n, MSG_NOSIGNAL);
        if (w < 0 && (errno == EAGAIN || errno == EINTR)) {
            struct pollfd p = {.fd = fd, .events = POLLOUT};
            if (poll(&p, 1, 1000) <= 0)
                return false;
            continue;
        }
        if (w <= 0)
            return false;
        b += w;
        n -= (size_t)w;
    }
    return true;
}

/* Connects to the server: the socket, -1 (WHY says why) or -2 when stopped meanwhile. */
static int vrpn_connect(struct link *l, char *why, size_t why_size)
{
    struct addrinfo hints = {.ai_family = AF_UNSPEC, .ai_socktype = SOCK_STREAM}, *res = NULL;
    char port[16];
    snprintf(port, sizeof(port), "%d", l->address.port);
    int rc = getaddrinfo(l->address.host, port, &hints, &res);
    if (rc != 0) {
        snprintf(why, why_size, "cannot find the host: %s", gai_strerror(rc));
        return -1;
    }
    int fd = -1;
    snprintf(why, why_size, "no address to connect to");
    for (struct addrinfo *ai = res; ai && fd < 0; ai = ai->ai_next) {
        fd = socket(ai->ai_family, ai->ai_socktype, ai->ai_protocol);
        if (fd < 0)
            continue;
        fcntl(fd, F_SETFD, FD_CLOEXEC);
        fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
        int err = 0;
        if (connect(fd, ai->ai_addr, ai->ai_addrlen) != 0) {
            err = errno;
            if (err == EINPROGRESS) {
                struct pollfd p[2] = {{.fd = fd, .events = POLLOUT},
                                      {.fd = l->wake[0], .events = POLLIN}};
                int r = poll(p, 2, CONNECT_TIMEOUT_MS);
                if (r > 0 && p[1].revents) {
                    close(fd);
                    freeaddrinfo(res);
                    return -2;
                }
                socklen_t len = sizeof(err);
                if (r == 0)
                    err = ETIMEDOUT;
                else if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) != 0)
                    err = errno;
            }
        }
        if (err != 0) {
            snprintf(why, why_size, "%s", strerror(err));
            close(fd);
            fd = -1;
        }
    }
    freeaddrinfo(res);
    if (fd >= 0) {
        int one = 1;
        setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    }
    return fd;
}

static void note_sender(struct link *l, const char *sender, int sensor)
{
    int i = 0;
    while (i < l->senders_seen_count && strcmp(l->senders_seen[i], sender) != 0)
        i++;
    if (i == l->senders_seen_count) {
        if (i == SEEN_MAX)
            return;
        snprintf(l->senders_seen[i], sizeof(l->senders_seen[i]), "%s", sender);
        l->sensors_seen[i] = 0;
        l->senders_seen_count++;
    }
    if (sensor >= 0 && sensor < 64)
        l->sensors_seen[i] |= 1ull << sensor;
}

/* One VRPN event into the table (under the lock). */
static void apply_vrpn(struct link *l, const struct vrpn_event *ev, double now)
{
    l->frames++;
    struct entry *e;
    switch (ev->type) {
    case VRPN_POSE:
        note_sender(l, ev->sender, ev->sensor);
        e = find_entry(l, ENTRY_SENSOR, ev->sender, ev->sensor);
        if (!e)
            return;
        memcpy(e->position, ev->position, sizeof(e->position));
        memcpy(e->quat, ev->quat, sizeof(e->quat));
        quat_normalize(e->quat);
        e->seen = e->tracked = true;
        e->poses++;
        e->last_ms = now;
        return;
    case VRPN_BUTTON:
        note_sender(l, ev->sender, -1);
        e = find_entry(l, ENTRY_CONTROLS, ev->sender, -1);
        if (!e || ev->button >= TRACKER_BUTTONS_MAX)
            return;
        e->buttons[ev->button] = ev->state != 0;
        if (e->button_count < ev->button + 1)
            e->button_count = ev->button + 1;
        return;
    case VRPN_BUTTONS:
        note_sender(l, ev->sender, -1);
        e = find_entry(l, ENTRY_CONTROLS, ev->sender, -1);
        if (!e)
            return;
        e->button_count = ev->count < TRACKER_BUTTONS_MAX ? ev->count : TRACKER_BUTTONS_MAX;
        for (int i = 0; i < e->button_count; i++)
            e->buttons[i] = ev->states[i] != 0;
        return;
    case VRPN_ANALOG:
        note_sender(l, ev->sender, -1);
        e = find_entry(l, ENTRY_CONTROLS, ev->sender, -1);
        if (!e)
            return;
        e->axis_count = ev->count < TRACKER_AXES_MAX ? ev->count : TRACKER_AXES_MAX;
        memcpy(e->axes, ev->channels, sizeof(double) * (size_t)e->axis_count);
        return;
    default:
        return;
    }
}

/* Reads one connection until it ends: NULL when stopped, else why it ended. */
static const char *vrpn_session(struct link *l, int fd, struct vrpn_parser *p, uint8_t *buf,
                                size_t size, bool *handshake, char *why, size_t why_size)
{
    uint8_t cookie[VRPN_COOKIE_BYTES];
    vrpn_write_cookie(cookie, sizeof(cookie));
    if (!send_all(fd, cookie, sizeof(cookie))) {
        snprintf(why, why_size, "cannot send the cookie: %s", strerror(errno));
        return why;
    }
    vrpn_parser_init(p);
    struct vrpn_event ev;
    for (;;) {
        struct pollfd pf[2] = {{.fd = fd, .events = POLLIN}, {.fd = l->wake[0], .events = POLLIN}};
        int r = poll(pf, 2, 1000);
        if (r > 0 && pf[1].revents)
            return NULL;
        if (r < 0 && errno != EINTR) {
            snprintf(why, why_size, "%s", strerror(errno));
            return why;
        }
        if (r <= 0)
            continue;
        ssize_t n = recv(fd, buf, size, 0);
        if (n == 0) {
            snprintf(why, why_size, "the server closed the connection");
            return why;
        }
        if (n < 0) {
            if (errno == EAGAIN || errno == EINTR)
                continue;
            snprintf(why, why_size, "%s", strerror(errno));
            return why;
        }
        size_t pos = 0;
        enum vrpn_event_type t;
        while ((t = vrpn_parse(p, buf, (size_t)n, &pos, &ev)) != VRPN_NONE) {
            double now = time_now_ms();
            if (t == VRPN_ERROR) {
                pthread_mutex_lock(&l->lock);
                l->malformed++;
                pthread_mutex_unlock(&l->lock);
                snprintf(why, why_size, "%s", ev.why);
                return why;
            }
            if (t == VRPN_COOKIE) {
                pthread_mutex_lock(&l->lock);
                l->connected = true;
                l->connects++;
                pthread_mutex_unlock(&l->lock);
                *handshake = true;
                log_info("%s: connected (%s)", l->name, ev.name);
                continue;
            }
            if (t == VRPN_SKIPPED && ev.malformed) {
                pthread_mutex_lock(&l->lock);
                l->malformed++;
                pthread_mutex_unlock(&l->lock);
                refused(l, ev.why);
                continue;
            }
            pthread_mutex_lock(&l->lock);
            apply_vrpn(l, &ev, now);
            pthread_mutex_unlock(&l->lock);
        }
    }
}

static void *vrpn_main(void *arg)
{
    struct link *l = arg;
    parallel_name_thread("anvil-vrpn");
    struct vrpn_parser *p = malloc(sizeof(*p));
    size_t size = 16384;
    uint8_t *buf = malloc(size);
    if (!p || !buf) {
        log_error("%s: out of memory", l->name);
        goto done;
    }
    double backoff = BACKOFF_MIN_MS;
    bool down_reported = false;
    for (;;) {
        char why[160];
        const char *ended = why;
        bool handshake = false;
        int fd = vrpn_connect(l, why, sizeof(why));
        if (fd == -2)
            break;
        if (fd >= 0) {
            ended = vrpn_session(l, fd, p, buf, size, &handshake, why, sizeof(why));
            close(fd);
            if (!ended)
                break;
        }
        pthread_mutex_lock(&l->lock);
        l->connected = false;
        pthread_mutex_unlock(&l->lock);
        if (handshake) {
            log_warn("%s: lost the server (%s); reconnecting", l->name, ended);
            backoff = BACKOFF_MIN_MS;
            down_reported = true;
        } else if (!down_reported) {
            log_warn("%s: cannot connect (%s); retrying, up to every %.0f s", l->name, ended,
                     BACKOFF_MAX_MS / 1000.0);
            down_reported = true;
        }
        if (stop_requested(l, (int)backoff))
            break;
        backoff = fmin(2.0 * backoff, BACKOFF_MAX_MS);
    }
done:
    free(p);
    free(buf);
    return NULL;
}

/* ---- the registry ----------------------------------------------------------------------- */

static void link_free(struct link *l)
{
    if (l->thread_started) {
        ssize_t w = write(l->wake[1], "x", 1);
        (void)w;
        pthread_join(l->thread, NULL);
    }
    if (l->fd >= 0)
        close(l->fd);
    if (l->wake[0] >= 0)
        close(l->wake[0]);
    if (l->wake[1] >= 0)
        close(l->wake[1]);
    pthread_mutex_destroy(&l->lock);
    free(l);
}

static bool same_link(const struct tracker_address *a, const struct tracker_address *b)
{
    return a->protocol == b->protocol && a->port == b->port && a->port != 0 &&
           strcmp(a->host, b->host) == 0;
}

/* The link for A, made if needed, with one more reference (under the registry lock). */
static struct link *link_get(const struct tracker_address *a)
{
    for (int i = 0; i < LINKS_MAX; i++) {
        if (links[i] && same_link(&links[i]->address, a)) {
            links[i]->refs++;
            return links[i];
        }
    }
    int slot = 0;
    while (slot < LINKS_MAX && links[slot])
        slot++;
    if (slot == LINKS_MAX) {
        log_error("more than %d tracker links", LINKS_MAX);
        return NULL;
    }
    struct link *l = calloc(1, sizeof(*l));
    if (!l) {
        log_error("tracker: out of memory");
        return NULL;
    }
    l->address = *a;
    l->fd = l->wake[0] = l->wake[1] = -1;
    pthread_mutex_init(&l->lock, NULL);
    if (a->protocol == TRACKER_DTRACK)
        snprintf(l->name, sizeof(l->name), "DTrack %s%sport %d", a->host, a->host[0] ? " " : "",
                 a->port);
    else
        snprintf(l->name, sizeof(l->name), "VRPN %s:%d", a->host, a->port);
    if (pipe(l->wake) != 0) {
        log_error("%s: %s", l->name, strerror(errno));
        goto error;
    }
    fcntl(l->wake[0], F_SETFD, FD_CLOEXEC);
    fcntl(l->wake[1], F_SETFD, FD_CLOEXEC);
    if (a->protocol == TRACKER_DTRACK && !dtrack_listen(l))
        goto error;
    if (a->protocol == TRACKER_DTRACK && a->port == 0) { /* any free port: now a known one */
        l->address.port = l->port;
        snprintf(l->name, sizeof(l->name), "DTrack port %d", l->port);
    }
    if (pthread_create(&l->thread, NULL, a->protocol == TRACKER_DTRACK ? dtrack_main : vrpn_main,
                       l) != 0) {
        log_error("%s: cannot start its thread", l->name);
        goto error;
    }
    l->thread_started = true;
    l->refs = 1;
    links[slot] = l;
    return l;

error:
    link_free(l);
    return NULL;
}

static void link_put(struct link *l)
{
    if (!l)
        return;
    pthread_mutex_lock(&registry);
    bool last = --l->refs == 0;
    if (last) {
        for (int i = 0; i < LINKS_MAX; i++) {
            if (links[i] == l)
                links[i] = NULL;
        }
    }
    pthread_mutex_unlock(&registry);
    if (last)
        link_free(l);
}

/* ---- trackers ------------------------------------------------------------------------------ */

struct tracker {
    struct tracker_desc desc;
    char what[32];
    char describe[TRACKER_HOST_MAX + 96];
    struct link *link, *controls;
    enum entry_kind kind;
    const char *controls_device;
    double opened_ms;
    bool reported_first, reported_missing, was_tracked;
};

struct tracker *tracker_open(const struct tracker_desc *d)
{
    double a[9];
    bool axes_ok = axes_matrix(d->calibration.axes, a);
    assert(axes_ok && "tracker axes must form a rotation");
    (void)axes_ok;
    struct tracker *t = calloc(1, sizeof(*t));
    if (!t) {
        log_error("tracker: out of memory");
        return NULL;
    }
    t->desc = *d;
    snprintf(t->what, sizeof(t->what), "%s", d->what ? d->what : "tracker");
    t->desc.what = t->what;
    bool vrpn = d->address.protocol == TRACKER_VRPN;
    t->kind = vrpn ? ENTRY_SENSOR : d->flystick ? ENTRY_FLYSTICK : ENTRY_BODY;
    pthread_mutex_lock(&registry);
    t->link = link_get(&d->address);
    if (t->link && vrpn && d->controls.device[0] && !same_link(&d->controls, &d->address))
        t->controls = link_get(&d->controls);
    else if (t->link)
        t->controls = t->link, t->link->refs++;
    pthread_mutex_unlock(&registry);
    if (!t->link || !t->controls) {
        tracker_close(t);
        return NULL;
    }
    t->controls_device =
        vrpn && d->controls.device[0] ? t->desc.controls.device : t->desc.address.device;
    pthread_mutex_lock(&t->link->lock);
    want_entry(t->link, t->kind, vrpn ? d->address.device : "", d->sensor);
    pthread_mutex_unlock(&t->link->lock);
    if (vrpn) {
        pthread_mutex_lock(&t->controls->lock);
        want_entry(t->controls, ENTRY_CONTROLS, t->controls_device, -1);
        pthread_mutex_unlock(&t->controls->lock);
    }
    if (vrpn)
        snprintf(t->describe, sizeof(t->describe), "VRPN %s@%s:%d sensor %d", d->address.device,
                 d->address.host, d->address.port, d->sensor);
    else
        snprintf(t->describe, sizeof(t->describe), "DTrack %s %d on %s",
                 d->flystick ? "Flystick" : "body", d->sensor, t->link->name + strlen("DTrack "));
    t->opened_ms = time_now_ms();
    return t;
}

void tracker_close(struct tracker *t)
{
    if (!t)
        return;
    link_put(t->controls);
    link_put(t->link);
    free(t);
}

const char *tracker_describe(const struct tracker *t)
{
    return t->describe;
}

static void seen_text(struct link *l, char *out, size_t size)
{
    size_t n = 0;
    out[0] = '\0';
    if (l->address.protocol == TRACKER_DTRACK) {
        for (int k = 0; k < 2; k++) {
            uint64_t mask = k == 0 ? l->bodies_seen : l->flysticks_seen;
            if (!mask)
                continue;
            n += (size_t)snprintf(out + n, size - n, "%s%s", n ? ", " : "",
                                  k == 0 ? "bodies" : "Flysticks");
            for (int i = 0; i < 64 && n < size; i++) {
                if (mask & (1ull << i))
                    n += (size_t)snprintf(out + n, size - n, " %d", i);
            }
        }
        return;
    }
    for (int s = 0; s < l->senders_seen_count && n < size; s++) {
        n += (size_t)snprintf(out + n, size - n, "%s%s", n ? ", " : "", l->senders_seen[s]);
        if (l->sensors_seen[s] && n < size)
            n += (size_t)snprintf(out + n, size - n, " sensors");
        for (int i = 0; i < 64 && n < size; i++) {
            if (l->sensors_seen[s] & (1ull << i))
                n += (size_t)snprintf(out + n, size - n, " %d", i);
        }
    }
}

void tracker_sample(struct tracker *t, struct tracker_sample *out)
{
    memset(out, 0, sizeof(*out));
    out->rotation[3] = 1.0;
    double now = time_now_ms();
    bool vrpn = t->desc.address.protocol == TRACKER_VRPN;
    struct entry e = {0}, c = {0};
    bool connected;
    char seen[128];
    pthread_mutex_lock(&t->link->lock);
    const struct entry *found =
        find_entry(t->link, t->kind, vrpn ? t->desc.address.device : "", t->desc.sensor);
    if (found)
        e = *found;
    connected = t->link->connected;
    seen_text(t->link, seen, sizeof(seen));
    pthread_mutex_unlock(&t->link->lock);
    if (vrpn) {
        pthread_mutex_lock(&t->controls->lock);
        found = find_entry(t->controls, ENTRY_CONTROLS, t->controls_device, -1);
        if (found)
            c = *found;
        pthread_mutex_unlock(&t->controls->lock);
    } else {
        c = e;
    }
    out->seen = e.seen;
    out->tracked = e.seen && e.tracked && now - e.last_ms < STALE_MS;
    out->poses = e.poses;
    out->untracked = e.untracked;
    out->age_ms = e.seen ? now - e.last_ms : -1.0;
    if (e.seen)
        tracker_calibrate(&t->desc.calibration, e.position, e.quat, out->position, out->rotation);
    out->button_count = c.button_count;
    memcpy(out->buttons, c.buttons, sizeof(out->buttons));
    out->axis_count = c.axis_count;
    memcpy(out->axes, c.axes, sizeof(out->axes));

    /* Once each: what an engineer needs to hear. */
    if (e.seen && !t->reported_first) {
        log_info("%s: %s: first pose", t->what, t->describe);
        t->reported_first = t->was_tracked = true;
    } else if (!e.seen && !t->reported_missing && now - t->opened_ms > MISSING_MS) {
        if (!connected)
            log_warn("%s: %s: nothing received yet", t->what, t->describe);
        else
            log_warn("%s: %s: not in the stream yet (seen: %s)", t->what, t->describe,
                     seen[0] ? seen : "nothing tracked");
        t->reported_missing = true;
    }
    if (e.seen && t->was_tracked && !out->tracked) {
        log_warn("%s: %s is not tracked: keeping its last pose", t->what, t->describe);
        t->was_tracked = false;
    } else if (e.seen && !t->was_tracked && out->tracked) {
        log_info("%s: %s is tracked again", t->what, t->describe);
        t->was_tracked = true;
    }
}

void tracker_link_stats(const struct tracker *t, struct tracker_link_stats *out)
{
    memset(out, 0, sizeof(*out));
    struct link *l = t->link;
    pthread_mutex_lock(&l->lock);
    snprintf(out->name, sizeof(out->name), "%s", l->name);
    out->connected = l->connected && (l->address.protocol == TRACKER_VRPN ||
                                      time_now_ms() - l->last_frame_ms < 1000.0);
    out->frames = l->frames;
    out->dropped = l->dropped;
    out->malformed = l->malformed;
    out->connects = l->connects;
    out->port = l->port;
    seen_text(l, out->seen, sizeof(out->seen));
    pthread_mutex_unlock(&l->lock);
}

/* ---- the wand -------------------------------------------------------------------------------- */

struct wand {
    struct input_source base;
    struct tracker *tracker;
    struct tracker_wand_desc desc;
    bool have_pose;
    float pose[9];
    bool pressed[INPUT_BUTTON_COUNT];
    float axes[INPUT_AXIS_COUNT];
};

static bool wand_poll(struct input_source *s, const struct input_frame *frame,
                      struct input_queue *q)
{
    struct wand *w = (struct wand *)s;
    struct tracker_sample smp;
    tracker_sample(w->tracker, &smp);
    if (smp.seen) {
        const double *r = smp.rotation;
        double dir[3] = {-2.0 * (r[0] * r[2] + r[3] * r[1]), -2.0 * (r[1] * r[2] - r[3] * r[0]),
                         -(1.0 - 2.0 * (r[0] * r[0] + r[1] * r[1]))};
        /* The wand's up: the rotation of (0, 1, 0). */
        double up[3] = {2.0 * (r[0] * r[1] - r[3] * r[2]), 1.0 - 2.0 * (r[0] * r[0] + r[2] * r[2]),
                        2.0 * (r[1] * r[2] + r[3] * r[0])};
        struct input_event e = {.type = INPUT_POSE, .space = INPUT_SPACE_TRACKER, .has_up = true};
        for (int i = 0; i < 3; i++) {
            e.position[i] = (float)smp.position[i];
            e.direction[i] = (float)dir[i];
            e.up[i] = (float)up[i];
        }
        float pose[9] = {e.position[0],  e.position[1],  e.position[2],
                         e.direction[0], e.direction[1], e.direction[2],
                         e.up[0],        e.up[1],        e.up[2]};
        if (!w->have_pose || memcmp(pose, w->pose, sizeof(pose)) != 0) {
            memcpy(w->pose, pose, sizeof(pose));
            w->have_pose = true;
            input_queue_push(q, &e);
        }
    }
    for (int b = 0; b < INPUT_BUTTON_COUNT; b++) {
        int i = w->desc.buttons[b];
        bool down = i >= 0 && i < smp.button_count && smp.buttons[i];
        if (down == w->pressed[b])
            continue;
        w->pressed[b] = down;
        input_queue_push(q, &(struct input_event){.type = INPUT_BUTTON,
                                                  .button = (enum input_button)b,
                                                  .down = down});
    }
    for (int a = 0; a < INPUT_AXIS_COUNT; a++) {
        int i = w->desc.axes[a];
        double v = i >= 0 && i < smp.axis_count ? smp.axes[i] * w->desc.axis_scale[a] : 0.0;
        v = v < -1.0 ? -1.0 : v > 1.0 ? 1.0 : v;
        if (fabs(v) < w->desc.dead_zone)
            v = 0.0;
        if ((float)v == w->axes[a])
            continue;
        w->axes[a] = (float)v;
        input_queue_push(q, &(struct input_event){
                                .type = INPUT_AXIS, .axis = (enum input_axis)a, .value = (float)v});
    }
    return true;
}

static void wand_destroy(struct input_source *s)
{
    struct wand *w = (struct wand *)s;
    tracker_close(w->tracker);
    free(w);
}

static const struct input_source_impl wand_impl = {
    .name = "tracker",
    .poll = wand_poll,
    .destroy = wand_destroy,
};

struct input_source *tracker_wand_create(const struct tracker_wand_desc *d)
{
    struct wand *w = calloc(1, sizeof(*w));
    if (!w) {
        log_error("wand: out of memory");
        return NULL;
    }
    w->base.impl = &wand_impl;
    w->desc = *d;
    w->tracker = tracker_open(&d->tracker);
    if (!w->tracker) {
        free(w);
        return NULL;
    }
    log_info("wand: %s", tracker_describe(w->tracker));
    return &w->base;
}
