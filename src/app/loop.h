/*
 * app/loop: the one frame loop.  anvil render (a still picture, a scripted session, a display's
 * views) and anvil run (a window, a CAVE's walls, an HMD) all go through it:
 *
 *   poll the display's input -> session_update (input, menu, setters, playback: the frame
 *   state) -> session_apply (volumes) -> session_light (the light map, only when stale) ->
 *   display_sample_head (the head pose, sampled last) -> session_draw (every view) -> present
 *   -> the recording (--record: the frame's events, clock, head and cursor)
 */
#ifndef ANVIL_APP_LOOP_H
#define ANVIL_APP_LOOP_H

#include <stdbool.h>

#include "display/display.h"
#include "session/session.h"

struct loop_desc {
    bool run;     /* until the user quits (a window); else render: the script's frames, then
                     the settled picture */
    double time;  /* the display's clock at the first frame (--time), seconds */
    long frames;  /* run: stop after this many frames, each drawn (-1: until quit) */
    struct input_recorder *recorder; /* --record: every frame goes there (NULL: none) */
};

/* Runs frames of S on D as LD says.  Returns an exit code of app/app.h. */
int loop_run(struct display *d, struct session *s, const struct loop_desc *ld);

#endif
