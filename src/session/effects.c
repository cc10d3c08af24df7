/* Effect decisions: facts about the scene -> on/off per effect, with the reason. */
#include "session/effects.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cglm/cglm.h>

#include "common/log.h"
#include "common/parallel.h"

#define MEASURE_COLUMNS_MAX 128
#define MEASURE_STEPS_MAX 4096

static const char *const names[EFFECT_COUNT] = {
    "shadows", "forward", "peripheral", "multiple", "lateral", "phase", "ground_shadow",
    "detail", "temporal", "distortion",
};

const char *effects_name(enum effect e)
{
    return e >= 0 && e < EFFECT_COUNT ? names[e] : "?";
}

void effects_facts_init(struct effects_facts *f)
{
    memset(f, 0, sizeof(*f));
}

/* Per plane of a volume: its extinction in narrow cloud (EFFECTS_NARROW_RATE), all of its
 * extinction, and its ice and water extinction sums; the planes' sums are added in order
 * afterwards, so the facts do not depend on how many threads made them. */
struct plane_facts {
    const struct ext_volume *vol;
    const struct optics_params *optics;
    double *narrow, *total, *ice, *water; /* [n2] each */
};

static bool facts_planes(void *ctx, int share, size_t begin, size_t end)
{
    const struct plane_facts *pf = ctx;
    const struct ext_volume *vol = pf->vol;
    size_t plane = (size_t)vol->grid.n[0] * vol->grid.n[1];
    float *r = malloc(2 * plane * sizeof(float)); /* one plane's lateral rates */
    if (!r)
        return false;
    for (size_t k = begin; k < end; k++) {
        light_lateral_rates_plane(vol, (int)k, r);
        double narrow = 0.0, total = 0.0, ice = 0.0, water = 0.0;
        const float *beta = vol->beta + 2 * plane * k;
        for (size_t v = 0; v < plane; v++) {
            float bi = beta[2 * v], bw = beta[2 * v + 1];
            ice += bi > 0.0f ? bi : 0.0;
            water += bw > 0.0f ? bw : 0.0;
            double b = (bi > 0.0f ? (double)fminf(bi, 1e30f) : 0.0) +
                       (bw > 0.0f ? (double)fminf(bw, 1e30f) : 0.0);
            if (!(b > 0.0))
                continue;
            total += b;
            double f_ice = bi > 0.0f ? fmin(bi, 1e30) / b : 0.0;
            double g = pf->optics->g_water + f_ice * (pf->optics->g_ice - pf->optics->g_water);
            float gamma = (float)(0.75 * (1.0 - g));
            float rate = fmaxf(light_lateral_escape(gamma, (float)(r[2 * v] / b), 0.0f),
                               light_lateral_escape(gamma, 0.0f, (float)(r[2 * v + 1] / b)));
            if (rate >= EFFECTS_NARROW_RATE)
                narrow += b;
        }
        pf->narrow[k] = narrow;
        pf->total[k] = total;
        pf->ice[k] = ice;
        pf->water[k] = water;
    }
    free(r);
    return true;
}

/* The share of VOL's extinction in narrow cloud and its ice and water sums, in one pass over
 * the volume a share of planes per CPU, each plane's lateral rates made and used at once (a
 * plane of scratch per thread, not a volume).  False (logged) out of memory. */
static bool volume_sums(const struct ext_volume *vol, const struct optics_params *optics,
                        double *narrow_share, double *ice, double *water)
{
    size_t n2 = (size_t)vol->grid.n[2];
    double *sums = calloc(4 * n2, sizeof(double));
    struct plane_facts pf = {.vol = vol, .optics = optics, .narrow = sums, .total = sums + n2,
                             .ice = sums + 2 * n2, .water = sums + 3 * n2};
    if (!sums || !parallel_for(n2, 1, &pf, facts_planes)) {
        log_error("effects: out of memory for the lateral escape rates of a %d x %d plane",
                  vol->grid.n[0], vol->grid.n[1]);
        free(sums);
        return false;
    }
    double narrow = 0.0, total = 0.0;
    *ice = *water = 0.0;
    for (size_t k = 0; k < n2; k++) {
        narrow += pf.narrow[k];
        total += pf.total[k];
        *ice += pf.ice[k];
        *water += pf.water[k];
    }
    free(sums);
    *narrow_share = total > 0.0 ? narrow / total : 0.0;
    return true;
}

