#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "session/scene.h"
#include "session/effects.h"
#include "common/log.h"
#include "data/detail.h"
#include "data/source.h"
#include "data/synth.h"
#include "light/light.h"
#include "render/camera.h"

/* One time step (data.step) of the files the config names, as extinction. */
static bool load_data_step(const struct config *cfg, struct ext_volume *out)
{
    const char *files[CONFIG_MAX_FILES];
    struct data_source_desc desc;
    scene_source_desc(cfg, files, &desc);
    struct data_source *src = data_source_open(&desc);
    if (!src)
        return false;
    int steps = data_source_step_count(src);
    bool ok = false;
    if (cfg->data.step < 0 || cfg->data.step >= steps) {
        log_error("%s: data.step: expected a time step in [0, %d], got %d", cfg->path,
                  steps - 1, cfg->data.step);
    } else {
        double load_ms = 0.0, convert_ms = 0.0;
        ok = data_source_load(src, cfg->data.step, out, &load_ms, &convert_ms);
        if (ok) {
            const char *date = data_source_step_date(src, cfg->data.step);
            log_info("time step %d%s%s%s read in %.0f ms, converted in %.0f ms", cfg->data.step,
                     date[0] ? " (" : "", date, date[0] ? ")" : "", load_ms, convert_ms);
        }
    }
    data_source_close(src);
    return ok;
}

bool scene_synth_desc(const struct config *cfg, struct synth_desc *d)
{
    const struct config_scene *sc = &cfg->scene;
    memset(d, 0, sizeof(*d));
    switch (sc->kind) {
    case SCENE_STORM:
    case SCENE_DATA:
        d->kind = SYNTH_STORM;
        break;
    case SCENE_SLAB:
        d->kind = SYNTH_SLAB;
        break;
    case SCENE_SPHERE:
        d->kind = SYNTH_SPHERE;
        break;
    case SCENE_EMPTY:
        d->kind = SYNTH_EMPTY;
        break;
    case SCENE_VOXEL:
        d->kind = SYNTH_VOXEL;
        break;
    }
    for (int i = 0; i < 3; i++) {
        d->n[i] = sc->size[i];
        d->extent_m[i] = sc->extent_km[i] * 1000.0;
    }
    d->tau = sc->tau;
    d->ice_phase = sc->phase == PHASE_ICE;
    d->seed = sc->seed;
    d->time = sc->time;
    /* The same memory budget as data: the storm holds five mass ratios and the extinction
     * (7 floats a voxel), the test scenes the extinction alone. */
    double voxels = (double)d->n[0] * d->n[1] * d->n[2];
    double mib = voxels * (d->kind == SYNTH_STORM ? 7.0 : 2.0) * sizeof(float) / 1048576.0;
    if (mib > cfg->data.memory_mb) {
        log_error("%s%sscene.size [%d, %d, %d] needs %.0f MiB, more than data.memory (%.0f "
                  "MiB): lower scene.size or raise data.memory",
                  cfg->path, cfg->path[0] ? ": " : "", d->n[0], d->n[1], d->n[2], mib,
                  cfg->data.memory_mb);
        return false;
    }
    return true;
}

bool scene_build_synth(const struct synth_desc *d, const struct optics_params *optics,
                       const struct species_select *sel, const struct detail_desc *detail,
                       double height_k, struct ext_volume *out)
{
    /* Detail and height exaggeration as data sources apply them (data_source_load). */
    if (d->kind != SYNTH_STORM) {
        if (!synth_extinction(d, optics, out))
            return false;
        detail_apply_ext(detail, out);
        ext_volume_stretch_height(out, height_k);
        return true;
    }
    /* The storm goes through the species selection like real data does. */
    struct field_volume fields = {0};
    if (!synth_storm_fields(d, &fields))
        return false;
    detail_apply_fields(detail, &fields);
    bool ok = ext_volume_from_fields(&fields, optics, sel, out);
    field_volume_finish(&fields);
    if (ok)
        ext_volume_stretch_height(out, height_k);
    return ok;
}

void scene_species_select(const struct config *cfg, struct species_select *out)
{
    for (int f = 0; f < SPECIES_COUNT; f++) {
        out->enabled[f] = cfg->optics.enabled[f];
        out->scale[f] = cfg->optics.scale[f];
    }
}

