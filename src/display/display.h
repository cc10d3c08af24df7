/*
 * display: view sets.  A frame renders N views — CAVE walls times eyes, HMD eyes, a desktop
 * window — each a render target, a view matrix, a projection and an eye, and then presents
 * them: offscreen (files), a window, side-by-side / anaglyph / quad-buffer stereo, one window
 * per wall, an HMD with its lens warp, or an OpenXR runtime's swapchains.  The backends sit
 * behind one const table (display.c, `--display help`).
 *
 * Every view of a frame is drawn from the same renderer, so the view-independent work (the
 * volume, the deep light map) is done once per change whatever the number of views: the view
 * loop (display_draw) calls only renderer_draw.  This part knows nothing about how the volume
 * or the light map is made, and calls no GL itself (src/gpu does).
 *
 * The display owns its windows: it alone installs window callbacks, and it hands what they
 * report on as input events (display_poll_input), keys mapped through one table so that a key
 * means the same on every display.  Where the viewer is (head pose, navigation, the orbit
 * camera) is the caller's frame state: display_sample_head reads the head tracker, and
 * display_layout places the views for a given state.
 *
 * Must not know: the physics, the volume, the light map, the menu, the session.
 *
 * Frames: world metres (x east, y north, z up) -> navigation transform -> tracker metres
 * (x right, y up, z toward the viewer) -> eye.  Pure math (navigation, head poses, Kooima's
 * generalized perspective) is in view.c and head.c and needs no GL context.
 */
#ifndef ANVIL_DISPLAY_H
#define ANVIL_DISPLAY_H

#include <stdbool.h>
#include <stdio.h>

#include "config/display_config.h"
#include "gpu/gpu.h"
#include "input/input.h"
#include "input/tracker.h"
#include "render/image.h"
#include "render/render.h"

#define DISPLAY_MAX_VIEWS (2 * DISPLAY_MAX_WALLS)

/* ---- math: poses, navigation, generalized perspective (no GL) ------------------------- */

/* A rigid pose in tracker space: position (m) and rotation (unit quaternion x, y, z, w). */
struct display_pose {
    float position[3];
    float rotation[4];
};

/* The pose from a position and heading, pitch, roll in degrees (heading about +y, counter-
 * clockwise seen from above; pitch about the head's x, up positive; roll about its z). */
void display_pose_from_euler(const double position[3], const double hpr_deg[3],
                             struct display_pose *out);

/* OUT = A after B: B's pose given in A's frame, expressed in A's parent frame (A's rotation
 * applied to B's position, plus A's position; the rotations multiplied).  OUT may be A or B. */
void display_pose_compose(const struct display_pose *a, const struct display_pose *b,
                          struct display_pose *out);
/* OUT = the inverse of P (P composed with OUT is the identity).  OUT may be P. */
void display_pose_invert(const struct display_pose *p, struct display_pose *out);
/* The view matrix of an eye at pose EYE (looking along its -z, y up) for the world -> tracker
 * transform NAV (column-major): inverse(EYE) * NAV. */
void display_pose_view(const struct display_pose *eye, const float nav[16], float view[16]);

/* An OpenGL projection (column-major, NDC z in [-1, 1]) from a field of view given as the
 * four angles of its edges from the view axis, radians: LEFT and DOWN negative where the edge
 * lies left of or below the axis (OpenXR's XrFovf), so asymmetric frusta come out exactly.
 * NEAR and FAR: distances along the view axis. */
void display_fov_projection(float left, float right, float up, float down, float near,
                            float far, float out[16]);

/* World metres -> tracker metres (column-major 4x4):
 *   p_tracker = position + R * scale * A * (p_world - origin),
 * A turns world axes into tracker axes (east -> x, up -> y, north -> -z) and
 * R = Rz(roll) Rx(pitch) Ry(heading) (degrees, as in display_pose_from_euler). */
void display_navigation_matrix(const struct display_navigation *nav, float out[16]);

/* Eye positions: the head position -/+ half SEPARATION along the head's right axis (LEFT gets
 * the minus). */
void display_pose_eyes(const struct display_pose *head, double separation, float left[3],
                       float right[3]);

