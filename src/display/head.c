/*
 * Head poses: fixed, a scripted path of timed poses (or the head of a recording), an OpenHMD
 * device (opened by name in the process's one OpenHMD context, input_ohmd_open), or a body of
 * a DTrack or VRPN tracker (input/tracker.h, calibrated into the room); and the descs that
 * turn a display config's head.* and wand.* into the input part's.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <cglm/cglm.h>

#include <openhmd.h>

#include "common/log.h"
#include "display/display_impl.h"

/* ---- scripted paths ------------------------------------------------------------------ */

void display_path_finish(struct display_path *path)
{
    if (!path)
        return;
    free(path->time);
    free(path->pose);
    memset(path, 0, sizeof(*path));
}

/* Appends pose P at time T (a later time, or replacing the pose at the same time). */
static bool path_add(struct display_path *path, int *cap, double t, const struct display_pose *p)
{
    if (path->count > 0 && !(t > path->time[path->count - 1])) {
        path->pose[path->count - 1] = *p;
        return true;
    }
    if (path->count == *cap) {
        *cap = *cap ? 2 * *cap : 16;
        double *times = realloc(path->time, sizeof(double) * (size_t)*cap);
        if (times)
            path->time = times;
        struct display_pose *ps = realloc(path->pose, sizeof(*ps) * (size_t)*cap);
        if (ps)
            path->pose = ps;
        if (!times || !ps)
            return false;
    }
    path->time[path->count] = t;
    path->pose[path->count++] = *p;
    return true;
}

/* A recording (input_recorder) as a path: its head lines, at the sum of the frames' steps. */
static bool path_from_recording(const char *file, struct display_path *path)
{
    struct input_source *rec = input_script_open(file);
    if (!rec)
        return false;
    int cap = 0;
    double t = 0.0;
    bool ok = true;
    long last = input_script_last_frame(rec);
    for (long f = 0; f <= last && ok; f++) {
        struct input_script_frame info;
        if (!input_script_frame(rec, f, &info))
            continue;
        if (info.have_time)
            t += info.dt_s;
        if (info.have_head) {
            struct display_pose p;
            memcpy(p.position, info.head_position, sizeof(p.position));
            memcpy(p.rotation, info.head_rotation, sizeof(p.rotation));
            ok = path_add(path, &cap, t, &p);
        }
    }
    input_source_destroy(rec);
    if (!ok)
        log_error("%s: out of memory", file);
    else if (path->count == 0)
        log_error("%s: expected a recording with head lines (a tracked display's)", file);
    if (!ok || path->count == 0) {
        display_path_finish(path);
        return false;
    }
    return true;
}

/* Whether TEXT is a recording: a line "recorded ..." before any pose line. */
static bool is_recording(const char *text)
{
    for (const char *p = text; *p;) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')
            p++;
        if (strncmp(p, "recorded ", 9) == 0)
            return true;
        if (*p && *p != '#')
            return false;
        p = strchr(p, '\n');
        if (!p)
            break;
    }
    return false;
}

