/* The session: what the program holds while it runs, changed only through its setters. */
#include "session/session.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cglm/cglm.h>

#include "common/log.h"
#include "config/transfer_file.h"
#include "gpu/gpu.h"
#include "light/light.h"
#include "menu/menu.h"
#include "render/camera.h"
#include "session/camera_path.h"
#include "session/effects.h"
#include "session/lightmaps.h"
#include "session/map.h"
#include "session/menu_view.h"
#include "session/overlay_view.h"
#include "session/probe_view.h"
#include "session/scene.h"

#define SOURCES_MAX 2
#define FLY_SPEED 1.0   /* tracker metres per second at full deflection */
#define TURN_SPEED 45.0 /* degrees per second */
#define NAV_STEP 0.1    /* tracker metres per key press */
#define TURN_STEP 5.0   /* degrees per key press */
#define DRAG_DEG 0.3    /* degrees per pixel dragged */

/* The share of the last frame's time that one session_prepare may spend between two frames
 * (docs/architecture.md, "Time series": a frame and the work after it against the step
 * rate). */
#define PREPARE_SHARE 0.5

struct session {
    struct config cfg; /* read once by session_create; never written */
    struct session_desc desc;
    struct display_config display;
    bool tracker; /* the views are in tracker space (not the orbit camera) */
    char transfers_dir[CONFIG_PATH_MAX];

    struct renderer *renderer;
    struct render_settings base; /* from the config, the effects and the map */
    struct session_stats stats;
    struct lightmaps light;
    struct effects effects;
    struct scene_map *map;
    int map_step; /* the step whose map (terrain, coastlines, graticule) MAP is: a moving
                     domain's follows the step shown (follow_domain) */
    struct player *player;

    /* What the setters change. */
    struct session_settings settings;
    double sun_az, sun_el;
    struct playback playback;
    struct display_navigation nav, nav_home;
    struct display_camera camera, camera_home;
    /* The views framing the whole domain (Shift+F, the menu's Frame): the orbit camera's and
     * a tracked display's navigation fitting it to the room. */
    struct display_camera camera_frame;
    struct display_navigation nav_frame;
    bool quit;
    unsigned requests; /* SESSION_REQUEST_*, for the caller (session_take_requests) */

    /* The camera path keys are added to (N) and flown along (G). */
    struct camera_path *path;
    char path_file[CONFIG_PATH_MAX]; /* where it is saved on every new key; "" nowhere */
    bool path_playing;
    double path_time;

    /* Staged playback (a run of a series): the step after the one shown is readied between
     * frames (session_prepare), its volume through the renderer's pixel buffer and its light
     * map built, so that the step change is a swap of textures on the GPU. */
    bool staged;
    const struct ext_volume *stage_src; /* the next volume waiting for the pixel buffer */
    struct ext_volume probe_next;       /* with the probe: the staged step's extinction on the
                                           CPU, swapped with probe_volume at its step change */
    uint64_t probe_next_id;             /* its step (player_step_id), 0: none */
    double frame_start_ms, frame_ms;    /* the last frame's session_apply .. session_draw */
    double piece_ms[SESSION_PIECE_KINDS]; /* the last piece of each kind, wall ms (its estimate) */
    double upload_rate, copy_rate;        /* the last slab's bytes per wall ms (0: none yet) */

    /* What the last session_apply made the GPU hold. */
    int shown;                /* the step on screen */
    struct render_settings drawn; /* base with the frame's sun and temporal blend */
    struct frame_state applied;
    bool have_applied;

    /* The information overlay (overlay.when), and what it showed last. */
    struct overlay_view *overlay;
    struct overlay_model overlay_model;

    /* The probe (desc.probe): its reader of the data, the extinction of the step on screen on
     * the CPU (rank 0 marches it for the point), the point rank 0 picked last, and what the
     * panel showed, with what it was read for. */
    struct probe *probe;
    struct probe_view *probe_view;
    struct ext_volume probe_volume;
    uint64_t probe_volume_id;
    bool probe_picked;
    double probe_pick[3];
    struct probe_values probe_values;
    bool probe_read_ok;
    struct ext_volume first_histogram; /* the first step's histogram until the menu has it */
    struct {
        bool valid;
        double point[3];
        uint64_t volume;
        unsigned builds;
        int mode;
        bool wand;
    } probe_key;

    /* The menu and its sources (desc.menu); or a copy of another's (session_show_menu_state). */
    struct menu *menu;
    struct menu_view *menu_view;
    struct menu_view_state remote;
    uint8_t *remote_pixels;
    struct input_source *sources[SOURCES_MAX];
    int n_sources;
    struct input_source *script;
    struct input_queue queue;
    long frame;
    int view_size[2]; /* the orbit view's, as last drawn: the world menu follows it */
    bool placed;
    bool grabbing, drag_blocked;
    float grab_wand[3];
    double grab_position[3];
    float wand_pos[3], wand_dir[3];
    bool have_wand;
    /* A tracked wand dragging the selected slice (trigger held off the menu on the Slices
     * page): the wand's world position and the slice's position along its axis at the press. */
    bool slice_wand;
    double slice_wand_from[3], slice_wand_position, slice_wand_tilt;
    float wand_up[3], slice_wand_up[3]; /* the wand's up (tracker space), now and at the press */
    bool have_up, slice_wand_has_up;
    float axis[INPUT_AXIS_COUNT];
    /* A recording's head (input_script_frame): the frame states carry it, not the display's. */
    bool head_given;
    struct display_pose head;
    bool eyes_given; /* a recording's eyes relative to its head (a runtime's, OpenXR) */
    struct display_pose eyes[2];
};

/* ---- creation ------------------------------------------------------------------------- */

static const char *date_of(void *user, int step)
{
    return player_step_date(user, step);
}

static void model_from_session(struct session *s, struct menu_model *m)
{
    memset(m, 0, sizeof(*m));
    m->playing = s->playback.playing;
    m->loop = s->playback.loop;
    m->speed = s->playback.speed;
    m->step = s->playback.step;
    m->step_count = s->playback.count;
    player_species_present(s->player, m->species_present);
    const struct look *look = &s->settings.look;
    for (int f = 0; f < SPECIES_COUNT; f++) {
        m->species_on[f] = look->select.enabled[f];
        m->species_scale[f] = look->select.scale[f];
        memcpy(m->species_tint[f], look->tint.rgb[f], sizeof(m->species_tint[f]));
    }
    m->transfer_on = look->layer_count > 0 && look->layers[look_edited_layer(look)].enabled;
    look_edited_transfer(look, &m->transfer);
    m->layer_count = look->layer_count;
    memcpy(m->layers, look->layers, sizeof(m->layers));
    m->layer_edited = look_edited_layer(look);
    m->slice_count = look->slice_count;
    for (int i = 0; i < look->slice_count; i++) {
        m->slices[i].slice = look->slices[i];
        menu_slice_from_plane(&m->slices[i]);
    }
    m->slice_selected = 0;
    const struct grid3 *box = renderer_grid(s->renderer);
    for (int a = 0; a < 3; a++) {
        m->box_min_m[a] = box->origin[a];
        m->box_max_m[a] = box->origin[a] + box->n[a] * box->spacing[a];
    }
    m->sun_azimuth = fmod(s->sun_az + 360.0, 360.0);
    m->sun_elevation = s->sun_el;
    m->step_m = s->settings.step_m;
    m->lod_pixels = s->settings.lod_pixels;
    const struct grid3 *g = renderer_grid(s->renderer);
    double smin = fmin(g->spacing[0], fmin(g->spacing[1], g->spacing[2]));
    m->step_max_m = smin > 0.0 ? 4.0 * smin : 2000.0;
    m->light_resolution = s->settings.light_resolution[0];
    m->epsilon = s->settings.epsilon;
    m->diffuse_possible = s->effects.on[EFFECT_SHADOWS];
    m->diffuse_on = m->diffuse_possible && s->settings.diffuse;
    const struct probe_settings *ps = &s->settings.probe;
    m->probe_on = ps->on;
    m->probe_mode = ps->mode == PROBE_AT_DISTANCE ? MENU_PROBE_AT_DISTANCE
                                                  : MENU_PROBE_FIRST_VISIBLE;
    m->probe_threshold = ps->threshold;
    m->probe_distance_m = ps->distance_m;
    double diag = 0.0;
    for (int a = 0; a < 3; a++)
        diag += pow(g->n[a] * g->spacing[a], 2.0);
    m->probe_distance_max_m = fmax(2.0 * sqrt(diag), ps->distance_m);
}

/* The extinction of V kept on the CPU for the probe (the step on screen). */
static bool keep_probe_volume(struct session *s, const struct ext_volume *v)
{
    size_t n = grid3_count(&v->grid);
    if (!s->probe_volume.beta || grid3_count(&s->probe_volume.grid) != n) {
        ext_volume_finish(&s->probe_volume);
        if (!ext_volume_init(&s->probe_volume, &v->grid))
            return false;
    }
    s->probe_volume.grid = v->grid;
    memcpy(s->probe_volume.beta, v->beta, 2 * n * sizeof(float));
    s->probe_volume_id++;
    return true;
}

/* Staged playback: room for V's extinction for the probe until V's step is shown (the stage's
 * thread copies it there). */
static bool room_probe_next(struct session *s, const struct ext_volume *v)
{
    size_t n = grid3_count(&v->grid);
    s->probe_next_id = 0;
    if (!s->probe_next.beta || grid3_count(&s->probe_next.grid) != n) {
        ext_volume_finish(&s->probe_next);
        if (!ext_volume_init(&s->probe_next, &v->grid))
            return false;
    }
    s->probe_next.grid = v->grid;
    return true;
}

/* The histogram of the volume just shown into the menu's transfer editor. */
static void show_histogram(struct session *s, const struct ext_volume *v)
{
    if (!s->menu || !v->histogram)
        return;
    struct menu_model *m = menu_model(s->menu);
    m->histogram = *v->histogram;
    m->histogram_valid = true;
    menu_model_changed(s->menu);
}

/* Staged playback: the staged volume goes (its copy finished first: the volume it reads may
 * go next).  The step change that wanted it uploads as before. */
static void drop_staged(struct session *s)
{
    if (!s->staged)
        return;
    renderer_stage_cancel(s->renderer);
    s->stage_src = NULL;
    s->probe_next_id = 0;
}

/* The facts, gathered once: the first volume, the display, what can change while running. */
static bool decide_effects(struct session *s, const struct ext_volume *vol)
{
    struct effects_facts facts;
    struct effects_context c = {
        .time_steps = player_step_count(s->player),
        /* anvil run plays time and moves the sun; a render plays only when a script does. */
        .playback = s->desc.playback,
        .sun_moves = s->desc.interactive || s->desc.replay_of_run,
        .display = &s->display,
        .views = s->desc.views,
        .view_count = s->desc.view_count,
        .views_known = !s->desc.views_move,
    };
    if (!effects_gather(&s->cfg, vol, &c, &facts))
        return false;
    effects_decide(&s->cfg, &facts, &s->effects);
    for (int e = 0; e < EFFECT_COUNT; e++)
        log_debug("effect %s: %s (%s)", effects_name(e), s->effects.on[e] ? "on" : "off",
                  s->effects.reason[e]);
    lightmaps_set_effects(&s->light, &s->effects);
    return true;
}

static bool widget_known(const char *name, void *menu)
{
    return menu_widget_known(menu, name);
}

static bool create_menu(struct session *s)
{
    const struct session_desc *d = &s->desc;
    if (d->script) {
        s->script = input_script_open(d->script);
        if (!s->script)
            return false;
        s->sources[s->n_sources++] = s->script;
    }
    /* The display's wand (wand.*; anvil's --wand NAME makes it an OpenHMD controller). */
    const struct display_wand *wand = &s->display.wand;
    struct input_source *w = NULL;
    if (wand->source == DISPLAY_WAND_OPENHMD) {
        w = input_ohmd_create(wand->device, NULL);
    } else if (wand->source == DISPLAY_WAND_DTRACK || wand->source == DISPLAY_WAND_VRPN) {
        struct tracker_wand_desc wd;
        display_wand_desc(&s->display, &wd);
        w = tracker_wand_create(&wd);
    }
    if (wand->source != DISPLAY_WAND_NONE) {
        if (!w)
            return false;
        s->sources[s->n_sources++] = w;
    }
    struct menu_model model;
    model_from_session(s, &model);
    s->menu = menu_create(&(struct menu_desc){.step_date = date_of, .user = s->player}, &model);
    if (!s->menu)
        return false;
    /* A misspelled widget is a bad line of the script, not a warning at its frame. */
    if (s->script && !input_script_check_aims(s->script, widget_known, s->menu))
        return false;
    menu_set_visible(s->menu, d->show_menu);
    menu_take_changes(s->menu);
    s->menu_view = menu_view_create(s->renderer);
    return s->menu_view != NULL;
}

