/* The one frame loop of anvil render and anvil run. */
#include "app/loop.h"

#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "common/log.h"

#define SCRIPT_FRAMES_MAX 1000000

/* Seconds since the last call (or the script's frame time); the longest frame for --stats. */
static double frame_dt(struct session *s, double *last_ms)
{
    double now = time_now_ms(), dt = (now - *last_ms) * 1e-3;
    *last_ms = now;
    struct session_stats *st = session_stats(s);
    if (st->frame_ms_max < dt * 1e3 && st->frames > 1)
        st->frame_ms_max = dt * 1e3;
    double script = session_script_dt(s);
    return script > 0.0 ? script : dt;
}

/* The frame state -> the GPU -> the light map -> the head, sampled last (unless a recording
 * gave it) -> every view. */
static bool draw(struct display *d, struct session *s, struct frame_state *f)
{
    return session_light(s) &&
           (session_head_given(s) || display_sample_head(d, f->time_s, &f->head)) &&
           session_draw(s, d, f);
}

/* --record: the frame's events, clock, head (when drawn, and only a head that moves: a fixed
 * one is the display's) and cursor. */
static void record(const struct loop_desc *ld, struct display *d, const struct session *s,
                   const struct frame_state *f, bool drawn)
{
    if (!ld->recorder)
        return;
    struct input_record_frame r = {
        .frame = (long)f->frame,
        .time_s = f->time_s,
        .dt_s = f->dt_s,
        .have_head = drawn && (display_head_moves(d) || session_head_given(s)),
    };
    memcpy(r.head_position, f->head.position, sizeof(r.head_position));
    memcpy(r.head_rotation, f->head.rotation, sizeof(r.head_rotation));
    session_cursor(s, &r.step, &r.step_acc, &r.playing);
    input_recorder_frame(ld->recorder, &r, session_events(s));
}

/* One frame of a render: every frame is drawn, the script's clock stands still. */
static bool render_frame(struct display *d, struct session *s, const struct loop_desc *ld,
                         double dt, double time)
{
    struct frame_state f;
    bool redraw;
    if (!session_update(s, NULL, dt, time, &f, &redraw) || !session_apply(s, &f, NULL) ||
        !draw(d, s, &f))
        return false;
    record(ld, d, s, &f, true);
    return true;
}

int loop_run(struct display *d, struct session *s, const struct loop_desc *ld)
{
    double t0 = time_now_ms(), last = t0;
    if (!ld->run) {
        /* A script's frames, each drawn; then the settled result. */
        for (long n = 0; !session_script_done(s); n++) {
            if (n > SCRIPT_FRAMES_MAX) {
                log_error("the script has not ended after %d frames", SCRIPT_FRAMES_MAX);
                return EXIT_FAILED;
            }
            if (!render_frame(d, s, ld, frame_dt(s, &last), ld->time))
                return EXIT_FAILED;
        }
        if (!session_settle(s) || !render_frame(d, s, ld, 0.0, ld->time))
            return EXIT_FAILED;
        return EXIT_OK;
    }

    bool moving = display_head_moves(d), dirty = true, idle = false;
    long frames_left = ld->frames;
    struct input_queue *events = malloc(sizeof(*events));
    if (!events) {
        log_error("out of memory");
        return EXIT_FAILED;
    }
    int rc = EXIT_OK;
    while (!session_quit_requested(s) && !display_should_close(d) && frames_left != 0) {
        input_queue_clear(events);
        display_poll_input(d, idle ? 0.03 : 0.0, events);
        double dt = frame_dt(s, &last);
        double time = ld->time + (time_now_ms() - t0) * 1e-3;
        struct frame_state f;
        bool redraw = false, changed = false;
        if (!session_update(s, events, dt, time, &f, &redraw) || !session_apply(s, &f, &changed)) {
            rc = EXIT_FAILED;
            break;
        }
        bool drawn = dirty || redraw || changed || moving || frames_left > 0;
        if (drawn) {
            if (!draw(d, s, &f)) {
                rc = EXIT_FAILED;
                break;
            }
            dirty = false;
            if (frames_left > 0)
                frames_left--;
        }
        record(ld, d, s, &f, drawn);
        idle = !drawn;
    }
    free(events);
    return rc;
}
