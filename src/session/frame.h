/*
 * session/frame: the frame state.  One fixed-size, plain-data struct holding everything a
 * frame's picture depends on that can change between frames: the head and wand poses, the
 * navigation transform and the orbit camera, the time cursor and the playback fraction, the
 * sun, whether the menu shows, the revision of the look and quality settings, and the point
 * the probe reads.  Input
 * produces one per frame (session_update), drawing consumes it (session_apply, session_draw);
 * it travels as bytes (what a cluster broadcasts, what a recording stores).  No GL.
 */
#ifndef ANVIL_SESSION_FRAME_H
#define ANVIL_SESSION_FRAME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "display/display.h"

/* Bytes of a written frame state (frame_state_write), whatever the platform. */
#define FRAME_STATE_BYTES 384

struct frame_state {
    uint64_t frame;                 /* counted from 0 */
    double time_s;                  /* the display's clock: a head path's time */
    double dt_s;                    /* since the previous frame (a script: 1 / fps) */
    struct display_pose head;       /* tracker metres (sampled last: display_sample_head) */
    struct display_navigation nav;  /* world -> tracker (tracked displays) */
    struct display_camera camera;   /* the orbit display's world camera */
    bool wand_valid;                /* the wand's ray, in menu space */
    float wand_position[3], wand_direction[3];
    int32_t time_step;              /* the time step the cursor is on */
    float step_fraction;            /* effects.temporal: how far toward the next step, [0, 1] */
    bool playing;
    double sun_azimuth_deg, sun_elevation_deg;
    bool menu_visible;
    uint32_t settings_revision;     /* of the look and quality settings (session_settings) */
    bool probe_valid;               /* the probe reads the point below (docs/analysis.md) */
    double probe_point[3];          /* world metres: picked on rank 0 along the wand's ray */
};

/* Writes F into BUF (at least FRAME_STATE_BYTES): little-endian, with a magic number and a
 * version.  Returns the bytes written, FRAME_STATE_BYTES. */
size_t frame_state_write(const struct frame_state *f, uint8_t buf[FRAME_STATE_BYTES]);

/* Reads a frame state written by frame_state_write from LEN bytes.  False (logged) when the
 * bytes are not one: wrong length, magic or version, a number that is not finite, a pose's
 * rotation that is not a unit quaternion, a step fraction outside [0, 1]. */
bool frame_state_read(const uint8_t *buf, size_t len, struct frame_state *out);

#endif