/* The framing views of the volume's box G, for the frame key.  The views the session starts
 * with are the config's and the display's: where those give none, the command line put the
 * same framing there (app_frame_camera, app_frame_navigation). */
static void frame_views(struct session *s, const struct grid3 *g)
{
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = g->origin[a];
        hi[a] = g->origin[a] + g->n[a] * g->spacing[a];
    }
    const struct config_camera *c = &s->cfg.camera;
    scene_frame_camera(lo, hi, c->fov_deg, (double)s->cfg.render.width / s->cfg.render.height,
                       c->near_m, &s->camera_frame);
    s->nav_frame = s->nav;
    enum display_type t = s->display.type;
    bool room = t == DISPLAY_TYPE_CAVE || t == DISPLAY_TYPE_HMD || t == DISPLAY_TYPE_OPENXR;
    if (room && s->desc.room_navigation)
        s->nav_frame = *s->desc.room_navigation;
    else if (room)
        scene_frame_navigation(lo, hi, &s->display, &s->nav_frame);
    s->nav.given = s->nav_home.given = s->nav_frame.given = false; /* not frame state */
}

struct session *session_create(const struct config *cfg, const struct session_desc *d, int *rc)
{
    *rc = 4;
    struct session *s = calloc(1, sizeof(*s));
    if (!s) {
        log_error("out of memory");
        return NULL;
    }
    s->cfg = *cfg;
    s->desc = *d;
    s->stats.command = d->command;
    if (d->display)
        s->display = *d->display;
    else
        display_config_defaults(&s->display), s->display.type = DISPLAY_TYPE_ORBIT;
    s->desc.display = &s->display;
    s->tracker = s->display.type != DISPLAY_TYPE_ORBIT;
    snprintf(s->transfers_dir, sizeof(s->transfers_dir), "%s",
             d->transfers_dir ? d->transfers_dir : ".");
    s->sun_az = cfg->light.azimuth_deg;
    s->sun_el = cfg->light.elevation_deg;
    s->nav = s->nav_home = s->display.navigation;
    scene_camera(cfg, &s->camera);
    s->camera_home = s->camera;
    look_from_config(cfg, &s->settings.look);
    s->settings.step_m = cfg->render.step_m;
    s->settings.lod_pixels = cfg->render.lod_pixels;
    memcpy(s->settings.light_resolution, cfg->lightmap.resolution,
           sizeof(s->settings.light_resolution));
    s->settings.epsilon = cfg->lightmap.epsilon;
    probe_settings_from_config(cfg, &s->settings.probe);

    /* The data, opened once: the first step now, the rest behind a cache when time can play. */
    double t = time_now_ms();
    s->player = player_create(cfg, &(struct player_desc){.still = !d->playback,
                                                         .delay_ms = d->load_delay_ms,
                                                         .histogram = d->menu});
    if (!s->player) {
        *rc = 1;
        goto error;
    }
    struct ext_volume vol = {0};
    player_take_first(s->player, &vol);
    s->stats.volume_ms = time_now_ms() - t;
    log_info("volume %dx%dx%d (%.1f x %.1f x %.1f km) built in %.0f ms", vol.grid.n[0],
             vol.grid.n[1], vol.grid.n[2], vol.grid.n[0] * vol.grid.spacing[0] / 1000.0,
             vol.grid.n[1] * vol.grid.spacing[1] / 1000.0,
             vol.grid.n[2] * vol.grid.spacing[2] / 1000.0, s->stats.volume_ms);
    frame_views(s, &vol.grid);
    if (!decide_effects(s, &vol)) {
        ext_volume_finish(&vol);
        *rc = 1;
        goto error;
    }
    s->settings.diffuse = s->effects.on[EFFECT_MULTIPLE];
    s->renderer = renderer_create();
    bool ok = s->renderer != NULL;
    if (ok) {
        /* Views are timed only when reported: on a software driver a timed view waits for
         * itself (gpu.h, "timers"). */
        renderer_set_timing(s->renderer, d->time_views ? &s->stats.view_times : NULL);
        renderer_set_half(s->renderer, cfg->render.precision == PRECISION_HALF);
        renderer_set_counting(s->renderer, d->count_rays);
        ok = renderer_set_optics(s->renderer, &cfg->optics.params) &&
             renderer_set_volume(s->renderer, &vol);
    }
    if (ok && d->probe) {
        s->probe = probe_create(cfg);
        if (!s->probe)
            *rc = 1;
        ok = s->probe && keep_probe_volume(s, &vol);
    }
    /* The first step's histogram for the menu, made below (a copy: the cache keeps the step's
     * own for when it is shown again). */
    if (vol.histogram) {
        s->first_histogram.histogram = malloc(sizeof(*vol.histogram));
        if (s->first_histogram.histogram)
            *s->first_histogram.histogram = *vol.histogram;
    }
    player_keep_first(s->player, &vol);
    if (!ok)
        goto error;
    s->stats.upload_ms = renderer_stats(s->renderer)->upload_ms;
    if (!lightmaps_init(&s->light, cfg))
        goto error;
    lightmaps_set_effects(&s->light, &s->effects);
    lightmaps_set_timing(&s->light, &s->stats.build_times);
    bool moves;
    s->map_step = cfg->scene.kind == SCENE_DATA ? cfg->data.step : 0; /* the first step shown */
    s->map =
        scene_map_create(cfg, s->renderer, player_wrf_step_meta(s->player, s->map_step, &moves));
    if (!s->map)
        goto error;
    scene_render_settings(cfg, &s->base);
    scene_map_apply_settings(s->map, &s->base);
    effects_apply_render(&s->effects, &s->base);
    s->drawn = s->base;
    s->stats.device = gpu_renderer_name();
    playback_init(&s->playback, player_step_count(s->player),
                  cfg->scene.kind == SCENE_DATA ? cfg->data.step : 0, cfg->playback.speed,
                  cfg->playback.loop);
    s->shown = s->playback.step;
    s->staged = d->interactive && d->playback && !d->unstaged && s->playback.count > 1;
    s->view_size[0] = cfg->render.width;
    s->view_size[1] = cfg->render.height;
    enum overlay_when when = cfg->overlay.when;
    if (when == OVERLAY_ALWAYS || (when == OVERLAY_RUN && d->interactive)) {
        s->overlay = overlay_view_create(s->renderer, cfg);
        if (!s->overlay)
            goto error;
    }
    if (d->probe && !(s->probe_view = probe_view_create(s->renderer)))
        goto error;
    if (d->menu && !create_menu(s)) {
        *rc = 1;
        goto error;
    }
    show_histogram(s, &s->first_histogram);
    ext_volume_finish(&s->first_histogram);
    *rc = 0;
    return s;

error:
    session_destroy(s);
    return NULL;
}

void session_destroy(struct session *s)
{
    if (!s)
        return;
    free(s->path);
    free(s->remote_pixels);
    menu_view_destroy(s->menu_view, s->renderer); /* its meshes leave the renderer */
    overlay_view_destroy(s->overlay, s->renderer);
    probe_view_destroy(s->probe_view, s->renderer);
    probe_destroy(s->probe);
    ext_volume_finish(&s->probe_volume);
    ext_volume_finish(&s->probe_next);
    ext_volume_finish(&s->first_histogram);
    menu_destroy(s->menu);
    for (int i = 0; i < s->n_sources; i++)
        input_source_destroy(s->sources[i]);
    if (s->renderer)
        drop_staged(s); /* its copy reads a volume of the player's */
    player_destroy(s->player);
    lightmaps_finish(&s->light);
    scene_map_destroy(s->map, s->renderer);
    renderer_destroy(s->renderer);
    free(s);
}

/* ---- setters -------------------------------------------------------------------------- */

void session_get_settings(const struct session *s, struct session_settings *out)
{
    *out = s->settings;
}

void session_set_settings(struct session *s, const struct session_settings *in)
{
    bool look = memcmp(&in->look, &s->settings.look, sizeof(in->look)) != 0;
    bool diffuse = in->diffuse && s->effects.on[EFFECT_SHADOWS];
    if (diffuse != s->effects.on[EFFECT_MULTIPLE]) {
        /* The diffuse light, and lateral escape with it (on unless the config turns it off:
         * the scene's narrow share was decided for the multiple scattering it had). */
        struct effects *e = &s->effects;
        e->on[EFFECT_MULTIPLE] = diffuse;
        snprintf(e->reason[EFFECT_MULTIPLE], sizeof(e->reason[EFFECT_MULTIPLE]),
                 "%s from the menu", diffuse ? "on" : "off");
        bool lateral = diffuse && s->cfg.effects.mode[EFFECT_LATERAL] != EFFECT_OFF;
        if (lateral != e->on[EFFECT_LATERAL]) {
            e->on[EFFECT_LATERAL] = lateral;
            snprintf(e->reason[EFFECT_LATERAL], sizeof(e->reason[EFFECT_LATERAL]),
                     "%s with the diffuse light, from the menu", lateral ? "on" : "off");
        }
        lightmaps_set_effects(&s->light, e);
        log_info("diffuse light (multiple scattering) %s", diffuse ? "on" : "off");
    }
    s->settings = *in;
    s->settings.diffuse = diffuse;
    if (look) {
        if (player_has_fields(s->player)) {
            drop_staged(s); /* its copy reads a volume the series is about to drop */
            player_set_look(s->player, &s->settings.look);
        }
        else if (s->menu)
            menu_set_status(s->menu, "this scene has no mass ratios to change");
    }
}

void session_set_sun(struct session *s, double azimuth_deg, double elevation_deg)
{
    s->sun_az = fmod(azimuth_deg, 360.0);
    s->sun_el = fmin(90.0, fmax(-10.0, elevation_deg));
}

void session_set_step(struct session *s, int step)
{
    s->playback.step = step < 0 ? 0 : step >= s->playback.count ? s->playback.count - 1 : step;
    s->playback.acc = 0.0;
}

void session_set_time(struct session *s, double t)
{
    double top = s->playback.count - 1;
    t = t < 0.0 ? 0.0 : t > top ? top : t;
    s->playback.step = (int)floor(t);
    s->playback.acc = t - s->playback.step;
    if (s->playback.step >= s->playback.count - 1) {
        s->playback.step = s->playback.count - 1;
        s->playback.acc = 0.0;
    }
}

bool session_set_camera_path(struct session *s, const struct camera_path *p, const char *file)
{
    if (!s->path && !(s->path = calloc(1, sizeof(*s->path)))) {
        log_error("out of memory");
        return false;
    }
    if (p)
        *s->path = *p;
    else
        s->path->count = 0;
    snprintf(s->path_file, sizeof(s->path_file), "%s", file ? file : "");
    s->path_playing = false;
    return true;
}

/* The current view as the path's next key, 3 s after the last, saved to the path's file. */
static void path_add_key(struct session *s)
{
    if (!s->path && !session_set_camera_path(s, NULL, NULL))
        return;
    struct camera_path *p = s->path;
    if (p->count == CAMERA_PATH_MAX) {
        log_warn("camera path: it holds %d keys already", CAMERA_PATH_MAX);
        return;
    }
    double t = p->count ? p->keys[p->count - 1].time_s + 3.0 : 0.0;
    if (p->count == 0)
        p->has_steps = s->playback.count > 1;
    camera_path_key(&s->camera, t, s->playback.step + s->playback.acc, &p->keys[p->count++]);
    if (s->path_file[0] && camera_path_save(s->path_file, p))
        log_info("camera path: key %d at %.1f s, saved to %s", p->count, t, s->path_file);
    else if (!s->path_file[0])
        log_info("camera path: key %d at %.1f s (--path FILE saves it)", p->count, t);
}

static void path_toggle(struct session *s)
{
    if (!s->path || s->path->count < 2) {
        log_warn("camera path: it needs two keys to fly (N adds the current view)");
        return;
    }
    s->path_playing = !s->path_playing;
    s->path_time = 0.0;
    log_info("camera path: %s", s->path_playing ? "flying" : "stopped");
}