/* Kooima's generalized perspective for the screen WALL seen from EYE (tracker metres):
 * VIEW (tracker -> screen-aligned eye frame: x along the wall's bottom edge, y up the wall,
 * z out of the wall toward the viewer, origin at the eye) and PROJ (an off-axis frustum with
 * NEAR and FAR measured perpendicular to the wall).  EXTENT (may be NULL) receives the frustum
 * [left, right, bottom, top] at the near plane.  Returns false when the eye is on the wall's
 * plane or behind it (the wall is then invisible from there). */
bool display_wall_projection(const struct display_wall *wall, const float eye[3], float near,
                             float far, float view[16], float proj[16], float extent[4]);

/* ---- head tracking ------------------------------------------------------------------- */

/* A scripted head path: "t x y z heading pitch roll" per line (seconds, tracker metres,
 * degrees; '#' starts a comment; times strictly increasing).  A recording (input_recorder:
 * its first line "recorded ...") is a path too: its head lines at the sum of its frames'
 * steps. */
struct display_path {
    int count;
    double *time;          /* count */
    struct display_pose *pose; /* count */
};

/* Reads a path file.  On failure logs "FILE:LINE: expected ..." and returns false (PATH is then
 * empty).  Free with display_path_finish. */
bool display_path_load(const char *file, struct display_path *path);
void display_path_finish(struct display_path *path);
/* The pose at time T: linear in position, spherical-linear in rotation between the two
 * surrounding poses; clamped to the first and last. */
void display_path_eval(const struct display_path *path, double t, struct display_pose *out);

/* The input part's descs of CFG's tracked head (head.source dtrack or vrpn) and wand
 * (wand.source dtrack or vrpn): address, sensor, calibration (units "auto": DTrack's mm,
 * VRPN's m), and the wand's buttons and channels.  CFG must have been validated (the derived
 * fields of struct display_tracking). */
void display_head_desc(const struct display_config *cfg, struct tracker_desc *out);
void display_wand_desc(const struct display_config *cfg, struct tracker_wand_desc *out);

/* The world camera of the orbit display (anvil run without --display): world metres, z up. */
struct display_camera {
    double eye[3], target[3], up[3];
    double fov_deg;       /* vertical */
    double near_m, far_m;
};

/* ---- views --------------------------------------------------------------------------- */

enum view_eye { VIEW_EYE_MONO, VIEW_EYE_LEFT, VIEW_EYE_RIGHT };

struct view {
    /* World -> eye and projection, image size.  16-byte aligned: renderer_draw hands the
     * matrices to cglm's SIMD code. */
    _Alignas(16) struct render_view rv;
    char name[48];             /* "front-left", "screen", "left": image file names */
    int wall;                  /* wall index (hmd: 0) */
    enum view_eye eye;
    float eye_tracker[3];      /* eye position in tracker metres */
    float extent[4];           /* frustum [l, r, b, t] at the near plane (walls) */
    bool visible;              /* false: the eye is behind this wall; not drawn */
    struct gpu_texture target; /* RGBA32F render target (owned, made on first draw) */
};

struct view_set {
    struct view views[DISPLAY_MAX_VIEWS];
    int count;
};

/* Lays out the walls of CFG (one view per wall for mono walls, left and right for stereo
 * ones) for the head pose HEAD.  SIZES gives each wall's image [w, h].  Matrices map world
 * metres through the navigation transform NAV.  Textures already in SET are kept when the
 * layout is unchanged.  No GL. */
void view_set_layout(struct view_set *set, const struct display_config *cfg,
                     const struct display_navigation *nav, const struct display_pose *head,
                     const int (*sizes)[2]);

/* Image size of wall W: walls[w].size, else HEIGHT pixels high and the wall's aspect wide. */
void view_set_wall_size(const struct display_config *cfg, int w, int height, int out[2]);

/* The views of CFG's walls when its head does not move (head.source fixed): laid out for that
 * head with the config's navigation, HEIGHT pixels high where a wall has no size.  0 (SET
 * empty) for a moving head, a headset or the orbit display.  No GL. */
int view_set_fixed(const struct display_config *cfg, int height, struct view_set *set);

/* Frees the views' textures (GL context current). */
void view_set_finish(struct view_set *set);

