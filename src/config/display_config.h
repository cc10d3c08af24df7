/*
 * config/display_config: display files (displays/NAME.cfg, libconfig syntax) and their --set
 * overrides to one plain struct, through the same settings engine as scene files: which
 * display backend, its walls (three corners each in tracker space, the outputs they show on),
 * the stereo mode, the head and where it comes from (fixed, a path, OpenHMD, a DTrack or VRPN
 * tracker and its calibration into the room), the wand, the navigation transform that places
 * the storm in the room, and the HMD's device and lens.  Knows nothing about GL, windows or OpenHMD;
 * src/display/ turns this struct into views.
 *
 * Tracker space: metres, x to the right, y up, z toward the viewer (the OpenGL and OpenHMD
 * convention), so a viewer facing the front wall looks along -z.  World space (the scene): x
 * east, y north, z up, metres; the navigation transform maps world to tracker.
 */
#ifndef ANVIL_DISPLAY_CONFIG_H
#define ANVIL_DISPLAY_CONFIG_H

#include <stdbool.h>
#include <stdio.h>

#include "config/config.h"

#define DISPLAY_MAX_WALLS 8
#define DISPLAY_NAME_MAX 32

/* The display backends (src/display/display.c holds the table with the same names). */
enum display_type {
    DISPLAY_TYPE_HEADLESS, /* "headless": offscreen views only */
    DISPLAY_TYPE_DESKTOP,  /* "desktop": one mono window */
    DISPLAY_TYPE_STEREO,   /* "stereo": one window, side-by-side / anaglyph / quad-buffer */
    DISPLAY_TYPE_CAVE,     /* "cave": one window per wall, or viewports of one window */
    DISPLAY_TYPE_HMD,      /* "hmd": OpenHMD device, per-eye views and lens warp */
    DISPLAY_TYPE_ORBIT,    /* "orbit": the scene's own camera in one window (anvil run and
                              render without --display) */
    DISPLAY_TYPE_OPENXR,   /* "openxr": a headset through an OpenXR runtime (built with the
                              OpenXR loader only: display_type_available) */
};

enum display_stereo {
    DISPLAY_STEREO_MONO,         /* "mono": one view from the centre of the head */
    DISPLAY_STEREO_SIDE_BY_SIDE, /* "side-by-side": left eye in the left half */
    DISPLAY_STEREO_ANAGLYPH,     /* "anaglyph": red (left) / cyan (right) */
    DISPLAY_STEREO_QUAD_BUFFER,  /* "quad-buffer": GL back-left / back-right (active stereo) */
    DISPLAY_STEREO_PASSIVE,      /* "passive": each eye in its own window on its own output
                                    (two projectors per wall, polarised or filtered) */
};

enum display_head_source {
    DISPLAY_HEAD_FIXED,   /* "fixed": head.position, head.orientation */
    DISPLAY_HEAD_PATH,    /* "path": a file of timed poses, linearly interpolated */
    DISPLAY_HEAD_OPENHMD, /* "openhmd": the pose of an OpenHMD device (head.device) */
    DISPLAY_HEAD_DTRACK,  /* "dtrack": a body in ART DTrack's UDP output (head.address) */
    DISPLAY_HEAD_VRPN,    /* "vrpn": a sensor of a VRPN tracker (head.address) */
};

/* ---- tracked heads and wands (head.*, wand.*) ------------------------------------------ */

enum display_wand_source {
    DISPLAY_WAND_NONE,    /* "none": no wand (the mouse in a window still points) */
    DISPLAY_WAND_OPENHMD, /* "openhmd": an OpenHMD controller (wand.device) */
    DISPLAY_WAND_DTRACK,  /* "dtrack": a Flystick or body in ART DTrack's output */
    DISPLAY_WAND_VRPN,    /* "vrpn": a VRPN tracker sensor, with its buttons and analogs */
};

enum display_units {
    DISPLAY_UNITS_AUTO, /* "auto": the protocol's own (DTrack: mm, VRPN: m) */
    DISPLAY_UNITS_M,    /* "m" */
    DISPLAY_UNITS_CM,   /* "cm" */
    DISPLAY_UNITS_MM,   /* "mm" */
};

#define DISPLAY_ADDRESS_MAX 128
#define DISPLAY_DEVICE_MAX 64

/* Where a tracked thing comes from and how tracker coordinates become the room's: the same
 * settings in head.* and wand.*.  Calibration: p_room = offset + R (A (units p)), A the axis
 * map (room x, y, z as signed tracker axes), R the rotation (heading, pitch, roll). */