/* Flies the path by DT seconds; at its end it stops there. */
static void path_fly(struct session *s, double dt)
{
    if (!s->path_playing || s->tracker)
        return;
    s->path_time += dt > 0.0 ? dt : 0.0;
    double step = -1.0;
    camera_path_eval(s->path, s->path_time, &s->camera, &s->camera, &step);
    if (step >= 0.0)
        session_set_time(s, step);
    if (s->path_time >= camera_path_duration(s->path)) {
        s->path_playing = false;
        log_info("camera path: at its end");
    }
}

unsigned session_take_requests(struct session *s)
{
    unsigned r = s->requests;
    s->requests = 0;
    return r;
}

void session_view_text(const struct session *s, char *buf, size_t size)
{
    const struct display_camera *c = &s->camera;
    const struct display_navigation *n = &s->nav;
    if (s->tracker) {
        snprintf(buf, size,
                 "navigation = {\n    scale = %.9g;\n    origin = [%.6f, %.6f, %.6f];\n"
                 "    position = [%.6f, %.6f, %.6f];\n    orientation = [%.6f, %.6f, %.6f];\n};\n",
                 n->scale, n->origin_km[0], n->origin_km[1], n->origin_km[2], n->position[0],
                 n->position[1], n->position[2], n->orientation_deg[0], n->orientation_deg[1],
                 n->orientation_deg[2]);
    } else {
        /* Every digit (a framed camera's numbers are not round, and the bookmark must render
         * the same picture), each a real number to libconfig. */
        const double v[12] = {c->eye[0] / 1000.0,    c->eye[1] / 1000.0,    c->eye[2] / 1000.0,
                              c->target[0] / 1000.0, c->target[1] / 1000.0, c->target[2] / 1000.0,
                              c->up[0],              c->up[1],              c->up[2],
                              c->fov_deg,            c->near_m,             c->far_m / 1000.0};
        char t[12][32];
        for (int i = 0; i < 12; i++) {
            snprintf(t[i], sizeof(t[i]), "%.17g", v[i]);
            if (!strpbrk(t[i], ".eEn"))
                strcat(t[i], ".0");
        }
        snprintf(buf, size,
                 "camera = {\n    position = [%s, %s, %s];\n    target = [%s, %s, %s];\n"
                 "    up = [%s, %s, %s];\n    fov = %s;\n    near = %s;\n    far = %s;\n};\n",
                 t[0], t[1], t[2], t[3], t[4], t[5], t[6], t[7], t[8], t[9], t[10], t[11]);
    }
}

void session_look_text(const struct session *s, char *buf, size_t size)
{
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f) {
        snprintf(buf, size, "# (out of memory: the look is not written)\n");
        return;
    }
    const struct session_settings *set = &s->settings;
    const struct config *cfg = &s->cfg;
    if (cfg->scene.kind == SCENE_DATA)
        fprintf(f, "data = { step = %d; };\n", s->playback.step);
    if (set->step_m != cfg->render.step_m && set->lod_pixels != cfg->render.lod_pixels)
        fprintf(f, "render = { step = %.17e; lod = %.17e; };\n", set->step_m, set->lod_pixels);
    else if (set->step_m != cfg->render.step_m)
        fprintf(f, "render = { step = %.17e; };\n", set->step_m);
    else if (set->lod_pixels != cfg->render.lod_pixels)
        fprintf(f, "render = { lod = %.17e; };\n", set->lod_pixels);
    if (memcmp(set->light_resolution, cfg->lightmap.resolution, sizeof(set->light_resolution)) ||
        set->epsilon != cfg->lightmap.epsilon)
        fprintf(f, "lightmap = { resolution = [%d, %d, %d]; epsilon = %.17e; };\n",
                set->light_resolution[0], set->light_resolution[1], set->light_resolution[2],
                set->epsilon);
    /* The effects as this session decided them (and the menu turned them), so that a batch
     * render simulates what it did whatever its own facts would decide; not the temporal
     * blend (a still picture has none) nor the lens warp (the display's). */
    static const enum effect pinned[] = {EFFECT_SHADOWS,  EFFECT_FORWARD, EFFECT_PERIPHERAL,
                                         EFFECT_MULTIPLE, EFFECT_LATERAL, EFFECT_PHASE,
                                         EFFECT_GROUND_SHADOW, EFFECT_DETAIL};
    fprintf(f, "effects = {");
    for (size_t i = 0; i < sizeof(pinned) / sizeof(pinned[0]); i++)
        fprintf(f, " %s = \"%s\";", effects_name(pinned[i]),
                s->effects.on[pinned[i]] ? "on" : "off");
    fprintf(f, " };\n");
    const struct look *look = &set->look;
    fprintf(f, "look = {\n    species = {\n");
    for (int sp = 0; sp < SPECIES_COUNT; sp++) {
        const float *t = look->tint.rgb[sp];
        fprintf(f, "        %s = { enabled = %s; scale = %.17e; tint = [%.9e, %.9e, %.9e]; };\n",
                species_name((enum species)sp), look->select.enabled[sp] ? "true" : "false",
                look->select.scale[sp], (double)t[0], (double)t[1], (double)t[2]);
    }
    fprintf(f, "    };\n");
    fprintf(f, "    layers = (");
    for (int i = 0; i < look->layer_count; i++) {
        const struct transfer_layer *l = &look->layers[i];
        fprintf(f, "%s\n        {\n            field = \"%s\";\n", i ? "," : "",
                transfer_field_name(l->tf.field));
        transfer_file_write_group(f, "transfer", &l->tf, "            ");
        fprintf(f, "            opacity = %.17e;\n            mode = \"%s\";\n"
                   "            enabled = %s;\n        }",
                l->opacity, transfer_layer_mode_name(l->mode), l->enabled ? "true" : "false");
    }
    fprintf(f, "%s);\n", look->layer_count ? "\n    " : "");
    fprintf(f, "    slices = (");
    for (int i = 0; i < look->slice_count; i++) {
        const struct transfer_slice *sl = &look->slices[i];
        fprintf(f, "%s\n        {\n            field = \"%s\";\n", i ? "," : "",
                transfer_field_name(sl->tf.field));
        transfer_file_write_group(f, "transfer", &sl->tf, "            ");
        fprintf(f, "            axis = \"plane\";\n"
                   "            point = [%.17e, %.17e, %.17e];\n"
                   "            normal = [%.17e, %.17e, %.17e];\n"
                   "            opacity = %.17e;\n            contour_every = %.17e;\n"
                   "            enabled = %s;\n",
                sl->point[0] / 1000.0, sl->point[1] / 1000.0, sl->point[2] / 1000.0,
                sl->normal[0], sl->normal[1], sl->normal[2], sl->opacity, sl->contour_every,
                sl->enabled ? "true" : "false");
        if (sl->level > 0)
            fprintf(f, "            level = %d;\n", sl->level);
        if (sl->contour_count > 0) {
            fprintf(f, "            contours = [");
            for (int k = 0; k < sl->contour_count; k++)
                fprintf(f, "%s%.17e", k ? ", " : "", sl->contour_values[k]);
            fprintf(f, "];\n");
        }
        fprintf(f, "        }");
    }
    fprintf(f, "%s);\n};\n", look->slice_count ? "\n    " : "");
    if (set->probe.on)
        fprintf(f, "probe = { on = true; mode = \"%s\"; threshold = %.17e; distance = %.17e; };\n",
                set->probe.mode == PROBE_AT_DISTANCE ? "distance" : "first_visible",
                set->probe.threshold, set->probe.distance_m / 1000.0);
    if (fclose(f) != 0 || !text) {
        free(text);
        snprintf(buf, size, "# (out of memory: the look is not written)\n");
        return;
    }
    if (len >= size)
        snprintf(buf, size, "# (the look is longer than %zu bytes: not written)\n", size);
    else
        memcpy(buf, text, len + 1);
    free(text);
}

void session_sun_text(const struct session *s, char *buf, size_t size)
{
    snprintf(buf, size, "light = { azimuth = %.6f; elevation = %.6f; };\n", s->sun_az,
             s->sun_el);
}

bool session_uses_tracker(const struct session *s)
{
    return s->tracker;
}

int session_step_count(const struct session *s)
{
    return s->playback.count;
}

bool session_blends_steps(const struct session *s)
{
    return s->effects.on[EFFECT_TEMPORAL];
}

void session_set_playing(struct session *s, bool playing)
{
    struct playback *pb = &s->playback;
    if (playing && !pb->playing && pb->step >= pb->count - 1 && !pb->loop)
        pb->step = 0; /* play again from the start */
    pb->playing = playing;
    pb->acc = 0.0;
}

void session_set_navigation(struct session *s, const struct display_navigation *nav)
{
    s->nav = *nav;
}

void session_set_camera(struct session *s, const struct display_camera *camera)
{
    s->camera = *camera;
}

void session_reset_view(struct session *s)
{
    s->nav = s->nav_home;
    s->camera = s->camera_home;
}

void session_frame_view(struct session *s)
{
    if (s->tracker)
        s->nav = s->nav_frame;
    else
        s->camera = s->camera_frame;
}

/* ---- the menu's changes --------------------------------------------------------------- */

static void transfer_path(const struct session *s, int slot, char *buf, size_t size)
{
    snprintf(buf, size, "%s/tf-%d.cfg", s->transfers_dir, slot + 1);
}

static void edit_layer(struct look *look, int i, bool on, const struct transfer_function *tf);

/* The menu's layers into LOOK, the transfer editor's function and its on/off into the edited
 * one (a first layer made, emitting and opaque, when there is none and the edit is more than
 * the untouched default off); the model then holds what LOOK holds. */
static void edit_layers(struct look *look, struct menu_model *m)
{
    look->layer_count = m->layer_count;
    memcpy(look->layers, m->layers, sizeof(look->layers));
    int i = m->layer_edited >= 0 && m->layer_edited < look->layer_count ? m->layer_edited : 0;
    edit_layer(look, i, m->transfer_on, &m->transfer);
    m->layer_count = look->layer_count;
    memcpy(m->layers, look->layers, sizeof(m->layers));
    m->layer_edited = look->layer_count > 0 ? i : 0;
    look->edited = m->layer_edited; /* the editor's histogram counts its field */
}

static void edit_layer(struct look *look, int i, bool on, const struct transfer_function *tf)
{
    if (look->layer_count == 0) {
        struct transfer_function plain;
        transfer_defaults(&plain, TRANSFER_FIELD_QVAPOR);
        if (!on && transfer_equal(tf, &plain))
            return;
        look->layer_count = 1;
        look->layers[0] = (struct transfer_layer){
            .enabled = on, .mode = TRANSFER_LAYER_EMIT, .opacity = 1.0, .tf = *tf};
        return;
    }
    look->layers[i].enabled = on;
    look->layers[i].tf = *tf;
}

static void apply_changes(struct session *s, unsigned ch)
{
    struct menu_model *m = menu_model(s->menu);
    if (ch & MENU_CHANGE_PLAYBACK) {
        s->playback.loop = m->loop;
        s->playback.speed = m->speed;
        session_set_playing(s, m->playing);
    }
    if (ch & MENU_CHANGE_STEP)
        session_set_step(s, m->step);
    struct session_settings set = s->settings;
    if (ch & (MENU_CHANGE_SPECIES | MENU_CHANGE_TRANSFER)) {
        for (int sp = 0; sp < SPECIES_COUNT; sp++) {
            set.look.select.enabled[sp] = m->species_on[sp];
            set.look.select.scale[sp] = m->species_scale[sp];
            memcpy(set.look.tint.rgb[sp], m->species_tint[sp], sizeof(m->species_tint[sp]));
        }
        edit_layers(&set.look, m);
    }
    if (ch & MENU_CHANGE_SLICES) {
        set.look.slice_count = m->slice_count;
        for (int i = 0; i < m->slice_count; i++)
            set.look.slices[i] = m->slices[i].slice;
    }
    if (ch & MENU_CHANGE_SUN)
        session_set_sun(s, m->sun_azimuth, m->sun_elevation);
    if (ch & MENU_CHANGE_QUALITY) {
        set.step_m = m->step_m;
        set.lod_pixels = m->lod_pixels;
        for (int a = 0; a < 3; a++)
            set.light_resolution[a] = m->light_resolution;
        set.epsilon = m->epsilon;
        set.diffuse = m->diffuse_on;
    }
    if (ch & (MENU_ACTION_SAVE | MENU_ACTION_LOAD)) {
        char path[CONFIG_PATH_MAX + 32], status[128];
        transfer_path(s, m->slot, path, sizeof(path));
        if (ch & MENU_ACTION_SAVE) {
            snprintf(m->transfer.name, sizeof(m->transfer.name), "tf-%d", m->slot + 1);
            bool ok = transfer_file_save(path, &m->transfer);
            snprintf(status, sizeof(status), ok ? "saved %s" : "not saved: %s",
                     ok ? path : log_last_error());
        } else {
            struct transfer_function tf = m->transfer;
            bool ok = transfer_file_load(path, &tf);
            if (ok) {
                /* A function loaded is shown at once, as an edited one is. */
                m->transfer = tf;
                m->transfer_on = true;
                edit_layers(&set.look, m);
            }
            snprintf(status, sizeof(status), ok ? "loaded %s" : "kept the current one: %s",
                     ok ? path : log_last_error());
        }
        menu_set_status(s->menu, status);
        menu_model_changed(s->menu);
    }
    if (ch & MENU_CHANGE_PROBE) {
        set.probe.on = m->probe_on;
        set.probe.mode = m->probe_mode == MENU_PROBE_AT_DISTANCE ? PROBE_AT_DISTANCE
                                                                 : PROBE_FIRST_VISIBLE;
        set.probe.threshold = m->probe_threshold;
        set.probe.distance_m = m->probe_distance_m;
    }
    if (memcmp(&set, &s->settings, sizeof(set)) != 0) {
        set.revision++;
        session_set_settings(s, &set);
    }
    if (ch & MENU_ACTION_RESET_VIEW)
        session_reset_view(s);
    if (ch & MENU_ACTION_FRAME)
        session_frame_view(s);
    if (ch & MENU_ACTION_SAVE_VIEW)
        s->requests |= SESSION_REQUEST_BOOKMARK;
}

