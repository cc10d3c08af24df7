/*
 * The trackers of a display config as an engineer checks them (anvil trackers): the head and
 * the wand in room coordinates after calibration, how often their poses come, the frames
 * that did not track them, the wand's buttons and stick, and per link the frames, dropped
 * frames, refused input and the ids in the stream.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "display/display.h"

struct watched {
    const char *what;
    struct tracker *tracker;
    int buttons[INPUT_BUTTON_COUNT]; /* the wand's map */
    int axes[INPUT_AXIS_COUNT];
    double axis_scale[INPUT_AXIS_COUNT];
    uint64_t poses_before;
    double before_s;
};

struct display_trackers {
    struct watched items[2];
    int count;
    uint64_t frames_before[2];
    double links_before_s;
};

struct display_trackers *display_trackers_open(const struct display_config *cfg)
{
    struct display_trackers *t = calloc(1, sizeof(*t));
    if (!t) {
        log_error("out of memory");
        return NULL;
    }
    bool head = cfg->head.source == DISPLAY_HEAD_DTRACK || cfg->head.source == DISPLAY_HEAD_VRPN;
    bool wand = cfg->wand.source == DISPLAY_WAND_DTRACK || cfg->wand.source == DISPLAY_WAND_VRPN;
    if (!head && !wand) {
        log_error("%s: neither head.source (\"%s\") nor wand.source (\"%s\") is a tracker "
                  "(dtrack or vrpn)",
                  cfg->path, display_head_source_name(cfg->head.source),
                  display_wand_source_name(cfg->wand.source));
        free(t);
        return NULL;
    }
    if (head) {
        struct tracker_desc d;
        display_head_desc(cfg, &d);
        struct watched *w = &t->items[t->count++];
        w->what = "head";
        w->tracker = tracker_open(&d);
        if (!w->tracker)
            goto error;
        for (int b = 0; b < INPUT_BUTTON_COUNT; b++)
            w->buttons[b] = -1;
        w->axes[0] = w->axes[1] = -1;
    }
    if (wand) {
        struct tracker_wand_desc d;
        display_wand_desc(cfg, &d);
        struct watched *w = &t->items[t->count++];
        w->what = "wand";
        w->tracker = tracker_open(&d.tracker);
        if (!w->tracker)
            goto error;
        memcpy(w->buttons, d.buttons, sizeof(w->buttons));
        memcpy(w->axes, d.axes, sizeof(w->axes));
        memcpy(w->axis_scale, d.axis_scale, sizeof(w->axis_scale));
    }
    return t;

error:
    display_trackers_close(t);
    return NULL;
}

void display_trackers_close(struct display_trackers *t)
{
    if (!t)
        return;
    for (int i = 0; i < t->count; i++)
        tracker_close(t->items[i].tracker);
    free(t);
}

/* Heading, pitch, roll (degrees) of a unit quaternion, the inverse of
 * display_pose_from_euler: forward = (-cos p sin h, sin p, -cos p cos h), then the roll that
 * remains about the head's own z. */
static void euler_of(const double q[4], double hpr[3])
{
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double f[3] = {-2.0 * (x * z + w * y), -2.0 * (y * z - w * x), -(1.0 - 2.0 * (x * x + y * y))};
    double h = atan2(-f[0], -f[2]);
    double p = asin(fmax(-1.0, fmin(1.0, f[1])));
    /* qr = conj(qh qp) q */
    double ch = cos(h / 2), sh = sin(h / 2), cp = cos(p / 2), sp = sin(p / 2);
    double a[4] = {ch * sp, sh * cp, -sh * sp, ch * cp}; /* qh qp (x, y, z, w) */
    double ca[4] = {-a[0], -a[1], -a[2], a[3]};
    double r[4] = {
        ca[3] * x + ca[0] * w + ca[1] * z - ca[2] * y,
        ca[3] * y - ca[0] * z + ca[1] * w + ca[2] * x,
        ca[3] * z + ca[0] * y - ca[1] * x + ca[2] * w,
        ca[3] * w - ca[0] * x - ca[1] * y - ca[2] * z,
    };
    double roll = 2.0 * atan2(r[2], r[3]);
    if (roll > M_PI)
        roll -= 2.0 * M_PI;
    if (roll < -M_PI)
        roll += 2.0 * M_PI;
    hpr[0] = h * 180.0 / M_PI;
    hpr[1] = p * 180.0 / M_PI;
    hpr[2] = roll * 180.0 / M_PI;
    for (int i = 0; i < 3; i++)
        hpr[i] = fabs(hpr[i]) < 0.05 ? 0.0 : hpr[i]; /* no "-0.0" */
}

