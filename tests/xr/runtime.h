/*
 * The test runtime's side door: what a test in the same process asks the runtime library
 * that the OpenXR loader loaded (dlopen the same file, then dlsym these names).  The runtime
 * itself is reached through the loader only (XR_RUNTIME_JSON names its manifest).
 *
 * Script lines (ANVIL_XR_TEST_SCRIPT names a file of them; anvil_xr_test_script adds more),
 * '#' starting a comment:
 *   size W H                      the recommended eye image size (default 96 80)
 *   fov left|right L R U D        an eye's field of view, degrees (default -45 45 45 -45)
 *   eye left|right X Y Z          an eye's position in the head, metres (default -+0.032 0 0)
 *   stage on|off                  whether the runtime has a STAGE space (default on)
 *   local X Y Z                   the LOCAL space's origin in the stage (default 0 1.6 0)
 *   profile PATH                  the controllers' interaction profile
 *                                 (default /interaction_profiles/khr/simple_controller)
 * and, from frame F on (F counts the xrWaitFrame calls from 0):
 *   F head X Y Z YAW PITCH ROLL   the head in the stage, metres and degrees (yaw about +y,
 *                                 then pitch about x, then roll about z)
 *   F aim left|right X Y Z TX TY TZ   a hand's aim pose at X Y Z pointing at TX TY TZ
 *   F input PATH V [V2]           an input component's value, e.g.
 *                                 /user/hand/right/input/trigger/value 1 (thumbsticks: x y)
 *   F exit                        the runtime asks the session to stop (then exits)
 *   F lose                        the session is lost (LOSS_PENDING)
 */
#ifndef ANVIL_TEST_XR_RUNTIME_H
#define ANVIL_TEST_XR_RUNTIME_H

#include <stdbool.h>
#include <stdint.h>

#define ANVIL_XR_TEST_FAULTS_KEPT 16

struct anvil_xr_test_report {
    long frames_waited, frames_begun, frames_ended, layers, syncs;
    int faults;                       /* calls the runtime found wrong */
    char fault[ANVIL_XR_TEST_FAULTS_KEPT][256];
    char binding[8];                  /* "egl", "xlib" or "" before a session */
    char layer_space[8];              /* the space of the last layer: "stage", "local", ... */
    char states[512];                 /* every state the session entered, in order */
    char profile[128];                /* the profile the app suggested bindings for, or "" */
    float pose_error;                 /* the largest distance (m) between a layer view's
                                         position and the eye's, from the runtime's poses */
    float layer_pose[2][7];           /* the last layer's eye poses (x y z qx qy qz qw) */
    float layer_fov[2][4];            /* and fields of view (left right up down, radians) */
    float located_head[7];            /* the head pose located last, in the app's space */
};

/* anvil_xr_test_reset: forgets the script, the report and the images (between instances
 * only), then takes TEXT (may be NULL) as the whole script; anvil_xr_test_script adds lines. */
typedef bool (*anvil_xr_test_reset_fn)(const char *text);
typedef bool (*anvil_xr_test_script_fn)(const char *text);
typedef void (*anvil_xr_test_get_report_fn)(struct anvil_xr_test_report *out);
/* The last image submitted for EYE (0 left, 1 right): W x H RGBA8 as stored (sRGB-encoded),
 * row 0 at the bottom; NULL before any. */
typedef const uint8_t *(*anvil_xr_test_image_fn)(int eye, int *w, int *h);

#endif