/* ---- navigation ----------------------------------------------------------------------- */

/* The orbit camera turned about its target by D_AZ (clockwise from above) and D_EL degrees,
 * brought closer by ZOOM (< 1) and moved by MOVE (forward, right, up) times its distance. */
static void orbit(struct display_camera *c, double d_az, double d_el, double zoom,
                  const double move[3])
{
    struct camera_orbit o;
    camera_orbit_from(c->eye, c->target, &o);
    o.azimuth_deg += d_az;
    o.elevation_deg = fmin(89.0, fmax(-89.0, o.elevation_deg + d_el));
    o.distance_m *= zoom;
    double f[3], r[3], len = 0.0;
    for (int i = 0; i < 3; i++)
        f[i] = c->target[i] - c->eye[i];
    for (int i = 0; i < 3; i++)
        len += f[i] * f[i];
    len = sqrt(len);
    for (int i = 0; i < 3; i++)
        f[i] = len > 0.0 ? f[i] / len : 0.0;
    r[0] = f[1] * c->up[2] - f[2] * c->up[1];
    r[1] = f[2] * c->up[0] - f[0] * c->up[2];
    r[2] = f[0] * c->up[1] - f[1] * c->up[0];
    double rl = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int i = 0; i < 3; i++) {
        double dv = o.distance_m * (move[0] * f[i] + move[1] * (rl > 0.0 ? r[i] / rl : 0.0) +
                                    move[2] * (i == 2 ? 1.0 : 0.0));
        o.target[i] += dv;
    }
    camera_orbit_eye(&o, c->eye);
    memcpy(c->target, o.target, sizeof(c->target));
}

/* A navigation key: the same meaning on every display. */
static bool navigation_key(struct session *s, enum input_key k)
{
    static const struct {
        enum input_key key;
        double move[3]; /* forward, right, up: the viewer's */
        double turn[2]; /* the storm seen turning: left < 0; tilting toward the viewer > 0 */
        double zoom;    /* > 1: closer / larger */
    } map[] = {
        {INPUT_KEY_MOVE_FORWARD, {1, 0, 0}, {0, 0}, 1},
        {INPUT_KEY_MOVE_BACK, {-1, 0, 0}, {0, 0}, 1},
        {INPUT_KEY_MOVE_LEFT, {0, -1, 0}, {0, 0}, 1},
        {INPUT_KEY_MOVE_RIGHT, {0, 1, 0}, {0, 0}, 1},
        {INPUT_KEY_MOVE_UP, {0, 0, 1}, {0, 0}, 1},
        {INPUT_KEY_MOVE_DOWN, {0, 0, -1}, {0, 0}, 1},
        {INPUT_KEY_TURN_LEFT, {0, 0, 0}, {-TURN_STEP, 0}, 1},
        {INPUT_KEY_TURN_RIGHT, {0, 0, 0}, {TURN_STEP, 0}, 1},
        {INPUT_KEY_TURN_UP, {0, 0, 0}, {0, TURN_STEP}, 1},
        {INPUT_KEY_TURN_DOWN, {0, 0, 0}, {0, -TURN_STEP}, 1},
        {INPUT_KEY_ZOOM_IN, {0, 0, 0}, {0, 0}, 1.25},
        {INPUT_KEY_ZOOM_OUT, {0, 0, 0}, {0, 0}, 1 / 1.25},
    };
    for (size_t i = 0; i < sizeof(map) / sizeof(map[0]); i++) {
        if (map[i].key != k)
            continue;
        if (s->tracker) {
            /* Moving the viewer moves the world the other way in the room. */
            struct display_navigation *n = &s->nav;
            n->position[2] += NAV_STEP * map[i].move[0];
            n->position[0] -= NAV_STEP * map[i].move[1];
            n->position[1] -= NAV_STEP * map[i].move[2];
            n->orientation_deg[0] = fmod(n->orientation_deg[0] + map[i].turn[0], 360.0);
            n->orientation_deg[1] =
                fmin(89.0, fmax(-89.0, n->orientation_deg[1] + map[i].turn[1]));
            n->scale *= map[i].zoom;
        } else {
            const double move[3] = {0.05 * map[i].move[0], 0.05 * map[i].move[1],
                                    0.05 * map[i].move[2]};
            /* The storm tilting toward the viewer: the camera rises over its target. */
            orbit(&s->camera, map[i].turn[0], map[i].turn[1], 1.0 / map[i].zoom, move);
        }
        return true;
    }
    return false;
}

static bool sun_key(struct session *s, enum input_key k)
{
    switch (k) {
    case INPUT_KEY_SUN_LEFT:
        session_set_sun(s, s->sun_az - 5.0, s->sun_el);
        return true;
    case INPUT_KEY_SUN_RIGHT:
        session_set_sun(s, s->sun_az + 5.0, s->sun_el);
        return true;
    case INPUT_KEY_SUN_UP:
        session_set_sun(s, s->sun_az, s->sun_el + 2.0);
        return true;
    case INPUT_KEY_SUN_DOWN:
        session_set_sun(s, s->sun_az, s->sun_el - 2.0);
        return true;
    default:
        return false;
    }
}

/* The wand's grab, flying and turning (tracker space); a joystick flies the orbit camera. */
static void navigate(struct session *s, double dt)
{
    float fly = s->axis[INPUT_AXIS_FLY], turn = s->axis[INPUT_AXIS_TURN];
    if (!s->tracker) {
        if ((fly != 0.0f || turn != 0.0f) && dt > 0.0)
            orbit(&s->camera, turn * TURN_SPEED * dt, 0.0, 1.0,
                  (const double[3]){0.5 * fly * dt, 0.0, 0.0});
        return;
    }
    if (!s->have_wand)
        return;
    struct display_navigation *nav = &s->nav;
    if (s->grabbing) {
        for (int i = 0; i < 3; i++)
            nav->position[i] = s->grab_position[i] + (s->wand_pos[i] - s->grab_wand[i]);
    }
    if (fly != 0.0f && dt > 0.0) {
        /* Flying forward along the wand moves the world toward the user. */
        for (int i = 0; i < 3; i++)
            nav->position[i] -= s->wand_dir[i] * fly * FLY_SPEED * dt;
    }
    if (turn != 0.0f && dt > 0.0)
        nav->orientation_deg[0] = fmod(nav->orientation_deg[0] + turn * TURN_SPEED * dt, 360.0);
}

/* ---- one frame: input -> state -------------------------------------------------------- */

/* Menu space -> world, and world -> menu space, for the navigation NAV. */
static void menu_matrices(const struct session *s, const struct display_navigation *nav,
                          mat4 to_world, mat4 from_world)
{
    if (s->tracker) {
        float n[16];
        display_navigation_matrix(nav, n);
        memcpy(from_world, n, sizeof(mat4));
        glm_mat4_inv(from_world, to_world);
    } else {
        glm_mat4_identity(to_world);
        glm_mat4_identity(from_world);
    }
}

static void to_menu_space(const struct session *s, mat4 from_world, struct input_event *e)
{
    bool world_menu = !s->tracker;
    if ((e->space == INPUT_SPACE_WORLD) == world_menu)
        return;
    if (world_menu) { /* a tracked wand without a tracker-space menu: not pointing at it */
        e->type = INPUT_AXIS;
        e->axis = INPUT_AXIS_COUNT;
        return;
    }
    vec4 p = {e->position[0], e->position[1], e->position[2], 1.0f}, pt;
    vec4 d = {e->direction[0], e->direction[1], e->direction[2], 0.0f}, dt;
    glm_mat4_mulv(from_world, p, pt);
    glm_mat4_mulv(from_world, d, dt);
    float len = sqrtf(dt[0] * dt[0] + dt[1] * dt[1] + dt[2] * dt[2]);
    vec4 u = {e->up[0], e->up[1], e->up[2], 0.0f}, ut;
    glm_mat4_mulv(from_world, u, ut);
    float ulen = sqrtf(ut[0] * ut[0] + ut[1] * ut[1] + ut[2] * ut[2]);
    for (int i = 0; i < 3; i++) {
        e->position[i] = pt[i];
        e->direction[i] = len > 0.0f ? dt[i] / len : 0.0f;
        e->up[i] = ulen > 0.0f ? ut[i] / ulen : 0.0f;
    }
    e->space = INPUT_SPACE_TRACKER;
}

/* Places the menu: once in front of the user in tracker space, or on the right of the orbit
 * camera's view, following it. */
static void place_menu(struct session *s, const struct display_camera *cam, int width,
                       int height)
{
    if (s->tracker) {
        if (s->placed)
            return;
        /* (A rank of a cluster holds its own walls: the room's count says what it is.) */
        int room =
            s->display.room_wall_count > 0 ? s->display.room_wall_count : s->display.wall_count;
        if (room == 1 && s->display.wall_count == 1) {
            /* One screen (a stereo desktop, a powerwall): only what lies in front of it is
             * seen, so the panel goes on it, at its right, as the orbit view's: at most 85 %
             * of half its width and 90 % of its height; on the screen's plane it has no
             * parallax. */
            const struct display_wall *wl = &s->display.walls[0];
            float r[3], u[3], ww = 0.0f, wh = 0.0f;
            for (int i = 0; i < 3; i++) {
                r[i] = (float)(wl->lower_right[i] - wl->lower_left[i]);
                u[i] = (float)(wl->upper_left[i] - wl->lower_left[i]);
                ww += r[i] * r[i];
                wh += u[i] * u[i];
            }
            ww = sqrtf(ww);
            wh = sqrtf(wh);
            if (ww > 0.0f && wh > 0.0f) {
                float w = fminf(0.425f * ww, 0.9f * wh / menu_aspect(s->menu)), c[3];
                for (int i = 0; i < 3; i++) {
                    r[i] /= ww;
                    u[i] /= wh;
                    c[i] = (float)wl->lower_left[i] + r[i] * (0.97f * ww - 0.5f * w) +
                           u[i] * 0.5f * wh;
                }
                menu_set_pose(s->menu, c, r, u, w);
                s->placed = true;
                return;
            }
        }
        /* In front of the user, a little below the eyes, facing them. */
        const double *h = s->display.head.position;
        const float c[3] = {(float)h[0], (float)h[1] - 0.35f, (float)h[2] - 0.75f};
        const float r[3] = {1, 0, 0}, u[3] = {0, 1, 0};
        menu_set_pose(s->menu, c, r, u, 0.6f);
        s->placed = true;
        return;
    }
    struct render_view rv;
    camera_look_at(cam->eye, cam->target, cam->up, cam->fov_deg, cam->near_m, cam->far_m,
                   width > 0 ? width : 1, height > 0 ? height : 1, &rv);
    mat4 view, inv;
    memcpy(view, rv.view, sizeof(view));
    glm_mat4_inv(view, inv);
    float near = rv.proj[14] / (rv.proj[10] - 1.0f);
    float dist = 3.0f * fabsf(near);
    float half_h = dist / rv.proj[5], half_w = dist / rv.proj[0];
    float w = fminf(0.85f * half_w, 1.8f * half_h / menu_aspect(s->menu));
    float c[3], r[3], u[3];
    for (int i = 0; i < 3; i++) {
        r[i] = inv[0][i];
        u[i] = inv[1][i];
        c[i] = inv[3][i] - inv[2][i] * dist + r[i] * (half_w * 0.97f - 0.5f * w);
    }
    menu_set_pose(s->menu, c, r, u, w);
}

