/*
 * render/camera: camera matrices in the world frame (metres, z up) and an orbiting camera for
 * the desktop window.  Pure math, no GL.
 */
#ifndef ANVIL_RENDER_CAMERA_H
#define ANVIL_RENDER_CAMERA_H

#include <stdbool.h>

#include "render/render.h"

/* Fills VIEW's matrices for a pinhole camera at EYE looking at TARGET (metres), vertical field
 * of view FOV_DEG, NEAR/FAR in metres, image WIDTH x HEIGHT. */
void camera_look_at(const double eye[3], const double target[3], const double up[3],
                    double fov_deg, double near_m, double far_m, int width, int height,
                    struct render_view *view);

/* An orbit around a target: azimuth (degrees clockwise from north, like the sun), elevation
 * and distance. */
struct camera_orbit {
    double target[3];
    double azimuth_deg, elevation_deg, distance_m;
};

/* The orbit that puts the eye at EYE looking at TARGET. */
void camera_orbit_from(const double eye[3], const double target[3], struct camera_orbit *o);
void camera_orbit_eye(const struct camera_orbit *o, double eye[3]);

/* Unit vector toward a direction given by azimuth (clockwise from north) and elevation. */
void camera_direction(double azimuth_deg, double elevation_deg, double out[3]);

#endif
