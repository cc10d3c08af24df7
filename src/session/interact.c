/* The session's interaction: input -> menu -> playback, look, sun, quality, navigation. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cglm/cglm.h>

#include "session/interact.h"
#include "common/log.h"
#include "config/transfer_file.h"
#include "display/display.h"
#include "input/input.h"
#include "menu/menu.h"

#define SOURCES_MAX 3
#define FLY_SPEED 1.0  /* tracker metres per second at full deflection */
#define TURN_SPEED 45.0 /* degrees per second */

struct interact {
    struct config *cfg;
    struct renderer *renderer;
    struct lightmaps *light;
    struct session_stats *stats;
    struct interact_desc desc;
    char transfers_dir[CONFIG_PATH_MAX];

    struct player *player;
    struct playback playback;
    struct look look;
    struct menu *menu;
    struct menu_view *view;
    struct input_source *sources[SOURCES_MAX];
    int n_sources;
    struct input_source *script, *glfw;
    struct input_queue queue;
    long frame;
    int shown; /* the step on screen */
    bool placed;

    /* navigation */
    bool grabbing;
    float grab_wand[3];
    double grab_position[3];
    float wand_pos[3], wand_dir[3];
    bool have_wand;
    float axis[INPUT_AXIS_COUNT];
};

static const char *date_of(void *user, int step)
{
    return player_step_date(user, step);
}

static void model_from_session(struct interact *ia, struct menu_model *m)
{
    const struct config *cfg = ia->cfg;
    memset(m, 0, sizeof(*m));
    m->playing = ia->playback.playing;
    m->loop = ia->playback.loop;
    m->speed = ia->playback.speed;
    m->step = ia->playback.step;
    m->step_count = ia->playback.count;
    player_species_present(ia->player, m->species_present);
    for (int f = 0; f < SPECIES_COUNT; f++) {
        m->species_on[f] = ia->look.select.enabled[f];
        m->species_scale[f] = ia->look.select.scale[f];
        memcpy(m->species_tint[f], ia->look.tint.rgb[f], sizeof(m->species_tint[f]));
    }
    m->transfer_on = ia->look.transfer_on;
    m->transfer = ia->look.transfer;
    m->sun_azimuth = fmod(cfg->light.azimuth_deg + 360.0, 360.0);
    m->sun_elevation = cfg->light.elevation_deg;
    m->step_m = cfg->render.step_m;
    const struct grid3 *g = renderer_grid(ia->renderer);
    double smin = fmin(g->spacing[0], fmin(g->spacing[1], g->spacing[2]));
    m->step_max_m = smin > 0.0 ? 4.0 * smin : 2000.0;
    m->light_resolution = cfg->lightmap.resolution[0];
    m->epsilon = cfg->lightmap.epsilon;
    const struct effects *e = &ia->light->effects;
    m->diffuse_possible = !ia->light->have_effects || e->on[EFFECT_SHADOWS];
    m->diffuse_on = m->diffuse_possible && (!ia->light->have_effects || e->on[EFFECT_MULTIPLE]);
}

/* The menu's diffuse-light toggle: effects.multiple on or off from now on, and lateral escape
 * with it (on unless the config turns it off: the scene's narrow share was decided for the
 * multiple scattering it had).  The next frame builds the map, and so picks the eye pass's
 * variant, accordingly. */
static void set_diffuse(struct interact *ia, bool on)
{
    struct lightmaps *al = ia->light;
    if (!al->have_effects) {
        struct effects e;
        effects_decide(ia->cfg, NULL, &e);
        lightmaps_set_effects(al, &e);
    }
    struct effects *e = &al->effects;
    if (on == e->on[EFFECT_MULTIPLE] || (on && !e->on[EFFECT_SHADOWS]))
        return;
    ia->cfg->effects.mode[EFFECT_MULTIPLE] = on ? EFFECT_ON : EFFECT_OFF;
    e->on[EFFECT_MULTIPLE] = on;
    snprintf(e->reason[EFFECT_MULTIPLE], sizeof(e->reason[EFFECT_MULTIPLE]), "%s from the menu",
             on ? "on" : "off");
    bool lateral = on && ia->cfg->effects.mode[EFFECT_LATERAL] != EFFECT_OFF;
    if (lateral != e->on[EFFECT_LATERAL]) {
        e->on[EFFECT_LATERAL] = lateral;
        snprintf(e->reason[EFFECT_LATERAL], sizeof(e->reason[EFFECT_LATERAL]),
                 "%s with the diffuse light, from the menu", lateral ? "on" : "off");
    }
    log_info("menu: diffuse light (multiple scattering) %s", on ? "on" : "off");
}