/* The probe's point along the wand's or pointer's ray (rank 0): the first point of the step
 * on screen whose extinction passes the threshold, or the point the set distance along it.
 * While the ray is on the menu the last point stays (the panel can be read meanwhile). */
static void pick_probe(struct session *s)
{
    const struct probe_settings *ps = &s->settings.probe;
    if (!s->probe || !ps->on) {
        s->probe_picked = false;
        return;
    }
    if (!s->have_wand || (s->menu && menu_captures(s->menu)))
        return;
    mat4 to_world, from_world;
    menu_matrices(s, &s->nav, to_world, from_world);
    vec4 p = {s->wand_pos[0], s->wand_pos[1], s->wand_pos[2], 1.0f}, pw;
    vec4 d = {s->wand_dir[0], s->wand_dir[1], s->wand_dir[2], 0.0f}, dw;
    glm_mat4_mulv(to_world, p, pw);
    glm_mat4_mulv(to_world, d, dw);
    double o[3], dir[3], len = 0.0;
    for (int i = 0; i < 3; i++) {
        o[i] = pw[i];
        dir[i] = dw[i];
        len += dir[i] * dir[i];
    }
    len = sqrt(len);
    if (!(len > 0.0)) {
        s->probe_picked = false;
        return;
    }
    double t = ps->distance_m;
    for (int i = 0; i < 3; i++)
        dir[i] /= len;
    if (ps->mode == PROBE_AT_DISTANCE)
        s->probe_picked = true;
    else
        s->probe_picked = probe_first_visible(&s->probe_volume, o, dir, 1e12, ps->threshold, &t);
    for (int i = 0; s->probe_picked && i < 3; i++)
        s->probe_pick[i] = o[i] + t * dir[i];
}

/* Whether STEP is the staged next volume, whole on the GPU with its light map built (when
 * there is one): its step change is then a swap. */
static bool staged_ready(struct session *s, int step)
{
    if (player_next_step(s->player) != step || !renderer_next_cells(s->renderer))
        return false;
    return lightmaps_next_built(&s->light, player_step_id(s->player, true));
}

static bool ready(void *user, int step)
{
    struct session *s = user;
    return s->staged ? staged_ready(s, step) : player_ready(s->player, step);
}

/* A drag outside the menu while its Slices page shows moves the selected slice: up and down
 * along its axis (SLICE_DRAG_SHARE of the box's extent per pixel), left and right tilts it
 * (SLICE_DRAG_DEG per pixel); the change goes to the settings as the page's sliders send it. */
#define SLICE_DRAG_SHARE (1.0 / 400.0)
#define SLICE_DRAG_DEG 0.2
static void drag_slice(struct session *s, float du, float dv)
{
    struct menu_model *m = menu_model(s->menu);
    struct menu_slice *sl = &m->slices[m->slice_selected];
    int a = sl->axis;
    double lo = m->box_min_m[a], hi = m->box_max_m[a], c[3];
    sl->position_m = fmin(hi, fmax(lo, sl->position_m - dv * (hi - lo) * SLICE_DRAG_SHARE));
    sl->tilt_deg = fmin(60.0, fmax(-60.0, sl->tilt_deg + du * SLICE_DRAG_DEG));
    for (int k = 0; k < 3; k++)
        c[k] = 0.5 * (m->box_min_m[k] + m->box_max_m[k]);
    menu_slice_plane(sl, c);
    menu_model_changed(s->menu);
    apply_changes(s, MENU_CHANGE_SLICES);
}

/* Whether a drag outside the menu now moves a slice: the Slices page shows one. */
static bool slices_shown(const struct session *s)
{
    return s->menu && menu_visible(s->menu) && menu_page(s->menu) == MENU_PAGE_SLICES &&
           menu_model(s->menu)->slice_count > 0;
}

/* The tracker-space point P in world metres. */
static void wand_world(mat4 from_world, const float p[3], double out[3])
{
    mat4 to_world;
    glm_mat4_inv(from_world, to_world);
    vec4 pt = {p[0], p[1], p[2], 1.0f}, pw;
    glm_mat4_mulv(to_world, pt, pw);
    for (int i = 0; i < 3; i++)
        out[i] = pw[i] / pw[3];
}

/* The wand's roll since the press, degrees: the angle from the press's up to the wand's up
 * about the wand's ray (right-handed about the ray, so clockwise as the holder sees it), both
 * taken across the ray; 0 when the source gives no up. */
static double wand_roll_deg(const struct session *s)
{
    if (!s->have_up || !s->slice_wand_has_up)
        return 0.0;
    const float *d = s->wand_dir, *b = s->wand_up;
    double a[3], dot = 0.0, cr[3], sn = 0.0, cs = 0.0;
    for (int k = 0; k < 3; k++)
        dot += s->slice_wand_up[k] * d[k];
    for (int k = 0; k < 3; k++)
        a[k] = s->slice_wand_up[k] - dot * d[k];
    cr[0] = a[1] * b[2] - a[2] * b[1];
    cr[1] = a[2] * b[0] - a[0] * b[2];
    cr[2] = a[0] * b[1] - a[1] * b[0];
    for (int k = 0; k < 3; k++) {
        sn += cr[k] * d[k];
        cs += a[k] * b[k];
    }
    return atan2(sn, cs) * 180.0 / M_PI;
}

/* A tracked wand's drag of the selected slice: the plane moves along its normal by the wand's
 * world displacement along it since the press (along the slice's axis by that over the
 * normal's share of the axis), kept in the box, and tilts by the wand's roll since the press
 * (within the sliders' -60 to 60 degrees); the change goes to the settings as the page's
 * sliders send it, so every rank draws the same plane. */
static void wand_drag_slice(struct session *s, mat4 from_world)
{
    struct menu_model *m = menu_model(s->menu);
    struct menu_slice *sl = &m->slices[m->slice_selected];
    double w[3], along = 0.0, c[3];
    wand_world(from_world, s->wand_pos, w);
    for (int k = 0; k < 3; k++)
        along += (w[k] - s->slice_wand_from[k]) * sl->slice.normal[k];
    int a = sl->axis;
    double share = fabs(sl->slice.normal[a]) > 0.1 ? sl->slice.normal[a] : 1.0;
    double lo = m->box_min_m[a], hi = m->box_max_m[a];
    double pos = fmin(hi, fmax(lo, s->slice_wand_position + along / share));
    double tilt = fmin(60.0, fmax(-60.0, s->slice_wand_tilt + wand_roll_deg(s)));
    if (pos == sl->position_m && tilt == sl->tilt_deg)
        return;
    sl->position_m = pos;
    sl->tilt_deg = tilt;
    for (int k = 0; k < 3; k++)
        c[k] = 0.5 * (m->box_min_m[k] + m->box_max_m[k]);
    menu_slice_plane(sl, c);
    menu_model_changed(s->menu);
    apply_changes(s, MENU_CHANGE_SLICES);
}

/* One event: the menu's, navigation's or the session's own. */
static bool handle(struct session *s, mat4 from_world, struct input_event e)
{
    bool seen = true;
    switch (e.type) {
    case INPUT_POSE:
        to_menu_space(s, from_world, &e);
        if (e.type != INPUT_POSE)
            return false;
        /* The pointer's ray is part of the picture only where the menu shows it. */
        seen = s->menu && menu_visible(s->menu) &&
               (!s->have_wand || memcmp(s->wand_pos, e.position, sizeof(s->wand_pos)) != 0 ||
                memcmp(s->wand_dir, e.direction, sizeof(s->wand_dir)) != 0);
        memcpy(s->wand_pos, e.position, sizeof(s->wand_pos));
        memcpy(s->wand_dir, e.direction, sizeof(s->wand_dir));
        s->have_wand = true;
        s->have_up = e.has_up;
        if (e.has_up)
            memcpy(s->wand_up, e.up, sizeof(s->wand_up));
        if (s->slice_wand && slices_shown(s))
            wand_drag_slice(s, from_world);
        break;
    case INPUT_AXIS:
        if (e.axis < INPUT_AXIS_COUNT)
            s->axis[e.axis] = e.value;
        break;
    case INPUT_BUTTON:
        if (e.button == INPUT_BUTTON_GRAB && s->tracker) {
            s->grabbing = e.down && s->have_wand;
            memcpy(s->grab_wand, s->wand_pos, sizeof(s->grab_wand));
            memcpy(s->grab_position, s->nav.position, sizeof(s->grab_position));
        } else if (e.button == INPUT_BUTTON_TRIGGER && e.down) {
            /* A press the menu takes is not a drag of the view. */
            s->drag_blocked = s->menu && menu_captures(s->menu);
            /* A tracked wand's press off the menu on the Slices page takes the slice. */
            s->slice_wand = s->tracker && s->have_wand && !s->drag_blocked && slices_shown(s);
            if (s->slice_wand) {
                const struct menu_model *m = menu_model(s->menu);
                wand_world(from_world, s->wand_pos, s->slice_wand_from);
                s->slice_wand_position = m->slices[m->slice_selected].position_m;
                s->slice_wand_tilt = m->slices[m->slice_selected].tilt_deg;
                memcpy(s->slice_wand_up, s->wand_up, sizeof(s->slice_wand_up));
                s->slice_wand_has_up = s->have_up;
            }
        } else if (e.button == INPUT_BUTTON_TRIGGER) {
            s->slice_wand = false;
        } else if (e.button == INPUT_BUTTON_RESET && e.down && !s->menu) {
            session_reset_view(s);
        }
        break;
    case INPUT_KEY:
        if (e.key == INPUT_KEY_QUIT)
            s->quit = true;
        else if (e.key == INPUT_KEY_SCREENSHOT)
            s->requests |= SESSION_REQUEST_SCREENSHOT;
        else if (e.key == INPUT_KEY_BOOKMARK)
            s->requests |= SESSION_REQUEST_BOOKMARK;
        else if (e.key == INPUT_KEY_PATH_KEY)
            path_add_key(s);
        else if (e.key == INPUT_KEY_PATH_PLAY)
            path_toggle(s);
        else if (e.key == INPUT_KEY_FRAME)
            session_frame_view(s);
        else if (!navigation_key(s, e.key) && !sun_key(s, e.key) && !s->menu)
            seen = false;
        break;
    case INPUT_DRAG:
        if (s->drag_blocked)
            break;
        if (slices_shown(s)) {
            drag_slice(s, e.u, e.v);
            break;
        }
        if (s->tracker)
            s->nav.orientation_deg[0] = fmod(s->nav.orientation_deg[0] + DRAG_DEG * e.u, 360.0);
        else
            orbit(&s->camera, DRAG_DEG * e.u, DRAG_DEG * e.v, 1.0, (const double[3]){0, 0, 0});
        break;
    case INPUT_SCROLL:
        if (s->tracker)
            s->nav.scale *= pow(1.1, e.value);
        else
            orbit(&s->camera, 0.0, 0.0, pow(0.9, e.value), (const double[3]){0, 0, 0});
        break;
    case INPUT_AIM:
        break;
    }
    if (s->menu)
        menu_handle(s->menu, &e);
    return seen;
}

