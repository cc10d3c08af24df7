/*
 * app/interact: what `anvil run` (and a scripted `anvil render`) does between frames — time
 * playback through the time series cache, input from the wand, mouse or a script, the
 * in-world menu and what its changes mean (a new volume, the sun, quality, navigation), and
 * the menu's meshes in the scene.
 *
 * Light map rebuilds: every change that affects light (a new time step, species, tints, the
 * transfer function, the sun, light map quality) reaches the renderer once, when it is
 * committed — sliders and the transfer editor commit on release — and the next frame's
 * lightmaps_update rebuilds once for all views.
 */
#ifndef ANVIL_SESSION_INTERACT_H
#define ANVIL_SESSION_INTERACT_H

#include <stdbool.h>
#include <stdint.h>

#include "session/lightmaps.h"
#include "session/menu_view.h"
#include "session/player.h"
#include "session/scene.h"
#include "session/stats.h"
#include "config/display_config.h"
#include "data/volume.h"
#include "optics/transfer.h"

/* ---- the session's interaction -------------------------------------------------------- */

struct interact;
struct input_source;

struct interact_desc {
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
struct interact *interact_create(struct config *cfg, struct renderer *r,
                                         struct lightmaps *light, struct session_stats *st,
                                         const struct interact_desc *d);
void interact_destroy(struct interact *ia);

/* One frame's context.  */
struct interact_frame {
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
bool interact_frame(struct interact *ia, const struct interact_frame *f,
                        struct render_settings *s, bool *redraw, bool *nav_changed);

/* Scripted runs: whether the script has delivered everything and the volume caught up. */
bool interact_script_done(struct interact *ia);
double interact_script_dt(const struct interact *ia); /* 1 / fps, or 0 */
/* Waits for the wanted volume and uploads it (end of a scripted render). */
bool interact_settle(struct interact *ia);
struct menu *interact_menu(struct interact *ia);
int interact_step(const struct interact *ia); /* the step on screen */

#endif