struct interact *interact_create(struct config *cfg, struct renderer *r,
                                         struct lightmaps *light, struct session_stats *st,
                                         const struct interact_desc *d)
{
    struct interact *ia = calloc(1, sizeof(*ia));
    if (!ia) {
        log_error("out of memory");
        return NULL;
    }
    ia->cfg = cfg;
    ia->renderer = r;
    ia->light = light;
    ia->stats = st;
    if (d)
        ia->desc = *d;
    snprintf(ia->transfers_dir, sizeof(ia->transfers_dir), "%s",
             ia->desc.transfers_dir ? ia->desc.transfers_dir : ".");
    ia->player = player_create(cfg, NULL);
    if (!ia->player)
        goto error;
    playback_init(&ia->playback, player_step_count(ia->player),
                      cfg->scene.kind == SCENE_DATA ? cfg->data.step : 0, cfg->playback.speed,
                      cfg->playback.loop);
    ia->shown = ia->playback.step;
    look_from_config(cfg, &ia->look);
    if (ia->desc.script) {
        ia->script = input_script_open(ia->desc.script);
        if (!ia->script)
            goto error;
        ia->sources[ia->n_sources++] = ia->script;
    }
    if (ia->desc.window) {
        ia->glfw = input_glfw_create(ia->desc.window);
        if (!ia->glfw)
            goto error;
        ia->sources[ia->n_sources++] = ia->glfw;
    }
    if (ia->desc.wand) {
        struct input_source *w = input_ohmd_create(ia->desc.wand, NULL);
        if (!w)
            goto error;
        ia->sources[ia->n_sources++] = w;
    }
    struct menu_model model;
    model_from_session(ia, &model);
    ia->menu = menu_create(&(struct menu_desc){.step_date = date_of, .user = ia->player}, &model);
    if (!ia->menu)
        goto error;
    menu_set_visible(ia->menu, ia->desc.show_menu);
    menu_take_changes(ia->menu);
    ia->view = menu_view_create(r);
    if (!ia->view)
        goto error;
    return ia;

error:
    interact_destroy(ia);
    return NULL;
}

void interact_destroy(struct interact *ia)
{
    if (!ia)
        return;
    menu_view_destroy(ia->view, ia->renderer);
    menu_destroy(ia->menu);
    for (int i = 0; i < ia->n_sources; i++)
        input_source_destroy(ia->sources[i]);
    player_destroy(ia->player);
    free(ia);
}

struct menu *interact_menu(struct interact *ia)
{
    return ia->menu;
}

int interact_step(const struct interact *ia)
{
    return ia->shown;
}

double interact_script_dt(const struct interact *ia)
{
    return ia->script ? 1.0 / input_script_fps(ia->script) : 0.0;
}

bool interact_script_done(struct interact *ia)
{
    return ia->script && input_source_finished(ia->script) &&
           player_settled(ia->player, ia->playback.step);
}

/* ---- applying the menu's changes ------------------------------------------------------ */

static void sun_settings(const struct config *cfg, struct render_settings *s)
{
    struct render_settings fresh;
    scene_render_settings(cfg, &fresh);
    memcpy(s->sun_dir, fresh.sun_dir, sizeof(s->sun_dir));
    memcpy(s->sun_radiance, fresh.sun_radiance, sizeof(s->sun_radiance));
}

static void transfer_path(const struct interact *ia, int slot, char *buf, size_t size)
{
    snprintf(buf, size, "%s/tf-%d.cfg", ia->transfers_dir, slot + 1);
}