bool session_update(struct session *s, const struct input_queue *window_events, double dt,
                    double time_s, struct frame_state *out, bool *redraw)
{
    *redraw = false;
    struct display_navigation nav_before = s->nav;
    struct display_camera cam_before = s->camera;
    double sun_before[2] = {s->sun_az, s->sun_el};
    mat4 to_world, from_world;
    menu_matrices(s, &s->nav, to_world, from_world);
    if (s->menu)
        place_menu(s, &s->camera, s->view_size[0], s->view_size[1]);

    input_queue_clear(&s->queue);
    for (int i = 0; window_events && i < window_events->count; i++)
        input_queue_push(&s->queue, &window_events->events[i]);
    struct input_frame in = {.frame = s->frame};
    for (int i = 0; i < s->n_sources; i++) {
        if (!input_source_poll(s->sources[i], &in, &s->queue))
            return false;
    }
    /* A recording's frame: its clock, its head, and (below) its playback cursor. */
    struct input_script_frame rec = {0};
    if (s->script && input_script_frame(s->script, s->frame, &rec)) {
        if (rec.have_time) {
            dt = rec.dt_s;
            time_s = rec.time_s;
        }
        if (rec.have_head) {
            struct display_pose head;
            memcpy(head.position, rec.head_position, sizeof(head.position));
            memcpy(head.rotation, rec.head_rotation, sizeof(head.rotation));
            *redraw = !s->head_given || memcmp(&head, &s->head, sizeof(head)) != 0;
            s->head = head;
            s->head_given = true;
        }
        if (rec.have_eyes) {
            struct display_pose eyes[2];
            for (int e = 0; e < 2; e++) {
                memcpy(eyes[e].position, rec.eye_position[e], sizeof(eyes[e].position));
                memcpy(eyes[e].rotation, rec.eye_rotation[e], sizeof(eyes[e].rotation));
            }
            if (!s->eyes_given || memcmp(eyes, s->eyes, sizeof(eyes)) != 0)
                *redraw = true;
            memcpy(s->eyes, eyes, sizeof(eyes));
            s->eyes_given = true;
        }
    }
    bool head_moved = *redraw;
    s->frame++;
    unsigned before = 0, changes = 0;
    if (s->menu)
        menu_pixels(s->menu, &(int){0}, &(int){0}, &before);
    bool events = false;
    for (int i = 0; i < s->queue.count; i++)
        events |= handle(s, from_world, s->queue.events[i]);
    navigate(s, dt);
    bool flying = s->path_playing;
    path_fly(s, dt);
    if (s->menu) {
        changes = menu_take_changes(s->menu);
        apply_changes(s, changes);
    }
    bool picked_before = s->probe_picked;
    double pick_before[3];
    memcpy(pick_before, s->probe_pick, sizeof(pick_before));
    pick_probe(s);
    bool probe_moved = picked_before != s->probe_picked ||
                       (s->probe_picked && memcmp(pick_before, s->probe_pick,
                                                  sizeof(pick_before)) != 0);

    /* Playback: the cursor advances only onto loaded steps (a scripted render waits). */
    bool wait = !s->desc.interactive;
    int old_step = s->playback.step;
    bool was_playing = s->playback.playing;
    playback_tick(&s->playback, dt, wait ? NULL : ready, s);
    if (rec.have_cursor && rec.step < s->playback.count) {
        /* Where the recorded run's cursor was, stalls and all. */
        s->playback.step = rec.step;
        s->playback.acc = rec.step_acc;
        s->playback.playing = rec.playing;
    }
    if (s->menu) {
        struct menu_model *m = menu_model(s->menu);
        if (s->playback.step != m->step || s->playback.playing != m->playing) {
            m->step = s->playback.step;
            m->playing = s->playback.playing;
            menu_model_changed(s->menu);
        }
        bool present[SPECIES_COUNT];
        player_species_present(s->player, present);
        if (memcmp(present, m->species_present, sizeof(present)) != 0) {
            memcpy(m->species_present, present, sizeof(present));
            menu_model_changed(s->menu);
        }
        if (s->sun_az != sun_before[0] || s->sun_el != sun_before[1]) {
            m->sun_azimuth = fmod(s->sun_az + 360.0, 360.0);
            m->sun_elevation = s->sun_el;
            menu_model_changed(s->menu);
        }
    }

    memset(out, 0, sizeof(*out));
    out->frame = (uint64_t)(s->frame - 1);
    out->time_s = time_s;
    out->dt_s = dt > 0.0 ? dt : 0.0;
    if (s->head_given)
        out->head = s->head;
    else
        display_pose_from_euler(s->display.head.position, s->display.head.orientation_deg,
                                &out->head);
    out->nav = s->nav;
    out->camera = s->camera;
    if (s->menu)
        out->wand_valid = menu_ray(s->menu, out->wand_position, out->wand_direction,
                                   &(float){0});
    out->time_step = s->playback.step;
    double f = s->playback.acc;
    out->step_fraction = (float)(f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f);
    out->playing = s->playback.playing;
    out->sun_azimuth_deg = s->sun_az;
    out->sun_elevation_deg = s->sun_el;
    out->menu_visible = s->menu && menu_visible(s->menu);
    out->settings_revision = s->settings.revision;
    out->probe_valid = s->probe && s->settings.probe.on && s->probe_picked;
    if (out->probe_valid)
        memcpy(out->probe_point, s->probe_pick, sizeof(out->probe_point));

    unsigned after = 0;
    if (s->menu)
        menu_pixels(s->menu, &(int){0}, &(int){0}, &after);
    *redraw = head_moved || events || changes || after != before || s->playback.playing ||
              was_playing || flying || probe_moved ||
              s->playback.step != old_step ||
              memcmp(&nav_before, &s->nav, sizeof(nav_before)) != 0 ||
              memcmp(&cam_before, &s->camera, sizeof(cam_before)) != 0;
    return true;
}

/* ---- one frame: state -> GPU ---------------------------------------------------------- */

static bool upload(struct session *s, const struct ext_volume *v)
{
    if (!renderer_set_volume(s->renderer, v))
        return false;
    if (s->probe && !keep_probe_volume(s, v))
        return false;
    show_histogram(s, v);
    s->light.generation++;
    s->stats.volume_uploads++;
    s->stats.upload_ms_total += renderer_stats(s->renderer)->upload_ms;
    return true;
}

/* The step that follows STEP in playback (-1: none). */
static int step_after(const struct session *s, int step)
{
    const struct playback *pb = &s->playback;
    if (pb->count < 2)
        return -1;
    return step + 1 < pb->count ? step + 1 : pb->loop ? 0 : -1;
}

/* Staged playback: the light maps keyed by step (the ring of two), the next step's map built
 * between frames and not drawn. */
static void staged_light_ids(struct session *s)
{
    int next = step_after(s, s->shown);
    bool held = next >= 0 && player_next_step(s->player) == next &&
                renderer_next_cells(s->renderer) != NULL;
    s->light.temporal = true;
    s->light.ahead_only = true;
    s->light.step_id = player_step_id(s->player, false);
    s->light.next_id = held ? player_step_id(s->player, true) : 0;
}

/* Staged playback: WANT is the staged next volume, so the step change exchanges textures
 * (nothing uploaded, and its light map was built ahead). */
static bool swap_staged(struct session *s, int want, bool *swapped)
{
    *swapped = false;
    if (!s->staged || player_next_step(s->player) != want ||
        !renderer_next_cells(s->renderer))
        return true;
    const struct ext_volume *v = player_promote_next(s->player);
    if (!v)
        return true;
    if (!renderer_swap_next(s->renderer))
        return false;
    s->shown = want;
    s->stage_src = NULL;
    if (s->probe && s->probe_next_id == player_step_id(s->player, false)) {
        struct ext_volume t = s->probe_volume; /* copied between frames: no copy here */
        s->probe_volume = s->probe_next;
        s->probe_next = t;
        s->probe_next_id = 0;
        s->probe_volume_id++;
    } else if (s->probe && !keep_probe_volume(s, v)) {
        return false;
    }
    show_histogram(s, v);
    s->light.generation++;
    s->stats.volume_swaps++;
    *swapped = true;
    return true;
}

/* effects.temporal: keeps step k + 1 in the renderer's next volume and asks the eye pass to
 * blend it in at the frame's fraction (the light map pair follows: lightmaps).  Until k + 1 is
 * on the GPU (or while step k itself is still loading) the blend is 0: step k.  With staged
 * playback k + 1 arrives between frames (session_prepare). */
static bool temporal_frame(struct session *s, const struct frame_state *f, bool *changed)
{
    int next = s->shown == f->time_step ? step_after(s, f->time_step) : -1;
    int held = -1;
    if (s->staged) {
        held = renderer_next_cells(s->renderer) ? player_next_step(s->player) : -1;
    } else {
        const struct ext_volume *v =
            player_poll_next(s->player, next, !s->desc.interactive, &held);
        if (v) {
            if (!renderer_set_next_volume(s->renderer, v))
                return false;
            s->stats.volume_uploads++;
            *changed = true;
        }
    }
    uint64_t next_id = next >= 0 && held == next ? player_step_id(s->player, true) : 0;
    /* Staged: blended only once its map was built between frames, never built in the frame. */
    if (s->staged && !lightmaps_next_built(&s->light, next_id))
        next_id = 0;
    s->light.temporal = true;
    s->light.ahead_only = false;
    s->light.step_id = player_step_id(s->player, false);
    s->light.next_id = next_id;
    s->drawn.temporal = next_id != 0;
    s->drawn.temporal_f = next_id != 0 ? f->step_fraction : 0.0f;
    return true;
}

/* A domain that moves (a moving nest): the map of the step shown, its terrain, coastlines and
 * graticule where that step has them.  Made in the frame that first shows the step (19 - 28
 * ms on llvmpipe's machine for Katrina's 48 x 48 columns and ~500 coastline segments, most
 * of it the coastlines' reading and placing; not yet between frames with the staged step);
 * where it cannot be made the last map stays, with the message. */
static void follow_domain(struct session *s)
{
    if (s->map_step == s->shown)
        return;
    bool moves;
    const struct wrf_meta *m = player_wrf_step_meta(s->player, s->shown, &moves);
    if (moves && m) {
        struct scene_map *map = scene_map_remake(s->map, &s->cfg, s->renderer, m);
        if (!map)
            return;
        s->map = map;
    }
    s->map_step = s->shown;
}

bool session_apply(struct session *s, const struct frame_state *f, bool *changed)
{
    s->frame_start_ms = time_now_ms();
    bool uploaded = false;
    int want = f->time_step < s->playback.count ? f->time_step : s->playback.count - 1;
    if (want != s->shown && !swap_staged(s, want, &uploaded))
        return false;
    const struct ext_volume *v = NULL;
    if (want != s->shown) {
        /* Not the staged step (a jump, or it was not ready): uploaded now, in this frame.  The
         * series is about to make another step current: the staged copy must not read it. */
        drop_staged(s);
        v = s->desc.interactive ? player_poll(s->player, want, &s->shown)
                                : player_wait(s->player, want, &s->shown);
    } else if (!s->desc.interactive) {
        v = player_wait(s->player, want, &s->shown); /* a new look: made again, waited for */
    } else {
        if (!player_settled(s->player, want))
            drop_staged(s); /* the step shown is made again: the series may move on */
        v = player_poll(s->player, want, &s->shown);
    }
    if (v) {
        if (!upload(s, v))
            return false;
        uploaded = true;
    } else if (!player_settled(s->player, want)) {
        s->stats.frames_stale++;
    }
    s->drawn = s->base;
    scene_sun_settings(&s->cfg, f->sun_azimuth_deg, f->sun_elevation_deg, &s->drawn);
    s->drawn.step_m = (float)s->settings.step_m;
    s->drawn.lod_pixels = (float)s->settings.lod_pixels;
    if (s->effects.on[EFFECT_TEMPORAL]) {
        if (!temporal_frame(s, f, &uploaded))
            return false;
    } else if (s->staged) {
        staged_light_ids(s);
    }
    follow_domain(s);
    player_stats(s->player, &s->stats);
    s->stats.time_step = s->shown;
    s->applied = *f;
    s->have_applied = true;
    if (changed)
        *changed = uploaded;
    return true;
}

void session_collect_timings(struct session *s, bool wait)
{
    renderer_collect_timings(s->renderer, wait);
    lightmaps_collect_timings(&s->light, wait);
    const struct render_stats *rs = renderer_stats(s->renderer);
    s->stats.upload_bytes = (double)rs->upload_bytes;
    if (wait && s->desc.count_rays && renderer_counts(s->renderer, &s->stats.counts))
        s->stats.counted = true;
}

/* The light map's key besides the volume: the frame's sun, the effects' and the session's
 * settings. */
static void light_params(const struct session *s, struct lightmaps_params *p)
{
    double az = s->have_applied ? s->applied.sun_azimuth_deg : s->sun_az;
    double el = s->have_applied ? s->applied.sun_elevation_deg : s->sun_el;
    memset(p, 0, sizeof(*p));
    lightmaps_params_from(&s->cfg, &s->effects, az, el, p);
    memcpy(p->light.resolution, s->settings.light_resolution, sizeof(p->light.resolution));
    p->light.epsilon = s->settings.epsilon;
}

bool session_light(struct session *s)
{
    session_collect_timings(s, false);
    struct lightmaps_params p;
    light_params(s, &p);
    return lightmaps_update_params(&s->light, &p, s->renderer, &s->stats);
}

/* An upload slab from the pixel buffer: sized by the last slab's rate to the time left in
 * the call, between these bounds (the first, before any rate is known, is the lower one). */