bool display_path_load(const char *file, struct display_path *path)
{
    memset(path, 0, sizeof(*path));
    char *text = file_read_all(file, NULL);
    if (!text)
        return false;
    if (is_recording(text)) {
        free(text);
        return path_from_recording(file, path);
    }
    int cap = 0, line = 0;
    bool ok = true;
    for (char *p = text; *p && ok;) {
        char *end = strchr(p, '\n');
        if (end)
            *end = '\0';
        line++;
        char *hash = strchr(p, '#');
        if (hash)
            *hash = '\0';
        char *q = p;
        while (isspace((unsigned char)*q))
            q++;
        if (*q) {
            double v[7];
            int used = 0;
            int got = sscanf(q, "%lf %lf %lf %lf %lf %lf %lf %n", &v[0], &v[1], &v[2], &v[3],
                             &v[4], &v[5], &v[6], &used);
            bool finite = true;
            for (int i = 0; i < got; i++)
                finite = finite && isfinite(v[i]);
            if (got != 7 || q[used] != '\0' || !finite) {
                log_error("%s:%d: expected 7 numbers: t x y z heading pitch roll (seconds, "
                          "metres, degrees)",
                          file, line);
                ok = false;
                break;
            }
            if (path->count > 0 && !(v[0] > path->time[path->count - 1])) {
                log_error("%s:%d: expected a time after %g s (times must increase)", file, line,
                          path->time[path->count - 1]);
                ok = false;
                break;
            }
            if (path->count == cap) {
                cap = cap ? 2 * cap : 16;
                double *t = realloc(path->time, sizeof(double) * (size_t)cap);
                if (t)
                    path->time = t;
                struct display_pose *ps = realloc(path->pose, sizeof(*ps) * (size_t)cap);
                if (ps)
                    path->pose = ps;
                if (!t || !ps) {
                    log_error("%s: out of memory", file);
                    ok = false;
                    break;
                }
            }
            path->time[path->count] = v[0];
            display_pose_from_euler(&v[1], &v[4], &path->pose[path->count]);
            path->count++;
        }
        p = end ? end + 1 : p + strlen(p);
    }
    free(text);
    if (ok && path->count == 0) {
        log_error("%s:%d: expected at least one pose line: t x y z heading pitch roll", file,
                  line);
        ok = false;
    }
    if (!ok)
        display_path_finish(path);
    return ok;
}

