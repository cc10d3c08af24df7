/* Effect decisions (app/effects.h): auto from scene facts, on/off from the config, the
 * prerequisites, the thin-medium bound, the phase choice, the volume and view measurements. */
#include <math.h>
#include <string.h>

#include "testutil.h"

#include "session/effects.h"
#include "common/log.h"
#include "data/synth.h"
#include "light/light.h"
#include "render/camera.h"

static void known_thick(struct effects_facts *f)
{
    effects_facts_init(f);
    f->volume_known = true;
    f->max_tau_light = 50.0;
    f->beta_ice_sum = 1.0;
    f->beta_water_sum = 3.0;
    f->narrow_share = 0.02;
    f->views_known = true;
    f->ground_visible = true;
    f->time_steps = 1;
}

static void test_unknown_facts_simulate_everything(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    struct effects e;
    effects_decide(&cfg, NULL, &e);
    assert_true(e.on[EFFECT_SHADOWS] && e.on[EFFECT_FORWARD] && e.on[EFFECT_PERIPHERAL]);
    /* Multiple scattering too: nothing says the volume is thin; and its lateral escape. */
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_true(e.on[EFFECT_LATERAL]);
    assert_non_null(strstr(e.reason[EFFECT_LATERAL], "not measured"));
    assert_true(e.on[EFFECT_PHASE] && e.on[EFFECT_GROUND_SHADOW]);
    assert_false(e.on[EFFECT_TEMPORAL]);
    assert_false(e.on[EFFECT_DISTORTION]);
    for (int i = 0; i < EFFECT_COUNT; i++)
        assert_true(strlen(e.reason[i]) > 0);
    assert_string_equal(effects_name(EFFECT_GROUND_SHADOW), "ground_shadow");
    /* The names follow the enum: a new effect shifts nothing. */
    assert_string_equal(effects_name(EFFECT_PERIPHERAL), "peripheral");
    assert_string_equal(effects_name(EFFECT_MULTIPLE), "multiple");
    assert_string_equal(effects_name(EFFECT_LATERAL), "lateral");
    assert_string_equal(effects_name(EFFECT_PHASE), "phase");
    assert_string_equal(effects_name(EFFECT_DISTORTION), "distortion");
    assert_string_equal(effects_name(EFFECT_COUNT), "?");
    /* ...and auto simulates it too when nothing is known. */
    assert_true(config_set(&cfg, "effects.multiple=auto"));
    effects_decide(&cfg, NULL, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "not measured"));
}

static void test_thin_medium_bound(void **state)
{
    /* Forward scattering adds at most CP(theta/2) tau to a light value: auto turns it off
     * exactly when that stays below the tolerance. */
    struct config cfg;
    config_defaults(&cfg);
    struct light_settings s;
    light_settings_defaults(&s);
    light_settings_set_optics(&s, &cfg.optics.params, cfg.lightmap.forward_angle_deg);
    double gain = fmax(s.cp.water_ctr + s.cp.water_per, s.cp.ice_ctr + s.cp.ice_per);
    assert_true(gain > 0.0 && gain < 1.0);
    double thin = EFFECTS_FORWARD_TOLERANCE / gain;
    struct effects_facts f;
    known_thick(&f);
    struct effects e;
    f.max_tau_light = 0.99 * thin;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_SHADOWS]); /* thin, but tau > tolerance: shadows still show */
    assert_false(e.on[EFFECT_FORWARD]);
    assert_false(e.on[EFFECT_PERIPHERAL]);
    assert_non_null(strstr(e.reason[EFFECT_FORWARD], "thin"));
    f.max_tau_light = 1.01 * thin;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_FORWARD] && e.on[EFFECT_PERIPHERAL]);
    /* Nothing in the volume: no shadows, and nothing that needs them. */
    f.max_tau_light = 0.0;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_SHADOWS] || e.on[EFFECT_FORWARD] || e.on[EFFECT_GROUND_SHADOW]);
    assert_non_null(strstr(e.reason[EFFECT_FORWARD], "effects.shadows"));
    assert_non_null(strstr(e.light_builds, "no light map"));
}