bool effects_measure_volume(const struct ext_volume *vol, const double sun[3],
                            const struct optics_params *optics, struct effects_facts *f)
{
    const struct grid3 *g = &vol->grid;
    int n[3];
    for (int a = 0; a < 2; a++) {
        int most = g->n[0] > g->n[1] ? g->n[0] : g->n[1];
        n[a] = most < 2 ? 2 : most > MEASURE_COLUMNS_MAX ? MEASURE_COLUMNS_MAX : most;
    }
    n[2] = 2;
    struct light_grid lg;
    if (!light_grid_init(&lg, sun, g, n, LIGHT_GRID_AUTO))
        return false;
    /* March each column along the light in steps of half the shortest distance in which the
     * light crosses a voxel (the light map's own sub-step rule, halved). */
    double cross = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (fabs(lg.w[a]) > 1e-12)
            cross = fmin(cross, (a < 2 ? g->spacing[a] : grid3_min_dz(g)) / fabs(lg.w[a]));
    }
    double len = lg.hi[2] - lg.lo[2];
    int steps = (int)ceil(len / (0.5 * cross));
    steps = steps < 1 ? 1 : steps > MEASURE_STEPS_MAX ? MEASURE_STEPS_MAX : steps;
    double ds = len / steps;
    double max_tau = 0.0;
    for (int j = 0; j < n[1]; j++) {
        for (int i = 0; i < n[0]; i++) {
            double tau = 0.0;
            for (int k = 0; k < steps; k++) {
                double kz = (k + 0.5) / steps; /* the last node plane is k = 1 */
                float p[3], b[2];
                for (int a = 0; a < 3; a++)
                    p[a] = (float)(lg.origin[a] + i * (double)lg.du[a] + j * (double)lg.dv[a] +
                                   kz * (double)lg.dw[a]);
                light_sample_beta(vol, p, b);
                tau += ((double)b[0] + b[1]) * ds;
            }
            max_tau = fmax(max_tau, tau);
        }
    }
    double ice, water, narrow;
    if (!volume_sums(vol, optics, &narrow, &ice, &water))
        return false;
    f->narrow_share = narrow;
    f->volume_known = true;
    f->max_tau_light = isfinite(max_tau) ? max_tau : INFINITY;
    f->beta_ice_sum = ice;
    f->beta_water_sum = water;
    return true;
}

bool effects_detail_on(const struct config *cfg)
{
    return cfg->effects.mode[EFFECT_DETAIL] == EFFECT_ON; /* auto: off */
}

bool effects_gather(const struct config *cfg, const struct ext_volume *vol,
                    const struct effects_context *c, struct effects_facts *out)
{
    effects_facts_init(out);
    out->time_steps = c->time_steps;
    out->playback = c->playback;
    out->sun_moves = c->sun_moves;
    if (c->display) {
        out->hmd = c->display->type == DISPLAY_TYPE_HMD;
        out->runtime_warps = c->display->type == DISPLAY_TYPE_OPENXR;
        out->hmd_warp = c->display->hmd.warp;
    }
    double sun[3];
    light_sun_direction(cfg->light.azimuth_deg, cfg->light.elevation_deg, sun);
    if (!effects_measure_volume(vol, sun, &cfg->optics.params, out))
        return false;
    out->views_known = c->views_known;
    for (int i = 0; c->views_known && i < c->view_count; i++)
        out->ground_visible |= cfg->render.ground_on && effects_view_sees_ground(&c->views[i]);
    return true;
}

