/*
 * session: everything that changes while the program runs.  A session owns the data source
 * and the time cursor (player, playback), the volumes on the GPU and the renderer, the light
 * map(s), the map geometry, the effects decisions (decided once, from facts gathered once),
 * the look (species, tints, transfer function), the sun, the quality settings, navigation and
 * the orbit camera, the menu and its input sources.  session_create reads the config once and
 * keeps it unchanged; after that the menu, keys, joystick and wand change the session only
 * through its setters, and nothing writes a config.
 *
 * A frame, in the order of the one frame loop (app/loop.c):
 *
 *   session_update   input -> menu -> setters -> playback: the frame state (frame.h)
 *   session_apply    the frame state -> volumes on the GPU, the eye pass's settings
 *   session_light    the light map, rebuilt only when its key changed
 *   (the caller samples the head pose last: display_sample_head)
 *   session_draw     layout, the menu's meshes, every view, present
 *   session_prepare  between frames: the next step readied (a run of a series)
 *
 * session_update only produces state and session_apply/session_draw only consume it, so a
 * second session fed the same frame states draws the same pictures (a cluster's render nodes,
 * a replay).
 *
 * Must not know: windows and devices (the display and input parts hand it events), files other
 * than the scene's data and saved transfer functions, the command line.
 */
#ifndef ANVIL_SESSION_H
#define ANVIL_SESSION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "config/config.h"
#include "config/display_config.h"
#include "display/display.h"
#include "input/input.h"
#include "render/render.h"
#include "session/frame.h"
#include "session/player.h"
#include "session/probe.h"
#include "session/stats.h"

struct menu;

struct session_desc {
    const char *command;                  /* "render", "run": --stats and the log */
    const struct display_config *display; /* the display's config (copied); NULL: the orbit
                                             display of the scene's own camera */
    /* The navigation fitting the domain to the whole room (scene_frame_navigation over every
     * wall: a cluster's rank has only its own walls in DISPLAY); NULL: fitted to DISPLAY's. */
    const struct display_navigation *room_navigation;
    /* The display's first views (for the effects: does any see the ground?); NULL with
     * views_move: the views change while the session runs. */
    const struct render_view *views;
    int view_count;
    bool views_move;
    bool interactive;          /* anvil run: the sun moves, loads never wait */
    bool playback;             /* time can move (run, a script, frame states from elsewhere):
                                  the time series cache runs behind the first step */
    bool menu;                 /* make the menu and the input sources (run, --input, --menu):
                                  the script and the display's wand (display->wand) */
    bool show_menu;            /* start with the menu shown */
    const char *script;        /* --input FILE: scripted events, or NULL */
    const char *transfers_dir; /* where named transfer functions are saved ("." default) */
    bool time_views;           /* time every view and build (they are reported) */
    double load_delay_ms;      /* tests: every time step of the series loads this much slower */
    bool replay_of_run;        /* the script is a recording of anvil run: the effects are
                                  decided as that run decided them (the sun could move) */
    bool count_rays;           /* count what the views' rays do (renderer_set_counting; the
                                  counts go to the stats at session_collect_timings(s, true)) */
    bool unstaged;             /* a run's step changes upload and build in their own frame,
                                  without session_prepare (the playback bench's yardstick) */
    bool probe;                /* the probe can be used (run, a script, --menu; every rank of
                                  a cluster): a second reader of the data and the extinction
                                  of the step on screen kept on the CPU */
};

/* Builds the session for CFG (copied) on the current GL context: the first volume, the
 * renderer, the light map, the map, the effects, the menu.  NULL (logged) on failure; *RC then
 * holds the exit code's reason: 1 bad input, 4 anything else (out of memory, GL). */
struct session *session_create(const struct config *cfg, const struct session_desc *d, int *rc);
void session_destroy(struct session *s); /* NULL is fine; needs the GL context current */

/* ---- one frame ------------------------------------------------------------------------ */

/* Polls the session's own sources (script, wand), then handles WINDOW_EVENTS (may be NULL)
 * and those: the menu, navigation, keys; applies what the menu committed through the setters;
 * advances playback by DT seconds.  Fills OUT with the frame state (the head at the fixed
 * pose: the caller samples the real one last) at display time TIME_S.  *REDRAW says whether
 * the picture may have changed.  False on a failure (logged). */
bool session_update(struct session *s, const struct input_queue *window_events, double dt,
                    double time_s, struct frame_state *out, bool *redraw);