/* ---- displays ------------------------------------------------------------------------ */

struct display;

/* Why display_create returned NULL (the program's exit code follows from it). */
enum display_failure {
    DISPLAY_FAILED_NONE,
    DISPLAY_FAILED_INPUT,   /* what the display config names is wrong: a pose file, a device */
    DISPLAY_FAILED_CONTEXT, /* no OpenGL 4.5 context (no driver; for windows, no display) */
    DISPLAY_FAILED_OTHER,   /* anything else (out of memory, a shader) */
};

struct display_desc {
    bool offscreen;              /* render into textures only (anvil render): no windows */
    struct gpu_context *context; /* offscreen: use this context (not owned); NULL: create an
                                    EGL one */
    int height;                  /* image height of walls without a size (render.height) */
    struct display_camera camera; /* the orbit display's camera until display_layout is given
                                     another (the scene's camera) */
    int gpu_device;               /* offscreen: the EGL device by index (one per rank of a
                                     node); 0: the first */
    bool partial;                 /* these are some of the walls (a cluster's rank): no
                                     contact sheet of them all */
    /* Called right before the windows swap (a cluster's ranks wait for each other there). */
    void (*before_swap)(void *user);
    void *swap_user;
    unsigned swap_group; /* windows: join this swap group and its barrier (GLX_NV_swap_group);
                            0: none */
    bool head_given;     /* every head pose comes from the caller (a cluster's other ranks:
                            rank 0 samples it): no head tracker or device is opened, though
                            the head still counts as moving (display_head_moves) */
    enum display_failure *failure; /* receives why display_create failed (may be NULL) */
};

/* Whether this build has the backend of TYPE (openxr needs the OpenXR loader at build
 * time). */
bool display_type_available(enum display_type type);

/* Lists the backends (name, one-line description) for --display help. */
void display_list(void (*print)(const char *name, const char *what, void *user), void *user);

/* Opens the display CFG describes: its windows (or offscreen targets), its HMD device, its
 * head tracker.  The primary context is current on return.  CFG is copied.  Returns NULL
 * (reason logged, and its kind in *DESC->failure) when a window, context or device cannot be
 * had.  Destroy with display_destroy (which accepts NULL). */
struct display *display_create(const struct display_config *cfg, const struct display_desc *desc);
void display_destroy(struct display *d);

/* Whether D paces its frames through a runtime of its own (OpenXR: display_sample_head begins
 * the runtime's frame), so display_sample_head must be called every frame, even when the
 * caller has the head from elsewhere (a recording). */
bool display_paces_frames(const struct display *d);

/* Whether every window of D joined desc.swap_group (false without windows or swap groups). */
bool display_swap_grouped(const struct display *d);

/* The primary GL context (owned by the display unless it was given in the desc).  Valid until
 * display_destroy. */
struct gpu_context *display_context(struct display *d);

/* The head pose at time T (seconds) from the display's head tracker (fixed, a scripted path,
 * an OpenHMD device, the latest pose of a DTrack or VRPN body: never waiting on the network,
 * head.position and head.orientation until the first pose), or from the display's own headset
 * (OpenXR: this begins the runtime's frame, which display_present ends).  False (logged) when
 * the device fails. */
bool display_sample_head(struct display *d, double t, struct display_pose *head);

/* The eyes (left, right) relative to the head that the last display_layout drew, into OUT, for a
 * display whose runtime gives them every frame (OpenXR's xrLocateViews): what a recording keeps
 * beside the head so that its replay draws the same eyes, bit for bit, whatever the replaying
 * runtime's own offsets are.  False (OUT untouched) for a display whose eyes follow from the
 * head and its config alone (every other one). */
bool display_eyes_in_head(const struct display *d, struct display_pose out[2]);

/* The eyes relative to the head (left, right; copied) that the following display_layout calls
 * draw in place of the runtime's (a replay's recorded eyes); NULL: the runtime's again.  A
 * display whose eyes follow from the head ignores it. */
void display_give_eyes(struct display *d, const struct display_pose eyes[2]);

/* Places every view for HEAD, the navigation NAV (tracker displays) and CAMERA (the orbit
 * display), each taken as given: the caller owns them. */