bool effects_view_sees_ground(const struct render_view *view)
{
    mat4 proj, viewm, vp, inv;
    memcpy(proj, view->proj, sizeof(proj));
    memcpy(viewm, view->view, sizeof(viewm));
    glm_mat4_mul(proj, viewm, vp);
    glm_mat4_inv(vp, inv);
    for (int c = 0; c < 4; c++) {
        vec4 pn = {c & 1 ? 1.0f : -1.0f, c & 2 ? 1.0f : -1.0f, -1.0f, 1.0f};
        vec4 pf = {pn[0], pn[1], 1.0f, 1.0f};
        vec4 wn, wf;
        glm_mat4_mulv(inv, pn, wn);
        glm_mat4_mulv(inv, pf, wf);
        float zn = wn[2] / wn[3], zf = wf[2] / wf[3];
        if (zn > 0.0f && zf < zn)
            return true;
    }
    return false;
}

static void say(struct effects *out, enum effect e, bool on, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static void say(struct effects *out, enum effect e, bool on, const char *fmt, ...)
{
    out->on[e] = on;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out->reason[e], sizeof(out->reason[e]), fmt, ap);
    va_end(ap);
}

/* Decides an effect whose mode is on or off, or one that needs another effect that is off.
 * Returns true when decided; false leaves auto to the caller. */
static bool decide_fixed(struct effects *out, enum effect e, enum effect_mode mode,
                         enum effect needs, bool needs_on)
{
    if (mode == EFFECT_OFF) {
        say(out, e, false, "off in the config");
        return true;
    }
    if (!needs_on) {
        say(out, e, false, "needs effects.%s, which is off", names[needs]);
        return true;
    }
    if (mode == EFFECT_ON) {
        say(out, e, true, "on in the config");
        return true;
    }
    return false;
}

/* The largest share of the sun that forward scattering can add to a light map value per unit
 * optical depth crossed: CP(theta/2) of the more forward phase (docs/effects.md). */
static double forward_gain(const struct config *cfg)
{
    struct light_settings s;
    light_settings_defaults(&s);
    light_settings_set_optics(&s, &cfg->optics.params, cfg->lightmap.forward_angle_deg);
    return fmax(s.cp.water_ctr + s.cp.water_per, s.cp.ice_ctr + s.cp.ice_per);
}

void effects_decide(const struct config *cfg, const struct effects_facts *facts,
                    struct effects *out)
{
    struct effects_facts unknown;
    if (!facts) {
        effects_facts_init(&unknown);
        facts = &unknown;
    }
    memset(out, 0, sizeof(*out));
    const enum effect_mode *mode = cfg->effects.mode;
    const double tol = EFFECTS_FORWARD_TOLERANCE;
    double tau = facts->max_tau_light;
    /* The volume facts describe the first time step under the first sun.  When either can
     * change during the session, what is thin or absent now may not be later: auto keeps
     * the effect on rather than decide from one moment (effects are compiled into shader
     * variants, so switching them per step would recompile). */
    bool changes = facts->time_steps > 1 || facts->sun_moves;
    char why_changes[96];
    snprintf(why_changes, sizeof(why_changes), "%s%s%s",
             facts->time_steps > 1 ? "the data has several time steps" : "",
             facts->time_steps > 1 && facts->sun_moves ? " and " : "",
             facts->sun_moves ? "the sun can move" : "");

    /* Shadows: the light map changes light by 1 - e^-tau <= tau. */
    if (!decide_fixed(out, EFFECT_SHADOWS, mode[EFFECT_SHADOWS], EFFECT_SHADOWS, true)) {
        if (!facts->volume_known)
            say(out, EFFECT_SHADOWS, true, "auto: volume not measured, on");
        else if (tau <= tol && changes)
            say(out, EFFECT_SHADOWS, true, "auto: optically thin now (%.3g) but %s: on", tau,
                why_changes);
        else if (tau <= tol)
            say(out, EFFECT_SHADOWS, false,
                "auto: largest optical depth along the light %.3g <= %.3g: shadows change "
                "no light by more than half a display level",
                tau, tol);
        else
            say(out, EFFECT_SHADOWS, true, "auto: largest optical depth along the light %.3g",
                tau);
    }