static void apply_changes(struct interact *ia, unsigned ch, struct render_settings *s,
                          const struct interact_frame *f, bool *nav_changed)
{
    struct menu_model *m = menu_model(ia->menu);
    struct config *cfg = ia->cfg;
    if (ch & MENU_CHANGE_PLAYBACK) {
        if (m->playing && !ia->playback.playing && ia->playback.step >= ia->playback.count - 1 &&
            !m->loop)
            ia->playback.step = 0; /* play again from the start */
        ia->playback.playing = m->playing;
        ia->playback.loop = m->loop;
        ia->playback.speed = m->speed;
        ia->playback.acc = 0.0;
    }
    if (ch & MENU_CHANGE_STEP) {
        ia->playback.step = m->step;
        ia->playback.acc = 0.0;
    }
    if (ch & (MENU_CHANGE_SPECIES | MENU_CHANGE_TRANSFER)) {
        for (int sp = 0; sp < SPECIES_COUNT; sp++) {
            ia->look.select.enabled[sp] = m->species_on[sp];
            ia->look.select.scale[sp] = m->species_scale[sp];
            memcpy(ia->look.tint.rgb[sp], m->species_tint[sp], sizeof(m->species_tint[sp]));
        }
        ia->look.transfer_on = m->transfer_on;
        ia->look.transfer = m->transfer;
        if (player_has_fields(ia->player))
            player_set_look(ia->player, &ia->look);
        else
            menu_set_status(ia->menu, "this scene has no mass ratios to change");
    }
    if (ch & MENU_CHANGE_SUN) {
        cfg->light.azimuth_deg = m->sun_azimuth;
        cfg->light.elevation_deg = m->sun_elevation;
        sun_settings(cfg, s);
    }
    if (ch & MENU_CHANGE_QUALITY) {
        cfg->render.step_m = m->step_m;
        s->step_m = (float)m->step_m;
        for (int a = 0; a < 3; a++)
            cfg->lightmap.resolution[a] = m->light_resolution;
        cfg->lightmap.epsilon = m->epsilon;
        set_diffuse(ia, m->diffuse_on);
    }
    if (ch & (MENU_ACTION_SAVE | MENU_ACTION_LOAD)) {
        char path[CONFIG_PATH_MAX + 32], status[128];
        transfer_path(ia, m->slot, path, sizeof(path));
        if (ch & MENU_ACTION_SAVE) {
            snprintf(m->transfer.name, sizeof(m->transfer.name), "tf-%d", m->slot + 1);
            bool ok = transfer_file_save(path, &m->transfer);
            snprintf(status, sizeof(status), ok ? "saved %s" : "not saved: %s",
                     ok ? path : log_last_error());
        } else {
            struct transfer_function tf = m->transfer;
            bool ok = transfer_file_load(path, &tf);
            if (ok) {
                m->transfer = tf;
                ia->look.transfer = tf;
                if (player_has_fields(ia->player))
                    player_set_look(ia->player, &ia->look);
            }
            snprintf(status, sizeof(status), ok ? "loaded %s" : "kept the current one: %s",
                     ok ? path : log_last_error());
        }
        menu_set_status(ia->menu, status);
        menu_model_changed(ia->menu);
    }
    if ((ch & MENU_ACTION_RESET_VIEW) && f->nav && f->nav_home) {
        *f->nav = *f->nav_home;
        *nav_changed = true;
    }
}

/* ---- navigation (tracker space) ------------------------------------------------------- */

static void navigate(struct interact *ia, const struct interact_frame *f,
                     bool *nav_changed)
{
    struct display_navigation *nav = f->nav;
    if (!nav || !ia->have_wand)
        return;
    if (ia->grabbing) {
        for (int i = 0; i < 3; i++)
            nav->position[i] = ia->grab_position[i] + (ia->wand_pos[i] - ia->grab_wand[i]);
        *nav_changed = true;
    }
    float fly = ia->axis[INPUT_AXIS_FLY], turn = ia->axis[INPUT_AXIS_TURN];
    if (fly != 0.0f && f->dt > 0.0) {
        /* Flying forward along the wand moves the world toward the user. */
        for (int i = 0; i < 3; i++)
            nav->position[i] -= ia->wand_dir[i] * fly * FLY_SPEED * f->dt;
        *nav_changed = true;
    }
    if (turn != 0.0f && f->dt > 0.0) {
        nav->orientation_deg[0] = fmod(nav->orientation_deg[0] + turn * TURN_SPEED * f->dt,
                                       360.0);
        *nav_changed = true;
    }
}

/* ---- frames --------------------------------------------------------------------------- */

