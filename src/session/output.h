/*
 * session/output: where the frames of an animation go.  Either a numbered image sequence (a
 * name with one printf-style integer, "out/frame-%05d.png" or .pfm) or a movie (render/video.h:
 * "storm.mp4").  A display with several views writes one sequence per view, its name in front
 * of an image's ("out/front-left-frame-00000.png") or after a movie's ("cave-front-left.mp4"),
 * or where the name says "%v", and for each stereo wall a side-by-side sequence of its two
 * eyes ("cave-front.mp4").  Reads the views back from the GPU after each frame (the GL context of
 * the display current).
 */
#ifndef ANVIL_SESSION_OUTPUT_H
#define ANVIL_SESSION_OUTPUT_H

#include <stdbool.h>

#include "display/display.h"

struct frame_output_desc {
    const char *path;  /* an image sequence pattern or a movie */
    int fps;           /* movies: frames per second */
    const char *codec; /* movies: an FFmpeg encoder (NULL: H.264 where there is one) */
    float exposure;    /* of the tone mapping (PNG, movies) */
    bool per_view;     /* a display of several views (else the one view, under PATH itself) */
};

/* Checks PATH before any work is done: an image sequence name with exactly one integer
 * conversion ("%d", "%05d") and .png or .pfm, or a movie name; its folder exists.  False with
 * one message saying what was expected. */
bool frame_output_check(const char *path);
/* Whether PATH's folder exists (else logged). */
bool frame_output_folder_exists(const char *path);

struct frame_output;

struct frame_output *frame_output_open(const struct frame_output_desc *d);
/* Writes frame NUMBER of D's views.  False (logged) on failure. */
bool frame_output_add(struct frame_output *o, struct display *d, int number);
/* Finishes the movies (renamed into place).  False (logged) on failure.  Frees O. */
bool frame_output_close(struct frame_output *o);
/* Drops unfinished movies; NULL is fine. */
void frame_output_abort(struct frame_output *o);
/* Frames written so far. */
int frame_output_frames(const struct frame_output *o);

#endif