/* effects.multiple: the diffuse term adds at most 2 tau_max of the sun to the eye pass's
 * source; auto turns it off exactly when that is at most half a display level. */
static void test_multiple_thin_limit(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    assert_true(config_set(&cfg, "effects.multiple=auto")); /* the default is off */
    struct effects_facts f;
    known_thick(&f);
    struct effects e;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "auto: largest optical depth"));
    /* Shadows stay on above the tolerance; multiple is off below half of it. */
    double thin = 0.5 * EFFECTS_FORWARD_TOLERANCE;
    f.max_tau_light = 0.99 * thin;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_SHADOWS]); /* tau < tolerance: no shadows, nothing needs them */
    assert_false(e.on[EFFECT_MULTIPLE]);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "effects.shadows"));
    /* With shadows forced on, the thin limit itself decides. */
    assert_true(config_set(&cfg, "effects.shadows=on"));
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_SHADOWS]);
    assert_false(e.on[EFFECT_MULTIPLE]);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "optically thin"));
    f.max_tau_light = 1.01 * thin;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "thin limit"));
    /* Between the two limits (auto would drop shadows, tau <= tolerance): with shadows on,
     * multiple is on, since 2 tau > tolerance. */
    config_defaults(&cfg);
    assert_true(config_set(&cfg, "effects.multiple=auto"));
    f.max_tau_light = 0.75 * EFFECTS_FORWARD_TOLERANCE;
    assert_true(config_set(&cfg, "effects.shadows=on"));
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    /* Thin now, but the scene can change, or it was never measured: on. */
    f.max_tau_light = 0.5 * thin;
    f.time_steps = 3;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "several time steps"));
    f.time_steps = 1;
    f.sun_moves = true;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "the sun can move"));
    f.sun_moves = false;
    f.volume_known = false;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "not measured"));
}

/* effects.lateral: on when narrow cloud holds at least EFFECTS_NARROW_SHARE of the
 * extinction, off below; off with multiple scattering; on when the scene can change. */
static void test_lateral_narrow_share(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    struct effects_facts f;
    known_thick(&f);
    struct effects e;
    struct light_settings s;
    f.narrow_share = 1.01 * EFFECTS_NARROW_SHARE;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_LATERAL]);
    assert_non_null(strstr(e.reason[EFFECT_LATERAL], "through its sides (>="));
    effects_light_settings(&cfg, &e, &s);
    assert_true(s.multiple && s.lateral);
    f.narrow_share = 0.99 * EFFECTS_NARROW_SHARE;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_false(e.on[EFFECT_LATERAL]);
    assert_non_null(strstr(e.reason[EFFECT_LATERAL], "plane-parallel columns stand"));
    effects_light_settings(&cfg, &e, &s);
    assert_true(s.multiple && !s.lateral);
    /* The share can grow over the time steps: on. */
    f.time_steps = 4;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_LATERAL]);
    assert_non_null(strstr(e.reason[EFFECT_LATERAL], "several time steps"));
    f.time_steps = 1;
    /* Forced either way; and nothing to escape from without multiple scattering. */
    assert_true(config_set(&cfg, "effects.lateral=on"));
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_LATERAL]);
    assert_true(config_set(&cfg, "effects.multiple=off"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_LATERAL]);
    assert_non_null(strstr(e.reason[EFFECT_LATERAL], "effects.multiple"));
    config_defaults(&cfg);
    f.narrow_share = 0.5;
    assert_true(config_set(&cfg, "effects.lateral=off"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_LATERAL]);
    assert_non_null(strstr(e.reason[EFFECT_LATERAL], "off in the config"));
}

/* effects.multiple: on and off in the config, the shadows prerequisite, and the light map
 * settings that carry the decision. */