static void place_menu(struct interact *ia, const struct interact_frame *f)
{
    if (ia->desc.tracker_space) {
        if (ia->placed)
            return;
        /* In front of the user, a little below the eyes, facing them. */
        const float c[3] = {f->head[0], f->head[1] - 0.35f, f->head[2] - 0.75f};
        const float r[3] = {1, 0, 0}, u[3] = {0, 1, 0};
        menu_set_pose(ia->menu, c, r, u, 0.6f);
        ia->placed = true;
        return;
    }
    if (!f->have_camera)
        return;
    /* A panel on the right of the desktop view, following the camera. */
    mat4 view, inv;
    memcpy(view, f->view, sizeof(view));
    glm_mat4_inv(view, inv);
    float near = f->proj[14] / (f->proj[10] - 1.0f);
    float dist = 3.0f * fabsf(near);
    float half_h = dist / f->proj[5], half_w = dist / f->proj[0];
    float width = fminf(0.85f * half_w, 1.8f * half_h / menu_aspect(ia->menu));
    float c[3], r[3], u[3];
    for (int i = 0; i < 3; i++) {
        r[i] = inv[0][i];
        u[i] = inv[1][i];
        c[i] = inv[3][i] - inv[2][i] * dist + r[i] * (half_w * 0.97f - 0.5f * width);
    }
    menu_set_pose(ia->menu, c, r, u, width);
}

/* Menu space -> world, and world -> menu space. */
static void menu_matrices(const struct interact *ia, const struct interact_frame *f,
                          mat4 to_world, mat4 from_world)
{
    if (ia->desc.tracker_space && f->nav) {
        float n[16];
        display_navigation_matrix(f->nav, n);
        memcpy(from_world, n, sizeof(mat4));
        glm_mat4_inv(from_world, to_world);
    } else {
        glm_mat4_identity(to_world);
        glm_mat4_identity(from_world);
    }
}

static void to_menu_space(const struct interact *ia, mat4 from_world, struct input_event *e)
{
    bool world_menu = !ia->desc.tracker_space;
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
    for (int i = 0; i < 3; i++) {
        e->position[i] = pt[i];
        e->direction[i] = len > 0.0f ? dt[i] / len : 0.0f;
    }
    e->space = INPUT_SPACE_TRACKER;
}

static bool upload(struct interact *ia, const struct ext_volume *v)
{
    if (!renderer_set_volume(ia->renderer, v))
        return false;
    ia->light->generation++;
    ia->stats->volume_uploads++;
    ia->stats->upload_ms_total += renderer_stats(ia->renderer)->upload_ms;
    return true;
}

/* effects.temporal: keeps step k + 1 in the renderer's next volume and asks the eye pass to
 * blend it in at the playback position's fraction f (the light map pair follows: app_light).
 * Until k + 1 is on the GPU (or while step k itself is still loading) f is 0: step k. */
static bool temporal_frame(struct interact *ia, struct render_settings *s, bool *redraw)
{
    const struct playback *pb = &ia->playback;
    int next = -1;
    if (pb->count > 1 && ia->shown == pb->step) {
        next = pb->step + 1;
        if (next >= pb->count)
            next = pb->loop ? 0 : -1;
    }
    int held = -1;
    const struct ext_volume *v =
        player_poll_next(ia->player, next, ia->desc.wait_for_volumes, &held);
    if (v) {
        if (!renderer_set_next_volume(ia->renderer, v))
            return false;
        ia->stats->volume_uploads++;
        *redraw = true;
    }
    uint64_t next_id = next >= 0 && held == next ? player_step_id(ia->player, true) : 0;
    ia->light->temporal = true;
    ia->light->step_id = player_step_id(ia->player, false);
    ia->light->next_id = next_id;
    double f = pb->acc < 0.0 ? 0.0 : pb->acc > 1.0 ? 1.0 : pb->acc;
    s->temporal = next_id != 0;
    s->temporal_f = next_id != 0 ? (float)f : 0.0f;
    return true;
}

static bool ready(void *user, int step)
{
    return player_ready(user, step);
}

bool interact_frame(struct interact *ia, const struct interact_frame *f,
                        struct render_settings *s, bool *redraw, bool *nav_changed)
{
    *redraw = false;
    *nav_changed = false;
    place_menu(ia, f);
    mat4 to_world, from_world;
    menu_matrices(ia, f, to_world, from_world);