static void report_one(struct watched *w, double now_s, FILE *out)
{
    struct tracker_sample s;
    tracker_sample(w->tracker, &s);
    double rate =
        now_s > w->before_s ? (double)(s.poses - w->poses_before) / (now_s - w->before_s) : 0.0;
    w->poses_before = s.poses;
    w->before_s = now_s;
    fprintf(out, "  %s  %s: ", w->what, tracker_describe(w->tracker));
    if (!s.seen) {
        fprintf(out, "no pose yet\n");
        return;
    }
    double hpr[3];
    euler_of(s.rotation, hpr);
    fprintf(out,
            "%s  x %.3f y %.3f z %.3f m  heading %.1f pitch %.1f roll %.1f deg  %.0f Hz  "
            "untracked %llu frames",
            s.tracked ? "tracked" : "NOT TRACKED (last pose)", s.position[0], s.position[1],
            s.position[2], hpr[0], hpr[1], hpr[2], rate, (unsigned long long)s.untracked);
    if (w->buttons[0] >= 0 || w->buttons[1] >= 0 || w->buttons[2] >= 0 || w->buttons[3] >= 0) {
        fprintf(out, "  buttons");
        int shown = 0;
        for (int b = 0; b < INPUT_BUTTON_COUNT; b++) {
            int i = w->buttons[b];
            if (i >= 0 && i < s.button_count && s.buttons[i]) {
                fprintf(out, " %s", input_button_name((enum input_button)b));
                shown++;
            }
        }
        int raw = 0;
        for (int i = 0; i < s.button_count; i++)
            raw += s.buttons[i];
        fprintf(out, "%s (pressed:", shown ? "" : " none");
        for (int i = 0; i < s.button_count; i++) {
            if (s.buttons[i])
                fprintf(out, " %d", i);
        }
        fprintf(out, "%s)", raw ? "" : " none");
    }
    const char *names[INPUT_AXIS_COUNT] = {"fly", "turn"};
    for (int a = 0; a < INPUT_AXIS_COUNT; a++) {
        int i = w->axes[a];
        if (i >= 0)
            fprintf(out, "  %s %.2f", names[a],
                    i < s.axis_count ? s.axes[i] * w->axis_scale[a] : 0.0);
    }
    fprintf(out, "\n");
}

void display_trackers_report(struct display_trackers *t, double now_s, FILE *out)
{
    fprintf(out, "%.1f s\n", now_s);
    for (int i = 0; i < t->count; i++)
        report_one(&t->items[i], now_s, out);
    /* Each link once. */
    char names[2][TRACKER_HOST_MAX + 32] = {"", ""};
    for (int i = 0; i < t->count; i++) {
        struct tracker_link_stats st;
        tracker_link_stats(t->items[i].tracker, &st);
        if (i == 1 && strcmp(st.name, names[0]) == 0)
            continue;
        snprintf(names[i], sizeof(names[i]), "%s", st.name);
        double rate = now_s > t->links_before_s
                          ? (double)(st.frames - t->frames_before[i]) / (now_s - t->links_before_s)
                          : 0.0;
        t->frames_before[i] = st.frames;
        fprintf(out, "  link  %s: %s, %.0f %s/s, %llu in all, %llu dropped, %llu malformed",
                st.name, st.connected ? "receiving" : "nothing arriving", rate,
                strncmp(st.name, "VRPN", 4) == 0 ? "messages" : "frames",
                (unsigned long long)st.frames, (unsigned long long)st.dropped,
                (unsigned long long)st.malformed);
        if (st.connects)
            fprintf(out, ", %llu connections", (unsigned long long)st.connects);
        fprintf(out, "; seen: %s\n", st.seen[0] ? st.seen : "nothing");
    }
    t->links_before_s = now_s;
    fflush(out);
}