#define STAGE_SLAB_MIN ((size_t)4 << 20)
#define STAGE_SLAB_MAX ((size_t)64 << 20)
/* Layers of level-0 cells a piece of the pair's cells (cells_build.comp's local_size_z). */
#define PAIR_CELL_LAYERS 4

size_t session_slab_bytes(double rate_bytes_per_ms, double left_ms)
{
    if (!(rate_bytes_per_ms > 0.0) || !(left_ms > 0.0))
        return STAGE_SLAB_MIN;
    double bytes = rate_bytes_per_ms * left_ms;
    if (bytes >= (double)STAGE_SLAB_MAX)
        return STAGE_SLAB_MAX;
    return bytes <= (double)STAGE_SLAB_MIN ? STAGE_SLAB_MIN : (size_t)bytes;
}

/* The CPU time of all of this process's threads, ms (a CPU rasteriser's included). */
static double cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* What the next piece of readying the next step would be, *WHAT in words; SESSION_PIECE_KINDS: none
 * can be done now. */
static enum session_piece_kind next_piece(struct session *s, const char **what)
{
    *what = "nothing";
    if (renderer_stage_busy(s->renderer)) {
        *what = renderer_stage_doing(s->renderer);
        return renderer_stage_copying(s->renderer)     ? SESSION_PIECE_COPY
               : renderer_stage_uploading(s->renderer) ? SESSION_PIECE_UPLOAD
                                                       : SESSION_PIECE_CELLS;
    }
    int next = step_after(s, s->shown);
    if (next >= 0 && player_next_step(s->player) == next && renderer_next_cells(s->renderer)) {
        if (s->effects.on[EFFECT_TEMPORAL] && !renderer_pair_cells_ready(s->renderer)) {
            *what = "a piece of the pair's cells";
            return SESSION_PIECE_PAIR;
        }
        *what = lightmaps_next_doing(&s->light);
        return SESSION_PIECE_LIGHT;
    }
    *what = "the stage's start";
    return SESSION_PIECE_START;
}

/* One piece of readying the step after the one shown, each waited for (so that its cost is
 * known and counted where it was issued); SLAB: the bytes an upload slab may take.
 * *PROGRESSED: the next piece can follow at once (not waiting for the stage's thread);
 * *MORE: work remains. */
static bool prepare_piece(struct session *s, size_t slab, bool *progressed, bool *more)
{
    *progressed = *more = false;
    int next = step_after(s, s->shown);
    /* While another step than the next is wanted (a jump, a rank holding), or the step shown is
     * being made again (a new look), nothing is staged: that step's upload would drop it. */
    bool settled = (!s->have_applied || s->applied.time_step == s->shown) &&
                   player_settled(s->player, s->shown);
    if (renderer_stage_busy(s->renderer)) {
        /* The copy's end, then the upload in slabs, then the cells. */
        bool ready = false;
        bool ok = renderer_stage_step(s->renderer, slab, &ready);
        gpu_finish();
        *progressed =
            ok && (!renderer_stage_copying(s->renderer) || renderer_stage_paced(s->renderer));
        *more = ok;
        return ok;
    }
    if (next < 0 || !settled)
        return true;
    if (player_next_step(s->player) == next && renderer_next_cells(s->renderer)) {
        /* Staged: its light map, once, with the sun of the last frame (the next frame's
         * session_apply sets the ids again). */
        s->light.temporal = true;
        s->light.step_id = player_step_id(s->player, false);
        s->light.next_id = player_step_id(s->player, true);
        if (lightmaps_next_built(&s->light, s->light.next_id))
            return true;
        struct lightmaps_params p;
        light_params(s, &p);
        /* The blend reads the pair's cells: made now in pieces, not in the first blended
         * frame. */
        bool done = true;
        if (s->effects.on[EFFECT_TEMPORAL] && !renderer_pair_cells_ready(s->renderer)) {
            bool ok = renderer_pair_cells_step(s->renderer, PAIR_CELL_LAYERS, &done);
            gpu_finish();
            *progressed = ok;
            *more = ok;
            return ok;
        }
        /* One piece of it a call (light_gpu_build_step with no time to spare does one). */
        bool ok = lightmaps_prepare_next(&s->light, &p, s->renderer, 1e-6, &done, &s->stats);
        *progressed = ok;
        *more = ok && !done;
        return ok;
    }
    if (!s->stage_src || player_next_step(s->player) != next) {
        int held = -1;
        s->stage_src = player_poll_next(s->player, next, false, &held);
    }
    if (!s->stage_src)
        return true; /* not loaded yet: the series' thread is on it */
    /* With the probe, its copy of the extinction too, by the stage rather than in the frame
     * of the step change. */
    if (s->probe && !room_probe_next(s, s->stage_src))
        return false;
    bool started = false;
    bool ok = renderer_stage_next(s->renderer, s->stage_src,
                                  s->probe ? s->probe_next.beta : NULL, &started);
    if (ok && started) {
        s->probe_next_id = s->probe ? player_step_id(s->player, true) : 0;
        s->stage_src = NULL; /* the renderer has it until the copy is done */
    }
    *progressed = ok && started && renderer_stage_paced(s->renderer); /* its first slice next */
    *more = ok;
    return ok;
}

bool session_prepare(struct session *s, bool *more)
{
    *more = false;
    if (!s->staged)
        return true;
    /* Pieces while they need not wait and the next, as long as the last of its kind, still
     * fits into PREPARE_SHARE of a frame's time (at least one piece a call). */
    double f = s->frame_ms > 10.0 ? s->frame_ms : 10.0, budget = PREPARE_SHARE * f;
    double t0 = time_now_ms();
    bool ok = true, progressed = true;
    s->stats.prepare_piece = NULL;
    s->stats.prepare_piece_ms = 0.0;
    for (int pieces = 0; ok && progressed; pieces++) {
        const char *what;
        enum session_piece_kind kind = next_piece(s, &what);
        enum light_build_phase phase = lightmaps_next_phase(&s->light);
        double t = time_now_ms(), left = budget - (t - t0);
        if (pieces > 0 && (left <= 0.0 || (kind < SESSION_PIECE_KINDS && s->piece_ms[kind] > left)))
            break;
        bool slice = kind == SESSION_PIECE_COPY && renderer_stage_paced(s->renderer);
        double *rate = slice ? &s->copy_rate : &s->upload_rate;
        size_t slab = session_slab_bytes(*rate, left);
        double c = cpu_ms(), cells = renderer_stage_cells_ms(s->renderer);
        ok = prepare_piece(s, slab, &progressed, more);
        double now = time_now_ms(), piece_cpu = cpu_ms() - c;
        if (kind < SESSION_PIECE_KINDS) {
            /* A slice of the copy makes the cells of the planes it copied: theirs. */
            double cells_cpu = slice ? renderer_stage_cells_ms(s->renderer) - cells : 0.0;
            s->piece_ms[kind] = now - t;
            s->stats.prepare_kind_ms[kind] += piece_cpu - cells_cpu;
            s->stats.prepare_kind_ms[SESSION_PIECE_CELLS] += cells_cpu;
            if (kind == SESSION_PIECE_LIGHT)
                s->stats.prepare_light_ms[phase] += piece_cpu;
        }
        if ((kind == SESSION_PIECE_UPLOAD || slice) && now > t)
            *rate = (double)slab / (now - t);
        if (now - t > budget)
            log_debug("playback: %s took %.1f ms (%.1f ms of CPU), over the call's %.1f ms", what,
                      now - t, piece_cpu, budget);
        if (piece_cpu > s->stats.prepare_piece_ms) {
            s->stats.prepare_piece = what;
            s->stats.prepare_piece_ms = piece_cpu;
        }
    }
    if (s->stats.prepare_piece_ms > s->stats.prepare_piece_max_ms) {
        s->stats.prepare_piece_max = s->stats.prepare_piece;
        s->stats.prepare_piece_max_ms = s->stats.prepare_piece_ms;
    }
    s->stats.prepare_ms += time_now_ms() - t0;
    if (!ok) {
        /* Most likely GPU memory for the second set of volume textures: play on without. */
        log_warn("playback: the next time step could not be readied on the GPU (see above); "
                 "from now on each step change uploads its step and builds its light map in "
                 "its frame");
        drop_staged(s);
        s->staged = false;
        *more = false;
    }
    return true;
}

/* "2005-08-28 06:00 UTC" from WRF's "2005-08-28_06:00:00". */
static void date_text(const char *times, char *buf, size_t size)
{
    int y, mo, da, h, mi;
    if (sscanf(times, "%d-%d-%d_%d:%d", &y, &mo, &da, &h, &mi) == 5)
        snprintf(buf, size, "%04d-%02d-%02d %02d:%02d UTC", y, mo, da, h, mi);
    else
        snprintf(buf, size, "%s", times);
}

/* What the overlay shows for F. */
static void overlay_model_of(struct session *s, const struct frame_state *f,
                             struct overlay_model *m)
{
    memset(m, 0, sizeof(*m));
    const struct config_overlay *co = &s->cfg.overlay;
    m->date = co->date;
    char when[64] = "";
    const char *times = player_step_date(s->player, s->shown);
    if (times[0])
        date_text(times, when, sizeof(when));
    else if (s->cfg.scene.kind == SCENE_STORM)
        snprintf(when, sizeof(when), "procedural storm");
    if (s->playback.count > 1)
        snprintf(m->date_text, sizeof(m->date_text), "%s%sstep %d of %d", when,
                 when[0] ? ", " : "", s->shown + 1, s->playback.count);
    else
        snprintf(m->date_text, sizeof(m->date_text), "%s", when);
    /* A legend per layer and slice shown, layers first. */
    const struct look *look = &s->settings.look;
    for (int i = 0; co->legend && i < look->layer_count + look->slice_count; i++) {
        bool layer = i < look->layer_count;
        const struct transfer_layer *l = layer ? &look->layers[i] : NULL;
        const struct transfer_slice *sl = layer ? NULL : &look->slices[i - look->layer_count];
        bool shown = layer ? l->enabled && l->opacity > 0.0 : sl->enabled && sl->opacity > 0.0;
        if (!shown || m->legend_count == OVERLAY_LEGENDS)
            continue;
        m->legends[m->legend_count++] = layer ? l->tf : sl->tf;
    }
    m->legend = m->legend_count > 0;
    if (m->legend)
        m->transfer = m->legends[0];
    m->north = co->north;
    if (!m->north)
        return;
    double x, y;
    if (s->tracker) {
        float n[16];
        display_navigation_matrix(&f->nav, n);
        x = n[4]; /* world north (0, 1, 0) in the room; the panel's up is forward, -z */
        y = -n[6];
    } else {
        /* A compass: north against the camera's heading, as seen from above. */
        double fx = f->camera.target[0] - f->camera.eye[0];
        double fy = f->camera.target[1] - f->camera.eye[1];
        x = -fx; /* north . right, with right = (fy, -fx) */
        y = fy;  /* north . forward */
    }
    m->north_deg = x * x + y * y > 1e-12 ? (float)(atan2(x, y) * 180.0 / M_PI) : 0.0f;
}

const struct probe_values *session_probe(const struct session *s)
{
    return s->probe ? &s->probe_values : NULL;
}

void session_set_status(struct session *s, const char *text)
{
    if (s->menu)
        menu_set_status(s->menu, text);
}

const struct overlay_model *session_overlay(const struct session *s)
{
    return s->overlay ? &s->overlay_model : NULL;
}

bool session_overlay_point(const struct session *s, float x, double world[3])
{
    return session_legend_point(s, 0, x, world);
}

bool session_legend_point(const struct session *s, int legend, float x, double world[3])
{
    int px, py;
    if (!s->overlay ||
        !overlay_legend_pixel_at(overlay_view_overlay(s->overlay), legend, x, &px, &py))
        return false;
    overlay_view_point(s->overlay, (float)px + 0.5f, (float)py + 0.5f, world);
    return true;
}

/* The values at the frame's probe point, read again only when the point, the step's volume
 * or its light map changed (every rank reads its own data: the point alone travels). */