    struct input_frame in = {.frame = ia->frame, .time = 0.0};
    if (f->have_camera) {
        mat4 v, p, vp, inv;
        memcpy(v, f->view, sizeof(v));
        memcpy(p, f->proj, sizeof(p));
        glm_mat4_mul(p, v, vp);
        glm_mat4_inv(vp, inv);
        memcpy(in.inv_view_proj, inv, sizeof(in.inv_view_proj));
        in.have_camera = true;
        in.width = f->width;
        in.height = f->height;
    }
    input_queue_clear(&ia->queue);
    for (int i = 0; i < ia->n_sources; i++) {
        if (!input_source_poll(ia->sources[i], &in, &ia->queue))
            return false;
    }
    ia->frame++;
    unsigned before = 0;
    menu_pixels(ia->menu, &(int){0}, &(int){0}, &before);
    for (int i = 0; i < ia->queue.count; i++) {
        struct input_event e = ia->queue.events[i];
        if (e.type == INPUT_POSE) {
            to_menu_space(ia, from_world, &e);
            if (e.type != INPUT_POSE)
                continue;
            memcpy(ia->wand_pos, e.position, sizeof(ia->wand_pos));
            memcpy(ia->wand_dir, e.direction, sizeof(ia->wand_dir));
            ia->have_wand = true;
        } else if (e.type == INPUT_AXIS && e.axis < INPUT_AXIS_COUNT) {
            ia->axis[e.axis] = e.value;
        } else if (e.type == INPUT_BUTTON && e.button == INPUT_BUTTON_GRAB && f->nav &&
                   ia->desc.tracker_space) {
            ia->grabbing = e.down && ia->have_wand;
            memcpy(ia->grab_wand, ia->wand_pos, sizeof(ia->grab_wand));
            memcpy(ia->grab_position, f->nav->position, sizeof(ia->grab_position));
        }
        menu_handle(ia->menu, &e);
    }
    if (ia->glfw)
        input_glfw_capture(ia->glfw, menu_captures(ia->menu));
    navigate(ia, f, nav_changed);

    unsigned ch = menu_take_changes(ia->menu);
    apply_changes(ia, ch, s, f, nav_changed);

    /* Playback: the cursor advances only onto loaded steps; the volume follows it. */
    struct menu_model *m = menu_model(ia->menu);
    int old_step = ia->playback.step;
    playback_tick(&ia->playback, f->dt, ia->desc.wait_for_volumes ? NULL : ready,
                      ia->player);
    if (ia->playback.step != old_step || m->playing != ia->playback.playing) {
        m->step = ia->playback.step;
        m->playing = ia->playback.playing;
        menu_model_changed(ia->menu);
    }
    bool present[SPECIES_COUNT];
    player_species_present(ia->player, present);
    if (memcmp(present, m->species_present, sizeof(present)) != 0) {
        memcpy(m->species_present, present, sizeof(present));
        menu_model_changed(ia->menu);
    }
    const struct ext_volume *v =
        ia->desc.wait_for_volumes ? player_wait(ia->player, ia->playback.step, &ia->shown)
                                  : player_poll(ia->player, ia->playback.step, &ia->shown);
    if (v) {
        if (!upload(ia, v))
            return false;
        *redraw = true;
    } else if (!player_settled(ia->player, ia->playback.step)) {
        ia->stats->frames_stale++;
    }
    if (ia->light->have_effects && ia->light->effects.on[EFFECT_TEMPORAL] &&
        !temporal_frame(ia, s, redraw))
        return false;
    player_stats(ia->player, ia->stats);
    ia->stats->time_step = ia->shown;

    float tw[16];
    memcpy(tw, to_world, sizeof(tw));
    if (!menu_view_update(ia->view, ia->menu, tw, (float)ia->cfg->render.exposure))
        return false;
    unsigned after = 0;
    menu_pixels(ia->menu, &(int){0}, &(int){0}, &after);
    if (after != before || ch || ia->queue.count > 0 || ia->playback.playing || *nav_changed)
        *redraw = true;
    return true;
}

bool interact_settle(struct interact *ia)
{
    if (player_settled(ia->player, ia->playback.step))
        return true;
    const struct ext_volume *v = player_wait(ia->player, ia->playback.step, &ia->shown);
    player_stats(ia->player, ia->stats);
    ia->stats->time_step = ia->shown;
    if (!v)
        return player_settled(ia->player, ia->playback.step);
    return upload(ia, v);
}