    /* Forward scattering adds at most CP(theta/2) tau to a light map value. */
    bool shadows = out->on[EFFECT_SHADOWS];
    if (!decide_fixed(out, EFFECT_FORWARD, mode[EFFECT_FORWARD], EFFECT_SHADOWS, shadows)) {
        double gain = forward_gain(cfg);
        double thin = gain > 0.0 ? tol / gain : INFINITY;
        if (!facts->volume_known)
            say(out, EFFECT_FORWARD, true, "auto: volume not measured, on");
        else if (tau <= thin && changes)
            say(out, EFFECT_FORWARD, true, "auto: optically thin now (%.3g) but %s: on", tau,
                why_changes);
        else if (tau <= thin)
            say(out, EFFECT_FORWARD, false,
                "auto: optically thin along the light (largest optical depth %.3g <= %.3g = "
                "half a display level / CP(theta/2) %.3f)",
                tau, thin, gain);
        else
            say(out, EFFECT_FORWARD, true,
                "auto: largest optical depth along the light %.3g > %.3g (thin limit)", tau,
                thin);
    }

    bool forward = out->on[EFFECT_FORWARD];
    if (!decide_fixed(out, EFFECT_PERIPHERAL, mode[EFFECT_PERIPHERAL], EFFECT_FORWARD,
                      forward))
        say(out, EFFECT_PERIPHERAL, true, "auto: follows effects.forward (on)");

    /* Multiple scattering: a node stores the diffuse light as 2(U + V), U and V the diffuse
     * fluxes relative to the sun.  In an optically thin column the diffuse light is at most
     * what was scattered out of the beam, 1 - e^-tau <= tau, so the eye pass gains at most
     * 2 tau_max of the sun (docs/effects.md). */
    if (mode[EFFECT_MULTIPLE] == EFFECT_VOLUME && shadows) {
        out->multiple_volume = true;
        say(out, EFFECT_MULTIPLE, true,
            "volume in the config: the diffuse light of a diffusion solve over the whole "
            "volume (light crossing columns; docs/lightmap.md), not the columns'");
    } else if (mode[EFFECT_MULTIPLE] == EFFECT_VOLUME) {
        say(out, EFFECT_MULTIPLE, false, "needs effects.%s, which is off", names[EFFECT_SHADOWS]);
    } else if (!decide_fixed(out, EFFECT_MULTIPLE, mode[EFFECT_MULTIPLE], EFFECT_SHADOWS,
                             shadows)) {
        double bound = 2.0 * tau;
        if (!facts->volume_known)
            say(out, EFFECT_MULTIPLE, true, "auto: volume not measured, on");
        else if (bound <= tol && changes)
            say(out, EFFECT_MULTIPLE, true, "auto: optically thin now (%.3g) but %s: on", tau,
                why_changes);
        else if (bound <= tol)
            say(out, EFFECT_MULTIPLE, false,
                "auto: optically thin along the light (diffuse light at most 2 x largest "
                "optical depth = %.3g <= %.3g, half a display level)",
                bound, tol);
        else
            say(out, EFFECT_MULTIPLE, true,
                "auto: largest optical depth along the light %.3g > %.3g (thin limit)", tau,
                0.5 * tol);
    }

    /* Lateral escape: only narrow cloud loses diffuse light through its sides. */
    bool multiple = out->on[EFFECT_MULTIPLE];
    if (out->multiple_volume) {
        say(out, EFFECT_LATERAL, false, "the diffuse light volume lets light out of every "
            "side itself (effects.multiple = \"volume\"): escape is the columns'");
    } else if (!decide_fixed(out, EFFECT_LATERAL, mode[EFFECT_LATERAL], EFFECT_MULTIPLE,
                             multiple)) {
        double share = facts->narrow_share;
        if (!facts->volume_known)
            say(out, EFFECT_LATERAL, true, "auto: volume not measured, on");
        else if (share < EFFECTS_NARROW_SHARE && changes)
            say(out, EFFECT_LATERAL, true, "auto: little narrow cloud now (%.3g %%) but %s: on",
                100.0 * share, why_changes);
        else if (share < EFFECTS_NARROW_SHARE)
            say(out, EFFECT_LATERAL, false,
                "auto: %.3g %% of the extinction is in cloud narrow enough to lose %g %% of its "
                "diffuse light per optical depth through its sides (< %g %%): the "
                "plane-parallel columns stand",
                100.0 * share, 100.0 * EFFECTS_NARROW_RATE, 100.0 * EFFECTS_NARROW_SHARE);
        else
            say(out, EFFECT_LATERAL, true,
                "auto: %.3g %% of the extinction is in cloud narrow enough to lose %g %% of its "
                "diffuse light per optical depth through its sides (>= %g %%)",
                100.0 * share, 100.0 * EFFECTS_NARROW_RATE, 100.0 * EFFECTS_NARROW_SHARE);
    }

