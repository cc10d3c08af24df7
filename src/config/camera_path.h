/*
 * config/camera_path: camera paths (key views) as libconfig files,
 *
 *   camera_path = {
 *       keys = (
 *           { time = 0.0; position = [2.0, -14.0, 4.0]; target = [30.0, 30.0, 7.0];
 *             up = [0.0, 0.0, 1.0]; fov = 50.0; },
 *           { time = 6.0; position = [...]; target = [...]; step = 2.5; },
 *       );
 *   };
 *
 * time: seconds into the path, increasing; position, target: km, as camera.*; up (default
 * [0, 0, 1]) and fov (default 50 degrees) as camera.*; step (optional, on every key or none):
 * the data's time step there, fractions blending steps.  Reading checks everything and fills
 * the caller's struct only when the whole file is valid; saving is atomic.  How a path is
 * flown between its keys is session/camera_path.h's.
 */
#ifndef ANVIL_CONFIG_CAMERA_PATH_H
#define ANVIL_CONFIG_CAMERA_PATH_H

#include <stdbool.h>

#define CAMERA_PATH_MAX 256

struct camera_key {
    double time_s;
    double position_km[3], target_km[3], up[3];
    double fov_deg;
    double step; /* the data's time step (has_steps) */
};

struct camera_path {
    int count;
    bool has_steps; /* every key names a time step */
    struct camera_key keys[CAMERA_PATH_MAX];
};

/* Reads PATH into OUT.  On failure logs one message "FILE:LINE: SETTING: expected ..." and
 * returns false with OUT untouched. */
bool camera_path_load(const char *path, struct camera_path *out);
/* Writes P to PATH atomically.  False (logged) on failure; the old file is kept. */
bool camera_path_save(const char *path, const struct camera_path *p);

#endif