struct display_tracking {
    char address[DISPLAY_ADDRESS_MAX]; /* ADDRESS: dtrack "PORT" or "HOST:PORT" (a multicast
                                          group or a local address); vrpn "Device@host[:port]" */
    int sensor;                        /* SENSOR: DTrack id (its GUI's number minus one) or
                                          VRPN sensor */
    enum display_units units;          /* UNITS */
    char axes[16];                     /* AXES: "x y z", "x z -y", ... */
    double offset[3];                  /* OFFSET: room metres */
    double rotation_deg[3];            /* ROTATION: heading, pitch, roll, degrees */
    /* Derived by display_config_validate from ADDRESS and AXES: */
    char host[DISPLAY_ADDRESS_MAX];    /* "" (dtrack: every local address) */
    int port;
    char device[DISPLAY_DEVICE_MAX];   /* vrpn: the device name before '@' */
    int axis_map[3];                   /* room axis i = sign * tracker axis |axis_map[i]| - 1 */
};

struct display_wand {
    enum display_wand_source source;   /* wand.source */
    char device[128];                  /* wand.device: OpenHMD controller (source = openhmd) */
    struct display_tracking tracking;  /* wand.address, sensor, units, axes, offset, rotation */
    bool flystick;                     /* wand.flystick: dtrack: a Flystick (6df2), else a
                                          body (6d) */
    char controls[DISPLAY_ADDRESS_MAX]; /* wand.controls: vrpn "Device@host[:port]" of the
                                          buttons and analogs; "" = the tracker's device */
    char controls_host[DISPLAY_ADDRESS_MAX]; /* derived from wand.controls */
    int controls_port;
    char controls_device[DISPLAY_DEVICE_MAX];
    int buttons[4];                    /* wand.buttons: device buttons of trigger, grab, menu,
                                          reset (-1: none) */
    int joystick[2];                   /* wand.joystick: analog channels of fly and turn */
    double joystick_scale[2];          /* wand.joystick_scale */
    double dead_zone;                  /* wand.dead_zone */
};

struct display_wall {
    char name[DISPLAY_NAME_MAX];  /* walls.[i].name: used in file names ("front") */
    double lower_left[3];         /* walls.[i].lower_left: tracker metres */
    double lower_right[3];        /* walls.[i].lower_right */
    double upper_left[3];         /* walls.[i].upper_left */
    int monitor;                  /* walls.[i].monitor: fullscreen on this monitor; -1 = window */
    char output[DISPLAY_DEVICE_MAX]; /* walls.[i].output: fullscreen on the output of this name
                                     (GLFW's monitor name, e.g. "DP-1"); "" = by monitor */
    char right_output[DISPLAY_DEVICE_MAX]; /* walls.[i].right_output: passive stereo: the right
                                     eye's output (the left eye's is output) */
    int window[4];                /* walls.[i].window: [x, y, w, h] on the desktop: fullscreen
                                     on the output exactly there, else a borderless window */
    int right_window[4];          /* walls.[i].right_window: passive stereo, the right eye */
    bool window_set, right_window_set;
    int viewport[4];              /* walls.[i].viewport: [x, y, w, h] in the shared window;
                                     w = 0: the wall has its own window */
    int size[2];                  /* walls.[i].size: image pixels; 0 = from render.height and
                                     the wall's aspect ratio */
    enum display_stereo stereo;   /* walls.[i].mode; without it display.mode (set by
                                     display_config_validate) */
    bool stereo_set;              /* walls.[i].mode given: the wall keeps its own mode */
    bool viewport_set;            /* walls.[i].viewport given */
    int rank;                     /* walls.[i].rank: the rank that draws it under mpirun; -1 =
                                     wall i on rank i mod the ranks */
    int line;                     /* line of the wall's group in the file (for messages) */
};

struct display_head {
    enum display_head_source source; /* head.source */
    double position[3];              /* head.position: tracker metres (openhmd: added to the
                                        device's position) */
    double orientation_deg[3];       /* head.orientation: heading, pitch, roll, degrees */
    char path[CONFIG_PATH_MAX];      /* head.path: pose file, resolved against the config */
    char device[128];                /* head.device: OpenHMD product name, or "null" */
    struct display_tracking tracking; /* head.address, sensor, units, axes, offset, rotation
                                        (source = dtrack, vrpn; until the first pose the head
                                        is at head.position and head.orientation) */
};

struct display_navigation {
    double scale;              /* navigation.scale: tracker metres per world metre */
    double origin_km[3];       /* navigation.origin: world point (km) placed at position */
    double position[3];        /* navigation.position: tracker metres */
    double orientation_deg[3]; /* navigation.orientation: heading, pitch, roll, degrees */
    bool given;                /* a navigation.* setting was given; else a tracked display
                                  (cave, hmd, openxr) fits the domain to its room */
};

struct display_hmd {
    char device[128];        /* hmd.device: OpenHMD product name (substring), or "null" */
    bool distortion_set;     /* hmd.distortion given: it replaces the device's */
    bool aberration_set;     /* hmd.aberration given: it replaces the device's */
    double distortion[4];    /* hmd.distortion: PanoTools [a, b, c, d] (OpenHMD's
                                UNIVERSAL_DISTORTION_K) */
    double aberration[3];    /* hmd.aberration: per-channel scale (UNIVERSAL_ABERRATION_K) */
    bool warp;               /* hmd.warp: apply the lens distortion pass */
};