    /* Per-species phase: one phase when one kind of particle is absent.  Decided from the
     * first step: a microphysics scheme that writes no ice species (WSM3) never has any. */
    out->single_phase_ice = facts->volume_known && facts->beta_ice_sum > facts->beta_water_sum;
    const char *single = out->single_phase_ice ? "ice" : "water";
    if (mode[EFFECT_PHASE] == EFFECT_OFF) {
        say(out, EFFECT_PHASE, false, "off in the config: the %s phase for every species%s",
            single, facts->volume_known ? " (the larger share of the extinction)" : "");
    } else if (mode[EFFECT_PHASE] == EFFECT_ON) {
        say(out, EFFECT_PHASE, true, "on in the config");
    } else if (!facts->volume_known) {
        say(out, EFFECT_PHASE, true, "auto: volume not measured, on");
    } else if (facts->beta_ice_sum <= 0.0 && facts->beta_water_sum <= 0.0) {
        say(out, EFFECT_PHASE, false, "auto: no extinction at all: one phase");
    } else if (facts->beta_ice_sum <= 0.0) {
        say(out, EFFECT_PHASE, false, "auto: no ice species (ice, snow, graupel) present: the "
            "water phase for all");
    } else if (facts->beta_water_sum <= 0.0) {
        say(out, EFFECT_PHASE, false, "auto: no water species (cloud, rain) present: the ice "
            "phase for all");
    } else {
        say(out, EFFECT_PHASE, true, "auto: ice and water species both present (ice share "
            "%.0f%%)", 100.0 * facts->beta_ice_sum /
                          (facts->beta_ice_sum + facts->beta_water_sum));
    }

    /* Ground shadow: only where the ground is drawn and seen. */
    if (!decide_fixed(out, EFFECT_GROUND_SHADOW, mode[EFFECT_GROUND_SHADOW], EFFECT_SHADOWS,
                      shadows)) {
        if (!cfg->render.ground_on)
            say(out, EFFECT_GROUND_SHADOW, false, "auto: the ground is not drawn "
                "(render.ground_on = false)");
        else if (!facts->views_known)
            say(out, EFFECT_GROUND_SHADOW, true, "auto: views not known, on");
        else if (!facts->ground_visible)
            say(out, EFFECT_GROUND_SHADOW, false, "auto: no view sees the ground");
        else
            say(out, EFFECT_GROUND_SHADOW, true, "auto: the ground is in view");
    }

    say(out, EFFECT_DETAIL, effects_detail_on(cfg),
        mode[EFFECT_DETAIL] == EFFECT_OFF  ? "off in the config"
        : mode[EFFECT_DETAIL] == EFFECT_ON ? "on in the config (detail.*: noise on the CPU when "
                                             "the volume is built)"
                                           : "auto: off (detail adds what the data lacks; ask "
                                             "for it with effects.detail = \"on\")");