void display_path_eval(const struct display_path *path, double t, struct display_pose *out)
{
    int n = path->count;
    if (n == 0) {
        memset(out, 0, sizeof(*out));
        out->rotation[3] = 1.0f;
        return;
    }
    if (t <= path->time[0] || n == 1) {
        *out = path->pose[0];
        return;
    }
    if (t >= path->time[n - 1]) {
        *out = path->pose[n - 1];
        return;
    }
    int lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (path->time[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    float s = (float)((t - path->time[lo]) / (path->time[hi] - path->time[lo]));
    const struct display_pose *a = &path->pose[lo], *b = &path->pose[hi];
    for (int i = 0; i < 3; i++)
        out->position[i] = a->position[i] + s * (b->position[i] - a->position[i]);
    versor qa, qb, q;
    memcpy(qa, a->rotation, sizeof(qa));
    memcpy(qb, b->rotation, sizeof(qb));
    glm_quat_slerp(qa, qb, s, q);
    memcpy(out->rotation, q, sizeof(q));
}

/* ---- trackers: the display config's head.* and wand.* as the input part's descs --------- */

static void tracking_desc(const struct display_tracking *t, bool vrpn, const char *what,
                          struct tracker_desc *out)
{
    memset(out, 0, sizeof(*out));
    out->what = what;
    out->address.protocol = vrpn ? TRACKER_VRPN : TRACKER_DTRACK;
    snprintf(out->address.host, sizeof(out->address.host), "%s", t->host);
    out->address.port = t->port;
    snprintf(out->address.device, sizeof(out->address.device), "%s", t->device);
    out->sensor = t->sensor;
    struct tracker_calibration *c = &out->calibration;
    tracker_calibration_identity(c);
    switch (t->units) {
    case DISPLAY_UNITS_AUTO:
        c->scale = vrpn ? 1.0 : 1e-3;
        break;
    case DISPLAY_UNITS_M:
        c->scale = 1.0;
        break;
    case DISPLAY_UNITS_CM:
        c->scale = 1e-2;
        break;
    case DISPLAY_UNITS_MM:
        c->scale = 1e-3;
        break;
    }
    memcpy(c->axes, t->axis_map, sizeof(c->axes));
    memcpy(c->offset, t->offset, sizeof(c->offset));
    memcpy(c->rotation_deg, t->rotation_deg, sizeof(c->rotation_deg));
}

void display_head_desc(const struct display_config *cfg, struct tracker_desc *out)
{
    tracking_desc(&cfg->head.tracking, cfg->head.source == DISPLAY_HEAD_VRPN, "head", out);
}

void display_wand_desc(const struct display_config *cfg, struct tracker_wand_desc *out)
{
    const struct display_wand *w = &cfg->wand;
    memset(out, 0, sizeof(*out));
    bool vrpn = w->source == DISPLAY_WAND_VRPN;
    tracking_desc(&w->tracking, vrpn, "wand", &out->tracker);
    out->tracker.flystick = !vrpn && w->flystick;
    if (vrpn && w->controls[0]) {
        out->tracker.controls.protocol = TRACKER_VRPN;
        snprintf(out->tracker.controls.host, sizeof(out->tracker.controls.host), "%s",
                 w->controls_host);
        out->tracker.controls.port = w->controls_port;
        snprintf(out->tracker.controls.device, sizeof(out->tracker.controls.device), "%s",
                 w->controls_device);
    }
    for (int b = 0; b < INPUT_BUTTON_COUNT; b++)
        out->buttons[b] = w->buttons[b];
    for (int a = 0; a < INPUT_AXIS_COUNT; a++) {
        out->axes[a] = w->joystick[a];
        out->axis_scale[a] = w->joystick_scale[a];
    }
    out->dead_zone = w->dead_zone;
}

/* ---- head trackers ------------------------------------------------------------------- */

bool display_head_tracker_init(struct display_head_tracker *h, const struct display_head *cfg,
                               const struct display_config *display)
{
    memset(h, 0, sizeof(*h));
    h->source = cfg->source;
    display_pose_from_euler(cfg->position, cfg->orientation_deg, &h->fixed);
    switch (cfg->source) {
    case DISPLAY_HEAD_FIXED:
        return true;
    case DISPLAY_HEAD_PATH:
        return display_path_load(cfg->path, &h->path);
    case DISPLAY_HEAD_OPENHMD:
        h->device = input_ohmd_open(cfg->device, -1);
        return h->device != NULL;
    case DISPLAY_HEAD_DTRACK:
    case DISPLAY_HEAD_VRPN: {
        struct tracker_desc td;
        display_head_desc(display, &td);
        h->tracker = tracker_open(&td);
        if (h->tracker)
            log_info("head: %s", tracker_describe(h->tracker));
        return h->tracker != NULL;
    }
    }
    return false;
}

void display_head_tracker_finish(struct display_head_tracker *h)
{
    if (!h)
        return;
    display_path_finish(&h->path);
    input_ohmd_close(h->device);
    tracker_close(h->tracker);
    memset(h, 0, sizeof(*h));
}

bool display_head_tracker_pose(struct display_head_tracker *h, double t,
                               struct display_pose *out)
{
    switch (h->source) {
    case DISPLAY_HEAD_FIXED:
        *out = h->fixed;
        return true;
    case DISPLAY_HEAD_PATH:
        display_path_eval(&h->path, t, out);
        return true;
    case DISPLAY_HEAD_OPENHMD: {
        input_ohmd_update();
        float q[4] = {0, 0, 0, 1}, p[3] = {0, 0, 0};
        ohmd_device_getf(h->device, OHMD_ROTATION_QUAT, q);
        ohmd_device_getf(h->device, OHMD_POSITION_VECTOR, p);
        float len = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(len > 1e-6f)) { /* the Null devices report a zero quaternion */
            q[0] = q[1] = q[2] = 0.0f;
            q[3] = len = 1.0f;
        }
        /* The configured pose is the device's origin in the room. */
        versor qo, qd, qr;
        memcpy(qo, h->fixed.rotation, sizeof(qo));
        for (int i = 0; i < 4; i++)
            qd[i] = q[i] / len;
        glm_quat_mul(qo, qd, qr);
        vec3 pr;
        glm_quat_rotatev(qo, p, pr);
        for (int i = 0; i < 3; i++)
            out->position[i] = h->fixed.position[i] + pr[i];
        memcpy(out->rotation, qr, sizeof(qr));
        return true;
    }
    case DISPLAY_HEAD_DTRACK:
    case DISPLAY_HEAD_VRPN: {
        /* The latest pose, never waiting; until the first one the configured head. */
        struct tracker_sample smp;
        tracker_sample(h->tracker, &smp);
        if (!smp.seen) {
            *out = h->fixed;
            return true;
        }
        for (int i = 0; i < 3; i++)
            out->position[i] = (float)smp.position[i];
        for (int i = 0; i < 4; i++)
            out->rotation[i] = (float)smp.rotation[i];
        return true;
    }
    }
    return false;
}