/* OpenXR (display.type = "openxr"). */
enum display_openxr_binding {
    DISPLAY_OPENXR_BINDING_AUTO, /* "auto": xlib with an X display ($DISPLAY), else egl */
    DISPLAY_OPENXR_BINDING_EGL,  /* "egl": a headless EGL context (XR_MNDX_egl_enable) */
    DISPLAY_OPENXR_BINDING_XLIB, /* "xlib": a GLX window (XrGraphicsBindingOpenGLXlibKHR) */
};

enum display_openxr_space {
    DISPLAY_OPENXR_SPACE_AUTO,  /* "auto": stage when the runtime has one, else local */
    DISPLAY_OPENXR_SPACE_STAGE, /* "stage": the room's floor (the runtime must have it) */
    DISPLAY_OPENXR_SPACE_LOCAL, /* "local": where the head was at the start, placed at
                                   head.position in the room */
};

struct display_openxr {
    enum display_openxr_binding binding; /* openxr.binding */
    enum display_openxr_space space;     /* openxr.space */
    double resolution_scale;             /* openxr.resolution_scale: of the runtime's
                                            recommended eye image size */
};

struct display_config {
    char path[CONFIG_PATH_MAX];        /* the file it came from */
    enum display_type type;            /* display.type */
    enum display_stereo stereo;        /* display.mode: default stereo mode of the walls */
    double eye_separation;             /* display.eye_separation: metres */
    double near_m, far_m;              /* display.near, display.far: tracker metres */
    int window_size[2];                /* display.window_size: the shared window (viewports,
                                          desktop), pixels */
    int monitor;                       /* display.monitor: of the shared window; -1 = window */
    struct display_head head;
    struct display_navigation navigation;
    struct display_hmd hmd;
    struct display_openxr openxr;
    struct display_wand wand;
    struct display_wall walls[DISPLAY_MAX_WALLS];
    int wall_count;
    int room_wall_count; /* the whole display's walls when WALLS holds one rank's
                            (display_config_walls_of_rank); 0: WALLS is the whole display */
};

/* Fills every setting with its default: a desktop mono window 0.52 x 0.32 m seen from 0.6 m,
 * the storm 60 km wide shown 0.6 m wide behind the screen. */
void display_config_defaults(struct display_config *cfg);

/* Reads PATH on top of the defaults (@include resolved relative to the including file; a
 * file with walls replaces the default wall list) and validates it (display_config_validate).
 * On failure logs one message "FILE:LINE: SETTING: expected ..." and returns false. */
bool display_config_load(const char *path, struct display_config *cfg);

/* Applies one "path=value" override (the --set option) of a display setting, with the same
 * types and ranges as the file: "display.eye_separation=0.07", "head.position=[0,1.7,0.4]",
 * "head.source=path", "hmd.warp=false", "walls.[0].mode=anaglyph" (the wall must exist).  A
 * path (head.path) is taken as given, relative to the working folder.  On failure logs
 * "--set PATH: expected ..." and returns false with CFG untouched.  Run
 * display_config_validate after the last one. */
bool display_config_set(struct display_config *cfg, const char *assignment);

/* The checks between settings, and the values derived from others: a wall without its own
 * mode takes display.mode; head.source = "path" needs head.path; a tracked head or wand
 * needs an address of its protocol's form and axes that form a rotation (the derived fields
 * of struct display_tracking are filled); walls are rectangles with unique names made of
 * letters, digits, '-' and '_'; a viewport has w, h >= 1; a passive wall names its right
 * eye's output.  Run after the file and after all display_config_set calls.  Logs and returns
 * false on the first problem ("FILE: SETTING: expected ..."). */
bool display_config_validate(struct display_config *cfg);

/* True when PATH ("PATH" or "PATH=VALUE", as given to --set) is a display file's: it lies in
 * display, head, navigation, hmd, openxr, wand or walls, known below that or not.  The
 * command line sends such a --set to the display config. */
bool display_config_has_setting(const char *path);

/* Keeps only the walls that rank RANK of SIZE draws (walls.[i].rank, or round the ranks in
 * turn); their names are kept.  Returns how many there are. */
int display_config_walls_of_rank(struct display_config *cfg, int rank, int size);

/* Names of the enums as written in files ("cave", "anaglyph", "path"); static strings. */
const char *display_type_name(enum display_type t);
const char *display_stereo_name(enum display_stereo s);
const char *display_head_source_name(enum display_head_source s);
const char *display_openxr_binding_name(enum display_openxr_binding b);
const char *display_openxr_space_name(enum display_openxr_space s);
const char *display_wand_source_name(enum display_wand_source s);

/* Writes the display settings as a markdown table with types, defaults, ranges and
 * descriptions, in the form of config_write_reference (docs/config-reference.md and
 * docs/displays.md carry it). */
void display_config_write_reference(FILE *out);

#endif
