/* The one frame loop of anvil render and anvil run. */
#include "app/loop.h"

#include <stdlib.h>

#include "app/app.h"
#include "common/log.h"

/* A script names frames up to INPUT_SCRIPT_FRAMES_MAX; playing it may take a little more. */
#define SCRIPT_FRAMES_MAX (INPUT_SCRIPT_FRAMES_MAX + 100000)

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

/* The frame state -> the GPU -> the light map -> the head, sampled last -> every view. */
static bool draw(struct display *d, struct session *s, struct frame_state *f)
{
    return session_light(s) && display_sample_head(d, f->time_s, &f->head) &&
           session_draw(s, d, f);
}

/* One frame of a render: every frame is drawn, the script's clock stands still. */
static bool render_frame(struct display *d, struct session *s, double dt, double time)
{
    struct frame_state f;
    bool redraw;
    return session_update(s, NULL, dt, time, &f, &redraw) && session_apply(s, &f, NULL) &&
           draw(d, s, &f);
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
            if (!render_frame(d, s, frame_dt(s, &last), ld->time))
                return EXIT_FAILED;
        }
        if (!session_settle(s) || !render_frame(d, s, 0.0, ld->time))
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
        idle = !drawn;
    }
    free(events);
    return rc;
}