static void read_probe(struct session *s, const struct frame_state *f)
{
    const struct probe_settings *ps = &s->settings.probe;
    unsigned builds = lightmaps_builds(&s->light);
    if (s->probe_key.valid == f->probe_valid && s->probe_key.volume == s->probe_volume_id &&
        s->probe_key.builds == builds && s->probe_key.mode == ps->mode &&
        s->probe_key.wand == f->wand_valid && s->probe_read_ok &&
        (!f->probe_valid || memcmp(s->probe_key.point, f->probe_point, sizeof(f->probe_point)) == 0))
        return;
    s->probe_key.valid = f->probe_valid;
    s->probe_key.volume = s->probe_volume_id;
    s->probe_key.builds = builds;
    s->probe_key.mode = ps->mode;
    s->probe_key.wand = f->wand_valid;
    memcpy(s->probe_key.point, f->probe_point, sizeof(f->probe_point));
    s->probe_read_ok = true;
    struct probe_values *v = &s->probe_values;
    if (!f->probe_valid) {
        memset(v, 0, sizeof(*v));
        if (!f->wand_valid)
            snprintf(v->why, sizeof(v->why), "point the wand or the mouse at the storm");
        else if (ps->mode == PROBE_FIRST_VISIBLE)
            snprintf(v->why, sizeof(v->why), "no extinction above %.2g /km along the ray",
                     ps->threshold * 1e3);
        else
            snprintf(v->why, sizeof(v->why), "no point along the ray");
    } else if (!probe_read(s->probe, s->shown, f->probe_point, v)) {
        memset(v, 0, sizeof(*v));
        snprintf(v->why, sizeof(v->why), "the data could not be read (see the log)");
    } else {
        probe_sample_beta(&s->probe_volume, f->probe_point, v->beta);
        float beam, diffuse[2];
        bool have_diffuse;
        if (lightmaps_sample(&s->light, f->probe_point, &beam, diffuse, &have_diffuse, NULL)) {
            v->have_light = true;
            v->light = beam;
            v->have_diffuse = have_diffuse;
            v->diffuse = diffuse[0];
        }
    }
    v->step = s->shown;
    snprintf(v->date, sizeof(v->date), "%s", player_step_date(s->player, s->shown));
}

static bool draw_probe(struct session *s, const struct frame_state *f, const float to_world[16])
{
    if (!s->settings.probe.on) {
        probe_view_hide(s->probe_view);
        return true;
    }
    read_probe(s, f);
    struct readout_model m;
    probe_values_readout(&s->probe_values, &m);
    const double *point = f->probe_valid ? f->probe_point : NULL;
    double size = 0.0;
    if (point && s->tracker) {
        size = 0.03 / f->nav.scale; /* 3 cm in the room */
    } else if (point) {
        double d2 = 0.0;
        for (int i = 0; i < 3; i++)
            d2 += (point[i] - f->camera.eye[i]) * (point[i] - f->camera.eye[i]);
        size = 0.03 * sqrt(d2);
    }
    return probe_view_update(s->probe_view, &m, point, size, s->tracker ? NULL : &f->camera,
                             s->view_size[0], s->view_size[1], s->display.head.position,
                             to_world, (float)s->cfg.render.exposure);
}

bool session_draw(struct session *s, struct display *d, const struct frame_state *f)
{
    if (!display_layout(d, &f->head, &f->nav, &f->camera))
        return false;
    if (!s->tracker && display_view_count(d) > 0) {
        s->view_size[0] = display_view(d, 0)->rv.width;
        s->view_size[1] = display_view(d, 0)->rv.height;
    }
    mat4 to_world, from_world;
    menu_matrices(s, &f->nav, to_world, from_world);
    float tw[16];
    memcpy(tw, to_world, sizeof(tw));
    float exposure = (float)s->cfg.render.exposure;
    if (s->menu && !menu_view_update(s->menu_view, s->menu, tw, exposure))
        return false;
    if (!s->menu && s->menu_view &&
        !menu_view_show(s->menu_view, &s->remote, s->remote_pixels, tw, exposure))
        return false;
    if (s->overlay) {
        overlay_model_of(s, f, &s->overlay_model);
        if (!overlay_view_update(s->overlay, &s->overlay_model, s->tracker ? NULL : &f->camera,
                                 s->view_size[0], s->view_size[1], s->display.head.position,
                                 tw, exposure))
            return false;
    }
    if (s->probe_view && !draw_probe(s, f, tw))
        return false;
    const struct look *look = &s->settings.look;
    struct render_layer layers[TRANSFER_LAYER_MAX];
    for (int i = 0; i < look->layer_count; i++)
        render_layer_from_transfer(&look->layers[i], exposure, &layers[i]);
    if (!renderer_set_layers(s->renderer, layers, look->layer_count))
        return false;
    struct render_slice slices[TRANSFER_SLICE_MAX];
    for (int i = 0; i < look->slice_count; i++)
        render_slice_from_transfer(&look->slices[i], exposure, &slices[i]);
    if (!renderer_set_slices(s->renderer, slices, look->slice_count))
        return false;
    if (!display_draw(d, s->renderer, &s->drawn))
        return false;
    for (int i = 0; i < display_view_count(d); i++) {
        const struct view *v = display_view(d, i);
        if (v->visible)
            session_stats_add_view(&s->stats);
    }
    s->stats.frames++;
    bool ok = display_present(d, s->renderer, (float)s->cfg.render.exposure);
    s->frame_ms = time_now_ms() - s->frame_start_ms;
    return ok;
}

/* ---- queries -------------------------------------------------------------------------- */

bool session_quit_requested(const struct session *s)
{
    return s->quit;
}

bool session_script_done(struct session *s)
{
    return !s->script ||
           (input_source_finished(s->script) && player_settled(s->player, s->playback.step));
}

long session_script_frames(const struct session *s)
{
    return s->script ? input_script_last_frame(s->script) + 1 : 0;
}

double session_script_dt(const struct session *s)
{
    return s->script ? 1.0 / input_script_fps(s->script) : 0.0;
}

bool session_head_given(const struct session *s)
{
    return s->head_given;
}

const struct display_pose *session_eyes_given(const struct session *s)
{
    return s->eyes_given ? s->eyes : NULL;
}

const struct input_queue *session_events(const struct session *s)
{
    return &s->queue;
}

void session_cursor(const struct session *s, int *step, double *acc, bool *playing)
{
    *step = s->playback.step;
    *acc = s->playback.acc;
    *playing = s->playback.playing;
}

bool session_settle(struct session *s)
{
    if (player_settled(s->player, s->playback.step))
        return true;
    const struct ext_volume *v = player_wait(s->player, s->playback.step, &s->shown);
    player_stats(s->player, &s->stats);
    s->stats.time_step = s->shown;
    if (!v)
        return player_settled(s->player, s->playback.step);
    return upload(s, v);
}

uint64_t session_sync_key(const struct session *s)
{
    /* FNV-1a over what makes the pictures besides the frame state: the config (read once,
     * never written), the look and quality, the effects decided, the step on screen and the
     * light map's key (its parameters and the steps it holds). */
    struct lightmaps_params p;
    light_params(s, &p);
    /* The next step's map counts only while it is blended in (a rank may hold it earlier). */
    uint64_t ids[2] = {s->light.step_id, s->drawn.temporal_f > 0.0f ? s->light.next_id : 0};
    const void *parts[] = {&s->cfg, &s->settings, &s->effects, &s->shown, &p, ids};
    const size_t sizes[] = {sizeof(s->cfg), sizeof(s->settings), sizeof(s->effects),
                            sizeof(s->shown), sizeof(p), sizeof(ids)};
    uint64_t h = 1469598103934665603ull;
    for (size_t k = 0; k < sizeof(sizes) / sizeof(sizes[0]); k++)
        for (size_t i = 0; i < sizes[k]; i++) {
            h ^= ((const unsigned char *)parts[k])[i];
            h *= 1099511628211ull;
        }
    return h;
}

void session_want_step(struct session *s, int step)
{
    if (step >= 0 && step < s->playback.count)
        player_want(s->player, step);
}

bool session_step_loaded(struct session *s, int step)
{
    if (player_settled(s->player, step) && s->shown == step)
        return true;
    /* Staged playback: loaded means ready to be swapped in, so that every rank's step change
     * is a swap in the same frame. */
    return s->staged ? staged_ready(s, step) : player_ready(s->player, step);
}

bool session_menu_state(struct session *s, struct menu_view_state *st, const uint8_t **pixels)
{
    if (!s->menu)
        return false;
    menu_view_state_of(s->menu, st, pixels);
    return true;
}

bool session_show_menu_state(struct session *s, const struct menu_view_state *st,
                             const uint8_t *pixels)
{
    if (s->menu)
        return true; /* it has its own */
    if (!s->menu_view && !(s->menu_view = menu_view_create(s->renderer)))
        return false;
    if (pixels) {
        size_t bytes = (size_t)st->width * (size_t)st->height * 4;
        uint8_t *copy = realloc(s->remote_pixels, bytes);
        if (!copy) {
            log_error("menu: out of memory");
            return false;
        }
        memcpy(copy, pixels, bytes);
        s->remote_pixels = copy;
    }
    s->remote = *st;
    return true;
}

void session_set_progress(struct session *s, struct progress *p)
{
    renderer_set_progress(s->renderer, p);
}

struct renderer *session_renderer(struct session *s)
{
    return s->renderer;
}

struct session_stats *session_stats(struct session *s)
{
    return &s->stats;
}

struct menu *session_menu(struct session *s)
{
    return s->menu;
}

const struct config *session_config(const struct session *s)
{
    return &s->cfg;
}

int session_step_shown(const struct session *s)
{
    return s->shown;
}

static const struct {
    enum input_key key;
    const char *what;
} key_help[] = {
    {INPUT_KEY_MOVE_FORWARD, "move forward (a tracked display: the storm comes closer)"},
    {INPUT_KEY_MOVE_BACK, "move back"},
    {INPUT_KEY_MOVE_LEFT, "move left"},
    {INPUT_KEY_MOVE_RIGHT, "move right"},
    {INPUT_KEY_MOVE_UP, "move up"},
    {INPUT_KEY_MOVE_DOWN, "move down"},
    {INPUT_KEY_TURN_LEFT, "turn left (the orbit camera goes round its target)"},
    {INPUT_KEY_TURN_RIGHT, "turn right"},
    {INPUT_KEY_TURN_UP, "tilt the storm toward you (the orbit camera rises over it)"},
    {INPUT_KEY_TURN_DOWN, "tilt it away"},
    {INPUT_KEY_ZOOM_IN, "closer (the orbit camera) or a larger storm (tracked displays)"},
    {INPUT_KEY_ZOOM_OUT, "farther, or a smaller storm"},
    {INPUT_KEY_SUN_LEFT, "sun azimuth - 5 degrees"},
    {INPUT_KEY_SUN_RIGHT, "sun azimuth + 5 degrees"},
    {INPUT_KEY_SUN_UP, "sun elevation + 2 degrees"},
    {INPUT_KEY_SUN_DOWN, "sun elevation - 2 degrees"},
    {INPUT_KEY_PLAY, "play / pause the time steps"},
    {INPUT_KEY_STEP_BACK, "one time step back"},
    {INPUT_KEY_STEP_FORWARD, "one time step forward"},
    {INPUT_KEY_MENU, "show / hide the menu (also the right mouse button)"},
    {INPUT_KEY_PAGE_NEXT, "the menu's next page"},
    {INPUT_KEY_PAGE_PREV, "the menu's previous page"},
    {INPUT_KEY_SCREENSHOT, "screenshot: the views as PNG and PFM files"},
    {INPUT_KEY_BOOKMARK, "print the camera (the navigation) as a scene file block and save a "
                         "bookmark"},
    {INPUT_KEY_PATH_KEY, "the current view becomes the camera path's next key (3 s on)"},
    {INPUT_KEY_PATH_PLAY, "fly the camera path from its start (again: stop)"},
    {INPUT_KEY_PROBE, "the probe on / off: the values where the pointer meets the clouds"},
    {INPUT_KEY_FRAME, "frame: the whole domain in view again (the orbit camera from the "
                      "south-west; a tracked display: fitted to the room)"},
    {INPUT_KEY_QUIT, "quit"},
};

struct key_print {
    void (*print)(const char *keys, const char *what, void *user);
    void *user;
};

static void print_key(const char *keys, enum input_key key, void *user)
{
    const struct key_print *kp = user;
    for (size_t i = 0; i < sizeof(key_help) / sizeof(key_help[0]); i++)
        if (key_help[i].key == key)
            kp->print(keys, key_help[i].what, kp->user);
}

void session_list_keys(void (*print)(const char *keys, const char *what, void *user),
                       void *user)
{
    struct key_print kp = {print, user};
    display_list_keys(print_key, &kp);
    print("Home", "reset the view", user);
    print("mouse", "left: choose in the menu, or drag to turn; middle: grab (tracked "
                   "displays); wheel: zoom",
          user);
}