bool scene_build_volume(const struct config *cfg, struct ext_volume *out)
{
    if (cfg->scene.kind == SCENE_DATA)
        return load_data_step(cfg, out);
    struct synth_desc d;
    if (!scene_synth_desc(cfg, &d))
        return false;
    struct detail_desc detail;
    scene_detail_desc(cfg, &detail);
    struct species_select sel;
    scene_species_select(cfg, &sel);
    return scene_build_synth(&d, &cfg->optics.params, &sel, &detail,
                             cfg->scene.height_exaggeration, out);
}

/* Sunlight through the air (light.atmosphere): Rayleigh optical depths at the wavelengths we
 * take for R, G, B (680, 550, 440 nm) plus a little aerosol, times the air mass of the path
 * (Kasten and Young's formula, finite at the horizon).  Normalised to the sun overhead, so that
 * light.color stays the noon colour.  An approximation: no ozone, no multiple scattering, one
 * standard clear atmosphere. */
void scene_sun_transmittance(double elevation_deg, double rgb[3])
{
    static const double tau[3] = {0.036 + 0.05, 0.097 + 0.06, 0.236 + 0.07};
    double el = fmax(elevation_deg, 0.0);
    double air_mass = 1.0 / (sin(el * M_PI / 180.0) + 0.50572 * pow(el + 6.07995, -1.6364));
    for (int c = 0; c < 3; c++)
        rgb[c] = exp(-tau[c] * (air_mass - 1.0));
}

int scene_time_steps(const struct config *cfg)
{
    if (cfg->scene.kind != SCENE_DATA)
        return 1;
    const char *files[CONFIG_MAX_FILES];
    struct data_source_desc desc;
    scene_source_desc(cfg, files, &desc);
    struct data_source *src = data_source_open(&desc);
    if (!src)
        return 0;
    int steps = data_source_step_count(src);
    data_source_close(src);
    return steps;
}

void scene_sun_settings(const struct config *cfg, double azimuth_deg, double elevation_deg,
                        struct render_settings *s)
{
    double sun[3];
    light_sun_direction(azimuth_deg, elevation_deg, sun);
    double air[3];
    scene_sun_transmittance(elevation_deg, air);
    for (int i = 0; i < 3; i++) {
        s->sun_dir[i] = (float)sun[i];
        s->sun_radiance[i] = (float)(cfg->light.intensity * cfg->light.color[i]);
        if (cfg->light.atmosphere)
            s->sun_radiance[i] *= (float)air[i];
    }
}

void scene_render_settings(const struct config *cfg, struct render_settings *s)
{
    memset(s, 0, sizeof(*s));
    scene_sun_settings(cfg, cfg->light.azimuth_deg, cfg->light.elevation_deg, s);
    for (int i = 0; i < 3; i++) {
        s->sky[i] = (float)cfg->render.sky[i];
        s->ground[i] = (float)cfg->render.ground[i];
    }
    s->ground_on = cfg->render.ground_on;
    s->step_m = (float)cfg->render.step_m;
    s->termination = (float)cfg->render.termination;
    s->lod_pixels = (float)cfg->render.lod_pixels;
    s->no_skip = !cfg->render.skip;
}

void scene_camera(const struct config *cfg, struct display_camera *out)
{
    const struct config_camera *c = &cfg->camera;
    for (int i = 0; i < 3; i++) {
        out->eye[i] = c->position_km[i] * 1000.0;
        out->target[i] = c->target_km[i] * 1000.0;
        out->up[i] = c->up[i];
    }
    out->fov_deg = c->fov_deg;
    out->near_m = c->near_m;
    out->far_m = c->far_km * 1000.0;
}

void scene_camera_view(const struct config *cfg, int width, int height, struct render_view *view)
{
    const struct config_camera *c = &cfg->camera;
    double eye[3], target[3];
    for (int i = 0; i < 3; i++) {
        eye[i] = c->position_km[i] * 1000.0;
        target[i] = c->target_km[i] * 1000.0;
    }
    camera_look_at(eye, target, c->up, c->fov_deg, c->near_m, c->far_km * 1000.0, width,
                   height, view);
}


