/*
 * session/camera_path: flying a camera path (config/camera_path.h) in time.  Positions follow
 * a Catmull-Rom spline through the keys, parameterised by the keys' own times (the non-uniform
 * form of Barry and Goldman's recursive construction, SIGGRAPH 1988), so the camera is at each
 * key exactly at its time; the view's orientation turns by spherical linear interpolation
 * between the keys' (Shoemake, SIGGRAPH 1985); the distance to the target, the field of view
 * and the data's time step go linearly.  Before the first key and after the last the camera
 * holds.  Pure math, no GL.
 */
#ifndef ANVIL_SESSION_CAMERA_PATH_H
#define ANVIL_SESSION_CAMERA_PATH_H

#include "config/camera_path.h"
#include "display/display.h"

/* The camera at T seconds (metres, as display_camera), near and far from BASE; *STEP (may be
 * NULL) the time step there when the path has steps, else left alone. */
void camera_path_eval(const struct camera_path *p, double t, const struct display_camera *base,
                      struct display_camera *out, double *step);

/* The path's length in seconds (its last key's time). */
double camera_path_duration(const struct camera_path *p);

/* A key for CAMERA (metres) at T seconds, with time step STEP. */
void camera_path_key(const struct display_camera *camera, double t, double step,
                     struct camera_key *out);

#endif
