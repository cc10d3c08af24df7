/*
 * session/animation: the frames of an animation, drawn and written one after another: the time
 * series from one step to another (fractions of a step blend two with effects.temporal), or a
 * camera path flown at a frame rate.  Each frame goes through the session as any frame does
 * (update, apply, light, the head sampled last, draw) and then to the output.  Needs the
 * display's GL context current.
 */
#ifndef ANVIL_SESSION_ANIMATION_H
#define ANVIL_SESSION_ANIMATION_H

#include <stdbool.h>

#include "config/camera_path.h"
#include "display/display.h"
#include "session/output.h"
#include "session/session.h"

struct animation_desc {
    const struct camera_path *path; /* fly this (NULL: the time series) */
    double first, last; /* the series: the steps from FIRST to LAST; a path: its frames */
    double by;          /* the series: steps a frame */
    double fps;         /* a path: frames a second */
    double time;        /* the display's clock (a head path's time) */
};

/* Frames of D and S as A says, each written to OUT (NULL: drawn only).  False (logged) on
 * failure. */
bool animation_run(struct display *d, struct session *s, const struct animation_desc *a,
                   struct frame_output *out);

/* Sets S's time (and on a path its camera, BASE giving what the path leaves alone) for frame I
 * of A: what animation_run does before each frame. */
void animation_set_frame(struct session *s, const struct animation_desc *a, long i,
                         const struct display_camera *base);

/* How many frames A has. */
long animation_frames(const struct animation_desc *a);

#endif