void scene_source_desc(const struct config *cfg, const char **file_ptrs,
                          struct data_source_desc *out)
{
    const struct config_data *cd = &cfg->data;
    memset(out, 0, sizeof(*out));
    out->format = cd->format == DATA_ISABEL       ? DATA_SOURCE_ISABEL
                  : cd->format == DATA_EXTINCTION ? DATA_SOURCE_EXTINCTION
                  : cd->format == DATA_CM1        ? DATA_SOURCE_CM1
                  : cd->format == DATA_CF         ? DATA_SOURCE_CF
                                                  : DATA_SOURCE_WRF;
    for (int i = 0; i < cd->file_count; i++)
        file_ptrs[i] = cd->files[i];
    out->files = file_ptrs;
    out->file_count = cd->file_count;
    wrf_desc_defaults(&out->wrf);
    out->wrf.levels = cd->levels;
    out->wrf.native_levels = cd->vertical == DATA_VERTICAL_NATIVE && cd->levels == 0;
    out->wrf.top_m = cd->top_km * 1000.0;
    for (int a = 0; a < 3; a++)
        out->wrf.stride[a] = cd->stride[a];
    for (int i = 0; i < 6; i++)
        out->wrf.crop[i] = cd->crop[i];
    out->wrf.memory_mb = cd->memory_mb;
    out->isabel.memory_mb = cd->memory_mb;
    for (int a = 0; a < 3; a++) {
        out->isabel.n[a] = cd->isabel_size[a];
        out->isabel.extent_m[a] = cd->isabel_extent_km[a] * 1000.0;
    }
    out->optics = cfg->optics.params;
    for (int f = 0; f < SPECIES_COUNT; f++) {
        out->select.enabled[f] = cfg->optics.enabled[f];
        out->select.scale[f] = cfg->optics.scale[f];
    }
    scene_detail_desc(cfg, &out->detail);
    out->height_scale = cfg->scene.height_exaggeration;
}

void scene_detail_desc(const struct config *cfg, struct detail_desc *out)
{
    memset(out, 0, sizeof(*out));
    out->on = effects_detail_on(cfg);
    for (int f = 0; f < SPECIES_COUNT; f++)
        out->amount[f] = cfg->detail.amount[f];
    out->scale_m = cfg->detail.scale_km * 1000.0;
    out->seed = cfg->detail.seed;
}


/* ---- framing -------------------------------------------------------------------------- */