static void test_multiple_modes(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    struct effects_facts f;
    known_thick(&f);
    struct effects e;
    struct light_settings s;
    /* The default, auto, turns it on in a thick medium, and the light map is told. */
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    effects_light_settings(&cfg, &e, &s);
    assert_true(s.multiple);
    assert_true(config_set(&cfg, "effects.multiple=off"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_MULTIPLE]);
    assert_string_equal(e.reason[EFFECT_MULTIPLE], "off in the config");
    assert_true(e.on[EFFECT_SHADOWS] && e.on[EFFECT_FORWARD] && e.on[EFFECT_PERIPHERAL]);
    effects_light_settings(&cfg, &e, &s);
    assert_false(s.multiple);
    assert_true(s.forward && s.peripheral);
    /* on wins over a thin medium (thin, but thick enough that shadows stay on). */
    assert_true(config_set(&cfg, "effects.multiple=on"));
    f.max_tau_light = 0.25 * EFFECTS_FORWARD_TOLERANCE;
    assert_true(config_set(&cfg, "effects.shadows=on"));
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE]);
    assert_string_equal(e.reason[EFFECT_MULTIPLE], "on in the config");
    effects_light_settings(&cfg, &e, &s);
    assert_true(s.multiple);
    /* on, but shadows are off: no light map, so no diffuse term either. */
    assert_true(config_set(&cfg, "effects.shadows=off"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_MULTIPLE]);
    assert_string_equal(e.reason[EFFECT_MULTIPLE], "needs effects.shadows, which is off");
    effects_light_settings(&cfg, &e, &s);
    assert_false(s.multiple);
    /* Independent of forward scattering: forward off leaves multiple (auto) on. */
    config_defaults(&cfg);
    assert_true(config_set(&cfg, "effects.multiple=auto"));
    known_thick(&f);
    assert_true(config_set(&cfg, "effects.forward=off"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_FORWARD]);
    assert_true(e.on[EFFECT_MULTIPLE]);
    effects_light_settings(&cfg, &e, &s);
    assert_true(s.multiple && !s.forward);
    assert_false(s.volume); /* auto is the columns */
    /* volume: the diffuse light volume in place of the columns, lateral escape off (it is the
     * columns'); never without shadows; "volume" is no value for the other effects. */
    config_defaults(&cfg);
    known_thick(&f);
    assert_true(config_set(&cfg, "effects.multiple=volume"));
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_MULTIPLE] && e.multiple_volume);
    assert_non_null(strstr(e.reason[EFFECT_MULTIPLE], "volume in the config"));
    assert_false(e.on[EFFECT_LATERAL]);
    effects_light_settings(&cfg, &e, &s);
    assert_true(s.multiple && s.volume && !s.lateral);
    assert_true(config_set(&cfg, "effects.shadows=off"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_MULTIPLE]);
    effects_light_settings(&cfg, &e, &s);
    assert_false(s.multiple);
    assert_false(config_set(&cfg, "effects.lateral=volume"));
}

static void test_a_changing_scene_keeps_effects_on(void **state)
{
    /* A thin (or empty) first step says nothing about later steps or another sun: auto keeps
     * shadows and forward scattering on, and says why. */
    struct config cfg;
    config_defaults(&cfg);
    struct effects_facts f;
    struct effects e;
    known_thick(&f);
    f.max_tau_light = 0.0;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_SHADOWS] || e.on[EFFECT_FORWARD]);
    f.time_steps = 6;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_SHADOWS] && e.on[EFFECT_FORWARD] && e.on[EFFECT_PERIPHERAL]);
    assert_non_null(strstr(e.reason[EFFECT_SHADOWS], "several time steps"));
    f.time_steps = 1;
    f.sun_moves = true;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_SHADOWS] && e.on[EFFECT_FORWARD]);
    assert_non_null(strstr(e.reason[EFFECT_FORWARD], "the sun can move"));
    /* "off" in the config still wins. */
    cfg.effects.mode[EFFECT_SHADOWS] = EFFECT_OFF;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_SHADOWS] || e.on[EFFECT_FORWARD]);
}