    /* Temporal interpolation: blends step k and k + 1 during playback (two volumes and two
     * light maps on the GPU).  Nothing to blend with one step or a still render. */
    int steps = facts->time_steps;
    const char *temporal_on = mode[EFFECT_TEMPORAL] == EFFECT_ON ? "on in the config" : "auto";
    if (mode[EFFECT_TEMPORAL] == EFFECT_OFF)
        say(out, EFFECT_TEMPORAL, false, "off in the config");
    else if (steps == 1)
        say(out, EFFECT_TEMPORAL, false, "%s%s one time step, nothing to interpolate",
            temporal_on, mode[EFFECT_TEMPORAL] == EFFECT_ON ? ", but" : ":");
    else if (!facts->playback)
        say(out, EFFECT_TEMPORAL, false, "%s%s a still render shows one step, nothing plays",
            temporal_on, mode[EFFECT_TEMPORAL] == EFFECT_ON ? ", but" : ":");
    else if (steps > 1)
        say(out, EFFECT_TEMPORAL, true, "%s: %d time steps and playback can run: steps k and "
            "k + 1 are blended (two volumes, one light map per step)", temporal_on, steps);
    else
        say(out, EFFECT_TEMPORAL, true, "%s: time steps not known and playback can run, on",
            temporal_on);

    if (mode[EFFECT_DISTORTION] == EFFECT_OFF)
        say(out, EFFECT_DISTORTION, false, "off in the config");
    else if (facts->runtime_warps)
        say(out, EFFECT_DISTORTION, false, "%s: the OpenXR runtime warps for its lenses",
            mode[EFFECT_DISTORTION] == EFFECT_ON ? "on in the config, but" : "auto");
    else if (!facts->hmd)
        say(out, EFFECT_DISTORTION, false, "%s: not an HMD display, nothing to distort",
            mode[EFFECT_DISTORTION] == EFFECT_ON ? "on in the config, but" : "auto");
    else if (mode[EFFECT_DISTORTION] == EFFECT_ON)
        say(out, EFFECT_DISTORTION, true, "on in the config: HMD lens pre-distortion");
    else if (!facts->hmd_warp)
        say(out, EFFECT_DISTORTION, false, "auto: HMD display, but its config turns the lens "
            "warp off (hmd.warp = false)");
    else
        say(out, EFFECT_DISTORTION, true, "auto: HMD display, lens pre-distortion");

    if (!shadows)
        snprintf(out->light_builds, sizeof(out->light_builds), "no light map (shadows off)");
    else if (steps == 1 && !facts->sun_moves)
        snprintf(out->light_builds, sizeof(out->light_builds),
                 "built once, ever: one time step and a fixed sun (the rebuild-on-change key "
                 "keeps it for every view and frame)");
    else if (steps > 1)
        snprintf(out->light_builds, sizeof(out->light_builds),
                 "built once for each time step shown (the data has %d)%s%s, shared by every "
                 "view",
                 steps, facts->sun_moves ? " and whenever the sun moves" : "",
                 out->on[EFFECT_TEMPORAL] ? " (temporal: two held, blended)" : "");
    else
        snprintf(out->light_builds, sizeof(out->light_builds),
                 "built when the sun, the time step or a light map setting changes, shared by "
                 "every view");
}

void effects_apply_render(const struct effects *e, struct render_settings *s)
{
    s->single_phase = !e->on[EFFECT_PHASE];
    s->single_phase_ice = e->single_phase_ice;
    s->no_ground_shadow = !e->on[EFFECT_GROUND_SHADOW];
}

void effects_light_settings(const struct config *cfg, const struct effects *e,
                            struct light_settings *s)
{
    light_settings_defaults(s);
    for (int a = 0; a < 3; a++)
        s->resolution[a] = cfg->lightmap.resolution[a] < 2 ? 2 : cfg->lightmap.resolution[a];
    s->forward = e->on[EFFECT_FORWARD];
    s->peripheral = e->on[EFFECT_PERIPHERAL];
    s->multiple = e->on[EFFECT_MULTIPLE];
    s->volume = e->on[EFFECT_MULTIPLE] && e->multiple_volume;
    s->lateral = e->on[EFFECT_LATERAL];
    s->grid = (enum light_grid_kind)cfg->lightmap.grid; /* names in enum order */
    s->epsilon = cfg->lightmap.epsilon;
    light_settings_set_optics(s, &cfg->optics.params, cfg->lightmap.forward_angle_deg);
    if (!e->on[EFFECT_PHASE])
        light_settings_one_phase(s, e->single_phase_ice);
}
