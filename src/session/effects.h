/*
 * app/effects: simulate only what the scene calls for.  Each effect (config.h's enum effect)
 * is on, off or auto in the config; auto is decided here from facts about the scene — the
 * optical depth along the light, which species are present, whether any view sees the
 * ground, the display — and every decision comes with a sentence saying why.
 *
 * effects_decide is a pure function of the config and the facts (no GL, no files, no
 * logging), so it is tested alone; measuring the facts is plain CPU work on the volume and
 * the view matrices.  The renderer and the light map turn an effect that is off into a shader
 * variant without its code (docs/effects.md).
 */
#ifndef ANVIL_SESSION_EFFECTS_H
#define ANVIL_SESSION_EFFECTS_H

#include <stdbool.h>

#include "config/config.h"
#include "config/display_config.h"
#include "data/volume.h"
#include "light/light.h"
#include "render/render.h"

/* Largest change of the light map (relative to the sun) that forward scattering may make
 * before auto turns it on: half of one 8-bit display level. */
#define EFFECTS_FORWARD_TOLERANCE (0.5 / 255.0)

/* Lateral escape (effects.lateral): a voxel is in narrow cloud when its escape rate
 * (light_lateral_escape, the larger axis) lets at least EFFECTS_NARROW_RATE of the diffuse
 * light out per unit optical depth.  Auto turns the effect on when such cloud holds at least
 * EFFECTS_NARROW_SHARE of the extinction. */
#define EFFECTS_NARROW_RATE 0.01
#define EFFECTS_NARROW_SHARE 0.005

/* What is known about the scene.  effects_facts_init marks everything unknown; an unknown
 * fact makes auto decide on (the full simulation) for the effects that depend on it. */
struct effects_facts {
    bool volume_known;        /* the four volume facts below were measured */
    double max_tau_light;     /* largest optical depth of a path along the light through the
                                 volume (INFINITY when it overflows) */
    double beta_ice_sum;      /* sums of the ice-phase and water-phase extinction over voxels */
    double beta_water_sum;
    double narrow_share;      /* share of the extinction in narrow cloud (EFFECTS_NARROW_RATE) */
    bool views_known;
    bool ground_visible;      /* some view sees the ground plane (and render.ground_on) */
    int time_steps;           /* time steps the session can show; 0 = unknown */
    bool sun_moves;           /* the sun can change during the session (anvil run's keys) */
    bool playback;            /* time can play during the session: anvil run, or a scripted
                                 render (--input) whose events may press play */
    bool hmd;                 /* the display is an HMD */
    bool hmd_warp;            /* ... and its display config asks for the lens warp (hmd.warp) */
    bool runtime_warps;       /* the display is an OpenXR headset: its runtime warps */
};

void effects_facts_init(struct effects_facts *f);

/* Measures the volume facts of VOL for the sun direction SUN (toward the sun): the optical
 * depth along the light through every column of a light-space grid as fine as the volume
 * across the light (at most 192 x 192 columns, the midpoint rule at half the shortest voxel
 * crossing), the sums of both extinctions, and the narrow share (light_lateral_rates, each
 * voxel's mean cosine mixed from OPTICS' phases by its ice share).  CPU, a few tens of
 * milliseconds for the default storm.  Returns false (logged) on a bad sun direction or out
 * of memory. */
bool effects_measure_volume(const struct ext_volume *vol, const double sun[3],
                            const struct optics_params *optics, struct effects_facts *f);

/* The detail effect's decision, which depends on no fact (effects_decide's own): for those
 * that make volumes, without deciding everything else. */
bool effects_detail_on(const struct config *cfg);

/* What a session knows besides the volume when it decides. */
struct effects_context {
    int time_steps;                       /* the scene's */
    bool playback;                        /* time can play */
    bool sun_moves;                       /* the sun can move (anvil run) */
    const struct display_config *display; /* the display (HMD facts); NULL: none */
    const struct render_view *views;      /* the views, when they are known and stay */
    int view_count;
    bool views_known;
};

/* Gathers the facts once, the same way for every caller (a session, anvil effects): C's, and
 * the volume facts of VOL under CFG's sun (effects_measure_volume).  False (logged) as
 * effects_measure_volume. */
bool effects_gather(const struct config *cfg, const struct ext_volume *vol,
                    const struct effects_context *c, struct effects_facts *out);

/* Whether VIEW sees the ground plane z = 0 from above: the eye is above it and some ray of
 * the frustum points down (the frustum's directions form a convex cone, so its corners
 * decide). */
bool effects_view_sees_ground(const struct render_view *view);

/* The decisions.  single_phase_ice says which phase serves every species when the phase
 * effect is off: the one with the larger share of the extinction (water when unknown). */
struct effects {
    bool on[EFFECT_COUNT];
    char reason[EFFECT_COUNT][200];
    bool single_phase_ice;
    bool multiple_volume; /* with EFFECT_MULTIPLE on: the diffuse light volume, not the columns */
    char light_builds[200]; /* how often the light map is built, and why */
};

/* Decides every effect from CFG's effects.* modes and FACTS (may be NULL: all unknown).
 * Pure: the same inputs give the same output. */
void effects_decide(const struct config *cfg, const struct effects_facts *facts,
                    struct effects *out);

/* The config name of an effect ("shadows", "ground_shadow", ...); static storage. */
const char *effects_name(enum effect e);

/* Writes the effects that concern the eye pass into S (single phase, ground shadow). */
void effects_apply_render(const struct effects *e, struct render_settings *s);

/* The light map settings that CFG and E ask for: resolution, forward angle, epsilon from
 * lightmap.*, forward, peripheral and multiple from E, and with the phase effect off both phases'
 * cumulative phases set to the single phase's (the light pass then compiles the mix out). */
void effects_light_settings(const struct config *cfg, const struct effects *e,
                            struct light_settings *s);

#endif