bool scene_domain_box(const struct config *cfg, double lo[3], double hi[3])
{
    struct grid3 g = {0};
    if (cfg->scene.kind == SCENE_DATA) {
        const char *files[CONFIG_MAX_FILES];
        struct data_source_desc desc;
        scene_source_desc(cfg, files, &desc);
        struct data_source *src = data_source_open(&desc);
        if (!src)
            return false;
        bool ok = data_source_grid(src, &g);
        data_source_close(src);
        if (!ok)
            return false;
    } else {
        struct synth_desc d;
        if (!scene_synth_desc(cfg, &d))
            return false;
        double k = cfg->scene.height_exaggeration > 0.0 ? cfg->scene.height_exaggeration : 1.0;
        for (int a = 0; a < 3; a++) {
            g.n[a] = d.n[a];
            g.spacing[a] = d.extent_m[a] / d.n[a] * (a == 2 ? k : 1.0);
            g.origin[a] = 0.0;
        }
    }
    for (int a = 0; a < 3; a++) {
        lo[a] = g.origin[a];
        hi[a] = g.origin[a] + g.n[a] * g.spacing[a];
    }
    return true;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static void normalize3(double v[3])
{
    double n = sqrt(dot3(v, v));
    for (int i = 0; i < 3; i++)
        v[i] /= n;
}

void scene_frame_camera(const double lo[3], const double hi[3], double fov_deg, double aspect,
                        double near_m, struct display_camera *out)
{
    const double azimuth = 225.0, elevation = 30.0, margin = 0.9;
    double centre[3], toward_eye[3], forward[3], right[3], up[3];
    const double z_up[3] = {0.0, 0.0, 1.0};
    for (int i = 0; i < 3; i++)
        centre[i] = 0.5 * (lo[i] + hi[i]);
    camera_direction(azimuth, elevation, toward_eye);
    for (int i = 0; i < 3; i++)
        forward[i] = -toward_eye[i];
    cross3(forward, z_up, right);
    normalize3(right);
    cross3(right, forward, up);
    /* A corner at q from the centre lies at depth D + q.forward from an eye at distance D,
     * q.right across and q.up above the axis; it is inside the image's middle part when both
     * are within margin * tan(half angle) * depth. */
    double tan_v = margin * tan(0.5 * fov_deg * M_PI / 180.0), tan_h = tan_v * aspect;
    double distance = 0.0, diagonal = 0.0;
    for (int c = 0; c < 8; c++) {
        double q[3] = {(c & 1 ? hi[0] : lo[0]) - centre[0], (c & 2 ? hi[1] : lo[1]) - centre[1],
                       (c & 4 ? hi[2] : lo[2]) - centre[2]};
        double along = dot3(q, forward);
        distance = fmax(distance, fabs(dot3(q, right)) / tan_h - along);
        distance = fmax(distance, fabs(dot3(q, up)) / tan_v - along);
        distance = fmax(distance, 2.0 * near_m - along);
        diagonal = fmax(diagonal, sqrt(dot3(q, q)));
    }
    for (int i = 0; i < 3; i++) {
        out->eye[i] = centre[i] + distance * toward_eye[i];
        out->target[i] = centre[i];
        out->up[i] = z_up[i];
    }
    out->fov_deg = fov_deg;
    out->near_m = near_m;
    out->far_m = fmax(2.0 * (distance + diagonal), 2000e3);
}

void scene_camera_to_config(const struct display_camera *c, struct config_camera *out)
{
    for (int i = 0; i < 3; i++) {
        out->position_km[i] = c->eye[i] / 1000.0;
        out->target_km[i] = c->target[i] / 1000.0;
        out->up[i] = c->up[i];
    }
    out->fov_deg = c->fov_deg;
    out->near_m = c->near_m;
    out->far_km = c->far_m / 1000.0;
}

void scene_frame_navigation(const double lo[3], const double hi[3],
                            const struct display_config *cfg, struct display_navigation *out)
{
    const double *head = cfg->head.position;
    /* The room in tracker metres (x right, y up, z toward the back). */
    double rlo[3], rhi[3];
    if (cfg->type == DISPLAY_TYPE_CAVE && cfg->wall_count > 0) {
        for (int i = 0; i < 3; i++)
            rlo[i] = INFINITY, rhi[i] = -INFINITY;
        for (int w = 0; w < cfg->wall_count; w++) {
            const struct display_wall *wall = &cfg->walls[w];
            for (int i = 0; i < 3; i++) {
                double c[4] = {wall->lower_left[i], wall->lower_right[i], wall->upper_left[i],
                               wall->lower_right[i] + wall->upper_left[i] - wall->lower_left[i]};
                for (int k = 0; k < 4; k++) {
                    rlo[i] = fmin(rlo[i], c[k]);
                    rhi[i] = fmax(rhi[i], c[k]);
                }
            }
        }
    } else {
        rlo[0] = head[0] - 1.5, rhi[0] = head[0] + 1.5;
        rlo[1] = 0.0, rhi[1] = fmax(head[1], 1.0);
        rlo[2] = head[2] - 3.7, rhi[2] = head[2];
    }
    /* The footprint: 80 % of the room's width, from the front wall to 0.2 m before the head
     * (the whole room's depth where the head stands outside it). */
    double front = rlo[2], back = fmin(rhi[2], head[2] - 0.2);
    if (!(back - front > 0.5))
        front = rlo[2], back = rhi[2];
    double width = 0.8 * (rhi[0] - rlo[0]), depth = back - front;
    /* The top at least 0.3 m below the eyes (and 1 m tall at most where the eyes are low). */
    double floor = rlo[1], tall = head[1] - floor - 0.3;
    if (!(tall > 0.3))
        tall = 1.0;
    double w = hi[0] - lo[0], d = hi[1] - lo[1], h = hi[2] - lo[2];
    double scale = fmin(fmin(width / w, depth / d), tall / h);
    memset(out, 0, sizeof(*out));
    out->scale = scale;
    out->origin_km[0] = 0.5 * (lo[0] + hi[0]) / 1000.0;
    out->origin_km[1] = 0.5 * (lo[1] + hi[1]) / 1000.0;
    out->origin_km[2] = lo[2] / 1000.0;
    /* Straight ahead of the head (north along -z), its southern edge at the back of the
     * footprint. */
    out->position[0] = head[0];
    out->position[1] = floor;
    out->position[2] = back - 0.5 * d * scale;
}