static void test_thin_bound_holds_in_the_light_map(void **state)
{
    /* The bound behind the threshold: forward on minus off <= CP(theta/2) tau, node by node,
     * on a slab lit along an axis. */
    struct synth_desc d = {.kind = SYNTH_SLAB, .n = {8, 8, 8}, .extent_m = {1e3, 1e3, 1e3},
                           .tau = 0.5};
    struct optics_params optics;
    optics_params_defaults(&optics);
    struct ext_volume vol = {0};
    assert_true(synth_extinction(&d, &optics, &vol));
    struct light_settings s;
    light_settings_defaults(&s);
    s.resolution[0] = s.resolution[1] = s.resolution[2] = 16;
    light_settings_set_optics(&s, &optics, 20.0);
    double gain = fmax(s.cp.water_ctr + s.cp.water_per, s.cp.ice_ctr + s.cp.ice_per);
    double sun[3] = {0, 0, 1};
    struct light_map on = {0}, off = {0};
    assert_true(light_map_build(&vol, sun, &s, &on));
    s.forward = false;
    assert_true(light_map_build(&vol, sun, &s, &off));
    size_t count = (size_t)16 * 16 * 16;
    double worst = 0.0;
    for (size_t i = 0; i < count; i++) {
        double diff = on.light[i] - off.light[i];
        assert_true(diff >= -1e-6);
        worst = fmax(worst, diff);
    }
    assert_true(worst > 0.0);
    assert_true(worst <= gain * 0.5 * (1.0 + 1e-3));
    light_map_finish(&on);
    light_map_finish(&off);
    ext_volume_finish(&vol);
}

static void test_config_modes_and_prerequisites(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    struct effects_facts f;
    known_thick(&f);
    struct effects e;
    assert_true(config_set(&cfg, "effects.forward=off"));
    assert_true(config_set(&cfg, "effects.peripheral=on"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_FORWARD]);
    assert_false(e.on[EFFECT_PERIPHERAL]); /* on, but it needs forward */
    assert_non_null(strstr(e.reason[EFFECT_PERIPHERAL], "effects.forward"));
    assert_true(config_set(&cfg, "effects.shadows=off"));
    assert_true(config_set(&cfg, "effects.ground_shadow=on"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_SHADOWS] || e.on[EFFECT_GROUND_SHADOW]);
    /* On wins over a thin medium (thin, but thick enough that shadows stay on). */
    config_defaults(&cfg);
    assert_true(config_set(&cfg, "effects.forward=on"));
    f.max_tau_light = 1.5 * EFFECTS_FORWARD_TOLERANCE;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_FORWARD]);
    assert_string_equal(e.reason[EFFECT_FORWARD], "on in the config");
}

static void test_phase(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    struct effects_facts f;
    known_thick(&f);
    struct effects e;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_PHASE]);
    f.beta_ice_sum = 0.0;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_PHASE]);
    assert_false(e.single_phase_ice);
    assert_non_null(strstr(e.reason[EFFECT_PHASE], "no ice"));
    f.beta_ice_sum = 2.0;
    f.beta_water_sum = 0.0;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_PHASE]);
    assert_true(e.single_phase_ice);
    /* Forced off with both present: the larger share serves all, in both passes. */
    f.beta_water_sum = 5.0;
    assert_true(config_set(&cfg, "effects.phase=off"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_PHASE]);
    assert_false(e.single_phase_ice);
    struct light_settings s;
    effects_light_settings(&cfg, &e, &s);
    assert_true(s.cp.ice_ctr == s.cp.water_ctr && s.cp.ice_per == s.cp.water_per);
    struct render_settings rs = {0};
    effects_apply_render(&e, &rs);
    assert_true(rs.single_phase && !rs.single_phase_ice);
}

