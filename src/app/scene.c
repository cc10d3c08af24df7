#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "app/cmd_data.h"
#include "common/log.h"
#include "data/detail.h"
#include "data/source.h"
#include "data/synth.h"
#include "light/light.h"
#include "render/camera.h"

bool app_load_config(const char *config_path, char **sets, int n_sets, struct config *cfg)
{
    config_defaults(cfg);
    if (config_path && !config_load(config_path, cfg))
        return false;
    for (int i = 0; i < n_sets; i++) {
        if (!config_set(cfg, sets[i]))
            return false;
    }
    return config_validate(cfg);
}

/* One time step (data.step) of the files the config names, as extinction. */
static bool load_data_step(const struct config *cfg, struct ext_volume *out)
{
    const char *files[CONFIG_MAX_FILES];
    struct data_source_desc desc;
    cmd_data_source_desc(cfg, files, &desc);
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

bool app_build_volume(const struct config *cfg, struct ext_volume *out)
{
    const struct config_scene *sc = &cfg->scene;
    struct synth_desc d = {0};
    switch (sc->kind) {
    case SCENE_STORM:
        d.kind = SYNTH_STORM;
        break;
    case SCENE_SLAB:
        d.kind = SYNTH_SLAB;
        break;
    case SCENE_SPHERE:
        d.kind = SYNTH_SPHERE;
        break;
    case SCENE_EMPTY:
        d.kind = SYNTH_EMPTY;
        break;
    case SCENE_VOXEL:
        d.kind = SYNTH_VOXEL;
        break;
    case SCENE_DATA:
        return load_data_step(cfg, out);
    }
    for (int i = 0; i < 3; i++) {
        d.n[i] = sc->size[i];
        d.extent_m[i] = sc->extent_km[i] * 1000.0;
    }
    d.tau = sc->tau;
    d.ice_phase = sc->phase == PHASE_ICE;
    d.seed = sc->seed;
    d.time = sc->time;
    /* The same memory budget as data: the storm holds five mass ratios and the extinction
     * (7 floats a voxel), the test scenes the extinction alone. */
    double voxels = (double)d.n[0] * d.n[1] * d.n[2];
    double mib = voxels * (d.kind == SYNTH_STORM ? 7.0 : 2.0) * sizeof(float) / 1048576.0;
    if (mib > cfg->data.memory_mb) {
        log_error("%s%sscene.size [%d, %d, %d] needs %.0f MiB, more than data.memory (%.0f "
                  "MiB): lower scene.size or raise data.memory",
                  cfg->path, cfg->path[0] ? ": " : "", d.n[0], d.n[1], d.n[2], mib,
                  cfg->data.memory_mb);
        return false;
    }
    /* Detail and height exaggeration as data sources apply them (data_source_load). */
    struct detail_desc detail;
    cmd_data_detail_desc(cfg, &detail);
    if (d.kind != SYNTH_STORM) {
        if (!synth_extinction(&d, &cfg->optics.params, out))
            return false;
        detail_apply_ext(&detail, out);
        ext_volume_stretch_height(out, cfg->scene.height_exaggeration);
        return true;
    }

    /* The storm goes through the species selection like real data does. */
    struct field_volume fields = {0};
    if (!synth_storm_fields(&d, &fields))
        return false;
    struct species_select sel;
    for (int f = 0; f < SPECIES_COUNT; f++) {
        sel.enabled[f] = cfg->optics.enabled[f];
        sel.scale[f] = cfg->optics.scale[f];
    }
    detail_apply_fields(&detail, &fields);
    bool ok = ext_volume_from_fields(&fields, &cfg->optics.params, &sel, out);
    field_volume_finish(&fields);
    if (ok)
        ext_volume_stretch_height(out, cfg->scene.height_exaggeration);
    return ok;
}

/* Sunlight through the air (light.atmosphere): Rayleigh optical depths at the wavelengths we
 * take for R, G, B (680, 550, 440 nm) plus a little aerosol, times the air mass of the path
 * (Kasten and Young's formula, finite at the horizon).  Normalised to the sun overhead, so that
 * light.color stays the noon colour.  An approximation: no ozone, no multiple scattering, one
 * standard clear atmosphere. */
void app_sun_transmittance(double elevation_deg, double rgb[3])
{
    static const double tau[3] = {0.036 + 0.05, 0.097 + 0.06, 0.236 + 0.07};
    double el = fmax(elevation_deg, 0.0);
    double air_mass = 1.0 / (sin(el * M_PI / 180.0) + 0.50572 * pow(el + 6.07995, -1.6364));
    for (int c = 0; c < 3; c++)
        rgb[c] = exp(-tau[c] * (air_mass - 1.0));
}

int app_time_steps(const struct config *cfg)
{
    if (cfg->scene.kind != SCENE_DATA)
        return 1;
    const char *files[CONFIG_MAX_FILES];
    struct data_source_desc desc;
    cmd_data_source_desc(cfg, files, &desc);
    struct data_source *src = data_source_open(&desc);
    if (!src)
        return 0;
    int steps = data_source_step_count(src);
    data_source_close(src);
    return steps;
}

void app_render_settings(const struct config *cfg, struct render_settings *s)
{
    memset(s, 0, sizeof(*s));
    double sun[3];
    light_sun_direction(cfg->light.azimuth_deg, cfg->light.elevation_deg, sun);
    double air[3];
    app_sun_transmittance(cfg->light.elevation_deg, air);
    for (int i = 0; i < 3; i++) {
        s->sun_dir[i] = (float)sun[i];
        s->sun_radiance[i] = (float)(cfg->light.intensity * cfg->light.color[i]);
        if (cfg->light.atmosphere)
            s->sun_radiance[i] *= (float)air[i];
        s->sky[i] = (float)cfg->render.sky[i];
        s->ground[i] = (float)cfg->render.ground[i];
    }
    s->ground_on = cfg->render.ground_on;
    s->step_m = (float)cfg->render.step_m;
    s->termination = (float)cfg->render.termination;
}

void app_camera_view(const struct config *cfg, int width, int height, struct render_view *view)
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

void app_stats_add_view(struct app_stats *st)
{
    st->views++;
}

void app_stats_add_build(struct app_stats *st)
{
    st->light_builds++;
}

/* The first GPU_TIMINGS_KEPT times of T; null where one has not arrived. */
static void write_list(FILE *f, const struct gpu_timings *t)
{
    unsigned n = t->count < GPU_TIMINGS_KEPT ? t->count : GPU_TIMINGS_KEPT;
    fputc('[', f);
    for (unsigned i = 0; i < n; i++) {
        fputs(i ? ", " : "", f);
        if (t->known[i])
            fprintf(f, "%.4f", t->ms[i]);
        else
            fputs("null", f);
    }
    fputc(']', f);
}

bool app_stats_write(const struct app_stats *st, const char *path)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f) {
        log_error("%s: out of memory", path);
        return false;
    }
    fprintf(f, "{\n  \"command\": \"%s\",\n", st->command ? st->command : "");
    fprintf(f, "  \"device\": \"");
    for (const char *p = st->device ? st->device : ""; *p; p++) {
        if (*p == '"' || *p == '\\')
            fputc('\\', f);
        fputc(*p, f);
    }
    fprintf(f, "\",\n  \"views\": %u,\n  \"light_map_builds\": %u,\n", st->views,
            st->light_builds);
    fprintf(f, "  \"view_ms\": ");
    write_list(f, &st->view_times);
    fprintf(f, ",\n  \"build_ms\": ");
    write_list(f, &st->build_times);
    fprintf(f, ",\n  \"light_map_bytes_dense\": %.0f,\n", st->light_bytes_dense);
    fprintf(f, "  \"light_map_bytes_compressed\": %.0f,\n", st->light_bytes_compressed);
    fprintf(f, "  \"gpu_bytes\": %zu,\n  \"nonfinite_pixels\": %zu,\n", st->gpu_bytes,
            st->nonfinite_pixels);
    fprintf(f, "  \"frames\": %u,\n  \"time_step\": %d,\n", st->frames, st->time_step);
    fprintf(f, "  \"cache_hits\": %u,\n  \"cache_misses\": %u,\n", st->cache_hits,
            st->cache_misses);
    fprintf(f, "  \"cache_loads\": %u,\n  \"frames_waited\": %u,\n  \"frames_stale\": %u,\n",
            st->cache_loads, st->frames_waited, st->frames_stale);
    fprintf(f, "  \"volume_uploads\": %u,\n  \"load_ms\": %.3f,\n  \"convert_ms\": %.3f,\n",
            st->volume_uploads, st->load_ms, st->convert_ms);
    fprintf(f, "  \"wait_ms\": %.3f,\n  \"upload_ms_total\": %.3f,\n", st->wait_ms,
            st->upload_ms_total);
    fprintf(f, "  \"frame_ms_max\": %.3f,\n", st->frame_ms_max);
    fprintf(f, "  \"volume_ms\": %.3f,\n  \"upload_ms\": %.3f,\n  \"total_ms\": %.3f\n}\n",
            st->volume_ms, st->upload_ms, st->total_ms);
    fclose(f);
    bool ok = file_write_atomic(path, buf, len);
    free(buf);
    return ok;
}