/* Makes the GPU state match F: the volume of F's time step (and with effects.temporal the
 * next one) when it is loaded (scripted renders wait for it), the sun and the temporal blend
 * of the eye pass.  *CHANGED (may be NULL) is set when a volume was uploaded or a staged one
 * swapped in (session_prepare). */
bool session_apply(struct session *s, const struct frame_state *f, bool *changed);

/* Builds the light map if its key changed since the last build (once for every view); first
 * moves the view and build times that arrived into the stats (never waiting). */
bool session_light(struct session *s);

/* Between frames (after session_draw): readies the step after the one shown, so that its step
 * change is a swap: its volume copied into a pixel buffer off the render thread, uploaded from
 * there in slabs, its light map built; as many of those pieces as need not wait for the copy,
 * for about as long as the last frame took (the light build is one piece, however long).
 * Playback moves onto that step only once it is ready (a stall, not a slow frame).  *MORE:
 * call again soon (work is in flight).  No-op but for runs of a series (session_desc
 * interactive and playback).  A step that cannot be readied (GPU memory, most likely) is
 * warned about once and turns staging off: step changes then upload in their frame.  Returns
 * true (false is kept for failures the frame loop must end on; there are none yet). */
bool session_prepare(struct session *s, bool *more);
/* The bytes of an upload slab session_prepare gives the renderer, from the last slab's rate
 * (bytes per wall ms, 0: none yet) and the ms left in the call: what fits, within 4 and 64
 * MiB. */
size_t session_slab_bytes(double rate_bytes_per_ms, double left_ms);

/* Places D's views for F, the menu's panel and ray, draws every view and presents them. */
bool session_draw(struct session *s, struct display *d, const struct frame_state *f);

/* ---- state ---------------------------------------------------------------------------- */

/* The look and quality: what the menu changes besides time, the sun and the view.  REVISION
 * increases with every change (the frame state carries it). */
struct session_settings {
    struct look look;
    double step_m;           /* render.step: eye pass ray step (0: automatic) */
    double lod_pixels;       /* render.lod: steps at least this many pixels wide (0: off) */
    int light_resolution[3]; /* lightmap.resolution */
    double epsilon;          /* lightmap.epsilon */
    bool diffuse;            /* effects.multiple (and lateral escape with it) */
    struct probe_settings probe;
    uint32_t revision;
};

void session_get_settings(const struct session *s, struct session_settings *out);
/* Takes IN (its revision too): a changed look makes the volumes again in the background. */
void session_set_settings(struct session *s, const struct session_settings *in);

void session_set_sun(struct session *s, double azimuth_deg, double elevation_deg);
/* The time cursor at T steps (step floor(T), blended toward the next by the fraction with
 * effects.temporal), clamped to the series. */
void session_set_time(struct session *s, double t);
void session_set_step(struct session *s, int step);
void session_set_playing(struct session *s, bool playing);
void session_set_navigation(struct session *s, const struct display_navigation *nav);
void session_set_camera(struct session *s, const struct display_camera *camera);
/* Navigation and camera back to where they started. */
void session_reset_view(struct session *s);
/* The view framing the whole domain (the Shift+F key, the menu's Frame): the orbit camera from
 * the south-west (scene_frame_camera), a tracked display's navigation fitted to its room
 * (scene_frame_navigation).  It travels in the frame state like any navigation. */
void session_frame_view(struct session *s);

/* The camera path that the path keys add to and fly (P NULL: an empty one), saved to FILE
 * (NULL: nowhere) at every new key.  False (logged) out of memory. */
struct camera_path;
bool session_set_camera_path(struct session *s, const struct camera_path *p, const char *file);

/* What the keys asked of the caller since the last call (a screenshot, a bookmark). */
enum { SESSION_REQUEST_SCREENSHOT = 1u << 0, SESSION_REQUEST_BOOKMARK = 1u << 1 };
unsigned session_take_requests(struct session *s);
/* The orbit camera as a scene file's camera block, or on a tracked display the navigation as a
 * display file's navigation block; the sun as a scene file's light block. */
void session_view_text(const struct session *s, char *buf, size_t size);
void session_sun_text(const struct session *s, char *buf, size_t size);
/* What a scene file needs besides the camera and the sun to render what the session shows:
 * the time step (data.step), the look (look.species.*, look.layers and look.slices with their
 * transfer functions written in place), the quality the menu changed (render.step,
 * lightmap.resolution, lightmap.epsilon) and the effects as the session decided them (all but
 * temporal and distortion), the probe when it is on.  SIZE of 96 KiB holds any look (four
 * layers and four slices whose functions have every point they can hold: about 45 KiB). */