static void test_ground_views_display_time(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    struct effects_facts f;
    known_thick(&f);
    struct effects e;
    f.ground_visible = false;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_GROUND_SHADOW]);
    struct render_settings rs = {0};
    effects_apply_render(&e, &rs);
    assert_true(rs.no_ground_shadow);
    f.ground_visible = true;
    assert_true(config_set(&cfg, "render.ground_on=false"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_GROUND_SHADOW]);

    config_defaults(&cfg);
    f.hmd = true;
    f.hmd_warp = true;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_DISTORTION]);
    f.hmd_warp = false;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_DISTORTION]);
    assert_true(config_set(&cfg, "effects.distortion=on"));
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_DISTORTION]);
    f.hmd = false;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_DISTORTION]);

    assert_non_null(strstr(e.light_builds, "once, ever"));
    f.time_steps = 4;
    effects_decide(&cfg, &f, &e);
    assert_non_null(strstr(e.light_builds, "the data has 4"));
    f.time_steps = 1;
    f.sun_moves = true;
    effects_decide(&cfg, &f, &e);
    assert_null(strstr(e.light_builds, "once, ever"));
}

/* effects.temporal: auto is on only when there are several steps and time can play. */
static void test_temporal_auto(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    struct effects_facts f;
    known_thick(&f);
    struct effects e;
    /* One step: nothing to blend, even when playback runs or the config asks. */
    f.playback = true;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_TEMPORAL]);
    assert_non_null(strstr(e.reason[EFFECT_TEMPORAL], "one time step"));
    /* Several steps and playback (anvil run, a script): on. */
    f.time_steps = 6;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_TEMPORAL]);
    assert_non_null(strstr(e.reason[EFFECT_TEMPORAL], "auto: 6 time steps"));
    assert_non_null(strstr(e.light_builds, "two held"));
    /* A still render of a series: off, and says why. */
    f.playback = false;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_TEMPORAL]);
    assert_non_null(strstr(e.reason[EFFECT_TEMPORAL], "still render"));
    assert_null(strstr(e.light_builds, "two held"));
    /* Steps not known but playing: the full simulation. */
    f.playback = true;
    f.time_steps = 0;
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_TEMPORAL]);
    /* off always wins; on still needs something to blend. */
    f.time_steps = 6;
    assert_true(config_set(&cfg, "effects.temporal=off"));
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_TEMPORAL]);
    assert_string_equal(e.reason[EFFECT_TEMPORAL], "off in the config");
    assert_true(config_set(&cfg, "effects.temporal=on"));
    effects_decide(&cfg, &f, &e);
    assert_true(e.on[EFFECT_TEMPORAL]);
    assert_non_null(strstr(e.reason[EFFECT_TEMPORAL], "on in the config"));
    f.time_steps = 1;
    effects_decide(&cfg, &f, &e);
    assert_false(e.on[EFFECT_TEMPORAL]);
    /* Pure: the same inputs give the same decision and reason. */
    struct effects again;
    effects_decide(&cfg, &f, &again);
    assert_string_equal(e.reason[EFFECT_TEMPORAL], again.reason[EFFECT_TEMPORAL]);
}

