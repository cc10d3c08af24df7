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
        if (ok)
            log_info("time step %d (%s) read in %.0f ms, converted in %.0f ms", cfg->data.step,
                     data_source_step_date(src, cfg->data.step), load_ms, convert_ms);
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

