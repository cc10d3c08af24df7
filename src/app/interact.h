/*
 * app/interact: what `anvil run` (and a scripted `anvil render`) does between frames — time
 * playback through the time series cache, input from the wand, mouse or a script, the
 * in-world menu and what its changes mean (a new volume, the sun, quality, navigation), and
 * the menu's meshes in the scene.
 *
 * Light map rebuilds: every change that affects light (a new time step, species, tints, the
 * transfer function, the sun, light map quality) reaches the renderer once, when it is
 * committed — sliders and the transfer editor commit on release — and the next frame's
 * app_light_update rebuilds once for all views.
 */
#ifndef ANVIL_APP_INTERACT_H
#define ANVIL_APP_INTERACT_H

#include <stdbool.h>
#include <stdint.h>

#include "app/app.h"
#include "config/display_config.h"
#include "data/volume.h"
#include "optics/transfer.h"

/* ---- playback: the time cursor (pure logic, no I/O) ----------------------------------- */

struct app_playback {
    int step, count;
    bool playing, loop;
    double speed;   /* steps per second */
    double acc;     /* fraction of a step accumulated */
    unsigned stalls; /* frames that wanted the next step before it was loaded */
};

void app_playback_init(struct app_playback *pb, int count, int step, double speed, bool loop);
/* Advances by DT seconds.  The cursor moves to the next step only once READY says it is loaded
 * (it waits there, counting stalls, rather than skip or block); at the end it stops (pausing)
 * unless LOOP.  Returns true when the step changed. */
bool app_playback_tick(struct app_playback *pb, double dt, bool (*ready)(void *user, int step),
                       void *user);

/* ---- the player: the time series cache over the scene's data --------------------------- */

/* How the volume is made from mass ratios (changed by the menu). */
struct app_look {
    struct species_select select;
    struct species_tint tint;
    bool transfer_on;
    struct transfer_function transfer;
};

void app_look_from_config(const struct config *cfg, struct app_look *look);

struct app_player;

struct app_player_desc {
    int prefetch;       /* -1: none; 0: default */
    double memory_mb;   /* 0: data.cache_memory */
    double delay_ms;    /* test hook: a slow reader */
};

/* Opens the scene's time steps behind a series cache (data.cache_memory, data.prefetch,
 * playback.loop), showing data.step.  CFG must outlive the player.  NULL (logged) on
 * failure.  No GL. */
struct app_player *app_player_create(const struct config *cfg, const struct app_player_desc *d);
void app_player_destroy(struct app_player *p);

int app_player_step_count(const struct app_player *p);
/* "2005-08-28_06:00:00" or "" (static per player, valid until destroy). */
const char *app_player_step_date(struct app_player *p, int step);
bool app_player_ready(struct app_player *p, int step);
/* Whether the look can change the volume (storm and WRF/Isabel data: yes; test scenes and
 * extinction files: no). */
bool app_player_has_fields(const struct app_player *p);
/* Species the data holds. */
void app_player_species_present(const struct app_player *p, bool present[SPECIES_COUNT]);

/* Changes the look: cached steps are dropped and made again in the background. */
void app_player_set_look(struct app_player *p, const struct app_look *look);

/* The volume to show for WANT when it differs from what was last returned (a new step or a
 * new look) and is loaded; NULL otherwise (nothing new, or not loaded yet: never blocks).
 * *SHOWN receives the step on screen.  The pointer is valid until the next call. */
const struct ext_volume *app_player_poll(struct app_player *p, int want, int *shown);
/* As app_player_poll but waits for the load (the end of a scripted run). */
const struct ext_volume *app_player_wait(struct app_player *p, int want, int *shown);
/* Whether the step on screen is WANT with the current look. */
bool app_player_settled(const struct app_player *p, int want);
/* effects.temporal: the next volume, tracked apart from the one shown.  As app_player_poll
 * (or with WAIT as app_player_wait) for step WANT (-1: none wanted); *HELD is the step the
 * caller's next volume holds, -1 none. */
const struct ext_volume *app_player_poll_next(struct app_player *p, int want, bool wait,
                                              int *held);
/* The identity (app_light_step_id) of the volume shown, or with NEXT of the next volume (0
 * when it is none, or made with an older look). */
uint64_t app_player_step_id(const struct app_player *p, bool next);

void app_player_stats(struct app_player *p, struct app_stats *st);

/* ---- the session's interaction -------------------------------------------------------- */

struct app_interact;
struct input_source;

struct app_interact_desc {
    const char *script;        /* --input FILE: scripted events, or NULL */
    const char *transfers_dir; /* where named transfer functions are saved ("." default) */
    bool tracker_space;        /* the menu lives in tracker space (--display), else world */
    void *window;              /* GLFW window for the desktop wand, or NULL */
    const char *wand;          /* OpenHMD controller for the wand ("null"), or NULL */
    bool show_menu;            /* start with the menu shown */
    bool wait_for_volumes;     /* scripted renders: each frame waits for the volume it wants,
                                  so the result does not depend on how fast files load */
};

/* Creates the player, the input sources, the menu and its meshes (added to R).  CFG, R, LIGHT
 * and ST must outlive it; CFG is changed by the menu (sun, quality).  Needs the GL context.
 * NULL (logged) on failure. */
struct app_interact *app_interact_create(struct config *cfg, struct renderer *r,
                                         struct app_light *light, struct app_stats *st,
                                         const struct app_interact_desc *d);
void app_interact_destroy(struct app_interact *ia);

/* One frame's context.  */
struct app_interact_frame {
    double dt;                 /* seconds since the last frame (scripted runs: 1 / fps) */
    /* Camera of the desktop window (mouse rays; world menus follow it), when have_camera. */
    bool have_camera;
    float view[16], proj[16];
    int width, height;
    /* Tracker space: the navigation (changed by flying and grabbing) and the head pose. */
    struct display_navigation *nav;
    const struct display_navigation *nav_home; /* reset view */
    float head[3];
};

/* Polls the input, runs the menu, advances playback, uploads a new volume when one is ready,
 * updates the render settings S and the menu meshes.  *REDRAW is set when something visible
 * changed; *NAV_CHANGED when the navigation moved.  False on a failure (logged). */
bool app_interact_frame(struct app_interact *ia, const struct app_interact_frame *f,
                        struct render_settings *s, bool *redraw, bool *nav_changed);

/* Scripted runs: whether the script has delivered everything and the volume caught up. */
bool app_interact_script_done(struct app_interact *ia);
double app_interact_script_dt(const struct app_interact *ia); /* 1 / fps, or 0 */
/* Waits for the wanted volume and uploads it (end of a scripted render). */
bool app_interact_settle(struct app_interact *ia);
struct menu *app_interact_menu(struct app_interact *ia);
int app_interact_step(const struct app_interact *ia); /* the step on screen */

/* ---- the menu in the scene (GL) -------------------------------------------------------- */

struct app_menu_view;
/* Meshes for the panel and the wand ray, added to R.  Needs the GL context. */
struct app_menu_view *app_menu_view_create(struct renderer *r);
void app_menu_view_destroy(struct app_menu_view *v, struct renderer *r);
/* Uploads the menu's image when it changed and places the panel and the ray with TO_WORLD
 * (menu space -> world, column-major).  EXPOSURE: the tone mapping's, so the panel shows its
 * own colours. */
bool app_menu_view_update(struct app_menu_view *v, struct menu *m, const float to_world[16],
                          float exposure);
/* The radiance the panel shows for an image texel (what the view's pixel holds). */
void app_menu_texel_radiance(const uint8_t rgba[4], float exposure, float out[3]);

#endif