static void test_measure_volume(void **state)
{
    /* A slab of vertical optical depth 3 lit from 30 degrees elevation: the longest path
     * through it along the light is 3 / sin(30) = 6 where it crosses the whole slab (the slab
     * is wide enough for such columns), up to the midpoint rule at the faces: half a sample
     * (tau 0.19 here) at each end. */
    struct synth_desc d = {.kind = SYNTH_SLAB, .n = {32, 32, 16}, .extent_m = {40e3, 40e3, 1e3},
                           .tau = 3.0, .ice_phase = true};
    struct optics_params optics;
    optics_params_defaults(&optics);
    struct ext_volume vol = {0};
    assert_true(synth_extinction(&d, &optics, &vol));
    double sun[3];
    light_sun_direction(45.0, 30.0, sun);
    struct effects_facts f;
    effects_facts_init(&f);
    assert_true(effects_measure_volume(&vol, sun, &optics, &f));
    assert_true(f.volume_known);
    assert_true(fabs(f.max_tau_light - 6.0) < 0.4);
    assert_true(f.beta_ice_sum > 0.0 && f.beta_water_sum == 0.0);
    /* 120 optical depths wide, 30 transport mean free paths of ice: nothing narrow. */
    assert_true(f.narrow_share == 0.0);
    ext_volume_finish(&vol);

    /* A ball of optical diameter 2 is narrow throughout (0.3 transport mean free paths of
     * water: escape 0.46 per optical depth at its centre); one of diameter 200 only near its
     * rim, where its chords are short. */
    struct synth_desc ball = {.kind = SYNTH_SPHERE, .n = {32, 32, 32},
                              .extent_m = {10e3, 10e3, 10e3}, .tau = 2.0};
    assert_true(synth_extinction(&ball, &optics, &vol));
    assert_true(effects_measure_volume(&vol, sun, &optics, &f));
    print_message("ball of optical diameter 2: narrow share %.3f\n", f.narrow_share);
    assert_true(f.narrow_share > 0.99);
    ext_volume_finish(&vol);
    ball.tau = 200.0;
    assert_true(synth_extinction(&ball, &optics, &vol));
    assert_true(effects_measure_volume(&vol, sun, &optics, &f));
    print_message("ball of optical diameter 200: narrow share %.3f\n", f.narrow_share);
    assert_true(f.narrow_share > 0.0 && f.narrow_share < 0.1);
    ext_volume_finish(&vol);

    /* Empty: zero, exactly. */
    struct synth_desc empty = {.kind = SYNTH_EMPTY, .n = {8, 8, 8}, .extent_m = {1e3, 1e3, 1e3}};
    assert_true(synth_extinction(&empty, &optics, &vol));
    assert_true(effects_measure_volume(&vol, sun, &optics, &f));
    assert_true(f.max_tau_light == 0.0);
    assert_true(f.narrow_share == 0.0);
    ext_volume_finish(&vol);
}

static void test_view_sees_ground(void **state)
{
    struct render_view v;
    double up[3] = {0, 0, 1};
    double eye[3] = {0, 0, 1000}, down[3] = {100, 0, 0}, sky[3] = {0, 0, 5000};
    camera_look_at(eye, down, up, 50.0, 1.0, 1e6, 64, 48, &v);
    assert_true(effects_view_sees_ground(&v));
    double upy[3] = {0, 1, 0};
    camera_look_at(eye, sky, upy, 50.0, 1.0, 1e6, 64, 48, &v);
    assert_false(effects_view_sees_ground(&v));
    double below[3] = {0, 0, -10}, ahead[3] = {100, 0, -10};
    camera_look_at(below, ahead, up, 50.0, 1.0, 1e6, 64, 48, &v);
    assert_false(effects_view_sees_ground(&v)); /* the ground is opaque from above only */
}

int main(void)
{
    log_set_level(LOG_WARN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unknown_facts_simulate_everything),
        cmocka_unit_test(test_thin_medium_bound),
        cmocka_unit_test(test_multiple_thin_limit),
        cmocka_unit_test(test_lateral_narrow_share),
        cmocka_unit_test(test_multiple_modes),
        cmocka_unit_test(test_a_changing_scene_keeps_effects_on),
        cmocka_unit_test(test_thin_bound_holds_in_the_light_map),
        cmocka_unit_test(test_config_modes_and_prerequisites),
        cmocka_unit_test(test_phase),
        cmocka_unit_test(test_ground_views_display_time),
        cmocka_unit_test(test_temporal_auto),
        cmocka_unit_test(test_measure_volume),
        cmocka_unit_test(test_view_sees_ground),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