void session_look_text(const struct session *s, char *buf, size_t size);
/* The menu's status line (a saved bookmark); no-op without a menu. */
void session_set_status(struct session *s, const char *text);
bool session_uses_tracker(const struct session *s);
/* The scene's time steps; whether steps are blended (effects.temporal). */
int session_step_count(const struct session *s);
bool session_blends_steps(const struct session *s);

/* Whether the user asked to quit (a quit key, a window's close button). */
bool session_quit_requested(const struct session *s);
/* Scripted runs: whether the script has delivered everything and the volume caught up; its
 * frame time (1 / fps, or 0 without a script). */
bool session_script_done(struct session *s);
double session_script_dt(const struct session *s);
long session_script_frames(const struct session *s); /* its last frame + 1; 0 without one */
/* Waits for the wanted volume and uploads it (the end of a scripted render). */
bool session_settle(struct session *s);

/* Recordings (input/input.h, input_recorder).  Whether the script gave the head (a recording
 * of a tracked display): the frame states then carry it, and the frame loop does not sample
 * the display's head. */
bool session_head_given(const struct session *s);
/* The eyes relative to the head (left, right) that the script gave with it (a recording of a
 * display whose runtime gives the eyes: display_eyes_in_head), valid until the next
 * session_apply; NULL when it gave none. */
const struct display_pose *session_eyes_given(const struct session *s);
/* The events the last session_update handled, in order (window events, then the script's and
 * the wand's).  Valid until the next session_update. */
const struct input_queue *session_events(const struct session *s);
/* The playback cursor after the last session_update. */
void session_cursor(const struct session *s, int *step, double *acc, bool *playing);

/* Moves the view and build times the GPU has ready into session_stats; with WAIT all of them
 * (before the report at the end of a run). */
void session_collect_timings(struct session *s, bool wait);

/* ---- a cluster's ranks (app/loop.c) -------------------------------------------------- */

/* A hash of what makes the pictures besides the frame state (the config, the look and
 * quality, the step on screen): ranks in step have equal keys (--check-sync). */
uint64_t session_sync_key(const struct session *s);
/* Whether STEP's volume is in memory (the cluster holds its walls at the old step until every
 * rank has the new one). */
bool session_step_loaded(struct session *s, int step);
/* Has STEP (and the next, for effects.temporal) loaded in the background while an older step
 * stays on screen: a cluster's rank whose step the others wait for. */
void session_want_step(struct session *s, int step);
/* The menu's meshes (rank 0): false without a menu; *PIXELS its image. */
struct menu_view_state;
bool session_menu_state(struct session *s, struct menu_view_state *st, const uint8_t **pixels);
/* A session without a menu shows ST (another's) from now on; PIXELS (copied) when ST's image
 * is new, else NULL to keep the last.  False (logged) out of memory or GL. */
bool session_show_menu_state(struct session *s, const struct menu_view_state *st,
                             const uint8_t *pixels);

/* Counts the rows of the following views in P (a long still picture: renderer_set_progress). */
struct progress;
void session_set_progress(struct session *s, struct progress *p);

struct renderer *session_renderer(struct session *s);
struct session_stats *session_stats(struct session *s);
struct menu *session_menu(struct session *s); /* NULL without a menu */
const struct config *session_config(const struct session *s);
int session_step_shown(const struct session *s);

/* What the probe showed in the last session_draw (NULL without a probe): the values, their
 * rows on the panel. */
const struct probe_values *session_probe(const struct session *s);

/* What the information overlay showed in the last session_draw, or NULL without one. */
struct overlay_model;
const struct overlay_model *session_overlay(const struct session *s);
/* Where in the world the overlay's legend shows the value at X in [0, 1] of its range (false
 * without a legend): for tests that read it off a picture. */
bool session_overlay_point(const struct session *s, float x, double world[3]);
/* The same for legend LEGEND (layers first, then slices, as the overlay lists them). */
bool session_legend_point(const struct session *s, int legend, float x, double world[3]);

/* The help text's lines for the keys and what they do here ("W  move forward"), through the
 * display's key table. */
void session_list_keys(void (*print)(const char *keys, const char *what, void *user),
                       void *user);

#endif
