/*
 * app/loop: the one frame loop.  anvil render (a still picture, a scripted session, a display's
 * views, an animation) and anvil run (a window, a CAVE's walls, an HMD) all go through it:
 *
 *   poll the display's input -> session_update (input, menu, setters, playback: the frame
 *   state) -> session_apply (volumes) -> session_light (the light map, only when stale) ->
 *   display_sample_head (the head pose, sampled last) -> session_draw (every view) -> present
 *   [-> the frame written: an animation] [-> the recording (--record: the frame's events,
 *   clock, head and cursor)]
 */
#ifndef ANVIL_APP_LOOP_H
#define ANVIL_APP_LOOP_H

#include <stdbool.h>

#include "config/camera_path.h"
#include "display/display.h"
#include "session/output.h"
#include "session/session.h"

/* What the frames of a render are. */
enum loop_frames {
    LOOP_STILL,  /* the script's frames (if any), then the settled picture: one is written */
    LOOP_SCRIPT, /* every frame of the script, FIRST..LAST */
    LOOP_STEPS,  /* the time series from step FIRST to LAST, BY steps a frame */
    LOOP_PATH,   /* the camera path at FPS frames a second, frames FIRST..LAST */
};

struct loop_desc {
    bool run;     /* until the user quits (a window); else render */
    double time;  /* the display's clock at the first frame (--time), seconds */
    long frames;  /* run: stop after this many frames, each drawn (-1: until quit) */
    /* render: */
    enum loop_frames kind;
    double first, last, by;
    const struct camera_path *path;
    double fps;
    struct frame_output *output; /* every frame of an animation goes here */
    /* run: where screenshots and bookmarks go ("" the working folder), and the files the
     * bookmarks include (the scene's config; the display's, on a tracked display). */
    const char *config_path, *display_path;
    bool data_from_args; /* the scene's data came as arguments: a bookmark names them */
    bool check_sync; /* a cluster: every frame, every rank's frame checked against rank 0's */
    struct input_recorder *recorder; /* --record: every frame goes there (NULL: none) */
};

/* Runs frames of S on D as LD says.  Returns an exit code of app/app.h. */
int loop_run(struct display *d, struct session *s, const struct loop_desc *ld);

#endif