bool display_layout(struct display *d, const struct display_pose *head,
                    const struct display_navigation *nav, const struct display_camera *camera);

/* display_sample_head at T, then display_layout with the display config's navigation and
 * the home camera (for callers without a frame state of their own: tests, one-off views). */
bool display_update(struct display *d, double t);

/* Whether the display's views come from the orbit camera (world space) rather than from a
 * head in tracker space. */
bool display_uses_camera(const struct display *d);
/* Whether the head moves by itself (a path or a device): then every frame is drawn. */
bool display_head_moves(const struct display *d);

/* The views of the current frame.  Pointers stay valid until display_destroy. */
int display_view_count(const struct display *d);
struct view *display_view(struct display *d, int i);
const struct display_config *display_get_config(const struct display *d);

/* The per-frame view loop: one renderer_draw per visible view, in view order, nothing else
 * (no light map build, no volume upload; the views' times go where renderer_set_timing
 * says).  Needs the primary context current. */
bool display_draw(struct display *d, struct renderer *r, const struct render_settings *s);

/* Composes the drawn views the way the display shows them (stereo composition, lens warp),
 * tone maps with EXPOSURE, and shows them in the windows, swapping all together.  Offscreen
 * displays compose into textures only. */
bool display_present(struct display *d, struct renderer *r, float exposure);

/* Composed screen images (e.g. the anaglyph, both HMD eyes after the warp): COUNT and each
 * one's name and linear RGBA32F texture.  Valid after display_present until the next one. */
int display_output_count(const struct display *d);
const struct gpu_texture *display_output(const struct display *d, int i, const char **name);

/* Windows: waits up to TIMEOUT_S for events (0: none), then appends to Q what the windows
 * reported since the last call, in order: keys (INPUT_KEY, through the one key table), mouse
 * buttons (left: trigger, middle: grab, right: the menu key), drags and the wheel, the
 * pointer's ray through the first view (world space) on displays with a pointer, and the
 * first joystick's buttons and left stick (fly, turn).  A window's close button is a
 * INPUT_KEY_QUIT.  An OpenXR display first appends its controllers' buttons, sticks and aim
 * ray (tracker space), and an INPUT_KEY_QUIT when the runtime ends the session.  Offscreen
 * displays append nothing else. */
void display_poll_input(struct display *d, double timeout_s, struct input_queue *q);
/* The key table for help texts: each meaning once, with the names of its keys ("R, Page Up"). */
void display_list_keys(void (*print)(const char *keys, enum input_key key, void *user),
                       void *user);
/* Whether a window's close button was pressed. */
bool display_should_close(const struct display *d);

/* Writes every drawn view as DIR/NAME.EXT (EXT "png": tone-mapped, "pfm": linear radiance),
 * every composed output likewise, and a contact sheet DIR/contact.EXT of all views (walls
 * across, eyes down).  Creates DIR.  Returns false (logged) on a failed write.  NONFINITE (may
 * be NULL) receives the count of non-finite pixels over all views. */
bool display_write_images(struct display *d, const char *dir, const char *ext, float exposure,
                          size_t *nonfinite);

/* ---- diagnostics: a display's trackers (anvil trackers) ---------------------------------- */

struct display_trackers;

/* Opens CFG's tracked head and wand (dtrack, vrpn) to watch them, without a window.  NULL
 * (logged) when CFG tracks neither or a link cannot be had. */
struct display_trackers *display_trackers_open(const struct display_config *cfg);
/* Writes what they hold at NOW_S seconds to OUT: per tracker its pose in room coordinates
 * after calibration (metres; heading, pitch, roll in degrees), tracked or not, its pose rate
 * since the last report, its untracked frames, the wand's buttons and stick; per link its
 * frame rate, frames, dropped frames, refused input and the ids it has seen. */
void display_trackers_report(struct display_trackers *t, double now_s, FILE *out);
void display_trackers_close(struct display_trackers *t); /* NULL is fine */

/* Arranges IMAGES (N of them) in a grid of COLUMNS, row 0 at the top, with GAP pixels of
 * BACKGROUND between them, into OUT (initialised here).  No GL. */
bool display_contact_sheet(const struct image *images, int n, int columns, int gap,
                           const float background[4], struct image *out);

#endif
