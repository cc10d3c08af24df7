/* Time playback: the cursor (playback) and the player over the time series cache. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "session/lightmaps.h"
#include "session/player.h"
#include "session/scene.h"
#include "common/log.h"
#include "data/derived.h"
#include "data/detail.h"
#include "data/series.h"
#include "data/geo.h"
#include "data/source.h"
#include "data/synth.h"
#include "data/wrf.h"
#include "data/wrf_write.h"

#define DATE_LEN 64

void playback_init(struct playback *pb, int count, int step, double speed, bool loop)
{
    memset(pb, 0, sizeof(*pb));
    pb->count = count > 0 ? count : 1;
    pb->step = step < 0 ? 0 : step >= pb->count ? pb->count - 1 : step;
    pb->speed = speed;
    pb->loop = loop;
}

bool playback_tick(struct playback *pb, double dt, bool (*ready)(void *user, int step),
                       void *user)
{
    if (!pb->playing || pb->count < 2 || !(dt > 0.0))
        return false;
    pb->acc += dt * pb->speed;
    bool changed = false;
    /* The epsilon keeps exact frame times (10 frames of 0.1 s) from falling a hair short. */
    while (pb->acc >= 1.0 - 1e-9) {
        int next = pb->step + 1;
        if (next >= pb->count) {
            if (!pb->loop) {
                pb->playing = false; /* the end: stop there */
                pb->acc = 0.0;
                break;
            }
            next = 0;
        }
        if (ready && !ready(user, next)) {
            pb->stalls++;
            pb->acc = 1.0; /* wait at the step boundary, do not build up a backlog */
            break;
        }
        pb->step = next;
        pb->acc -= 1.0;
        changed = true;
    }
    return changed;
}

/* ---- the player -------------------------------------------------------------------------- */

enum player_kind { PLAYER_STORM, PLAYER_FIELDS, PLAYER_EXTINCTION, PLAYER_TEST_SCENE };

/* Everything the series' thread reads to make a step, copied from the config when the player
 * is made and never written again: the loader sees neither the config nor the session. */
struct player_load {
    enum player_kind kind;
    struct synth_desc synth;      /* the storm and the test scenes */
    struct optics_params optics;
    struct species_select select; /* the config's (test scenes; the look has its own) */
    struct detail_desc detail;
    double height_k;
    char files[CONFIG_MAX_FILES][CONFIG_PATH_MAX];
    const char *file_ptrs[CONFIG_MAX_FILES];
    struct data_source_desc source; /* its files point into FILES above */
};

struct player {
    struct player_load ld; /* immutable after player_create */
    struct series *series; /* NULL for a still picture (player_desc.still) */
    int steps;
    char (*dates)[DATE_LEN];
    struct data_source *src; /* read by the series' thread only once the series runs */
    struct ext_volume first; /* the first step, made by player_create until taken */
    int first_step;          /* its step, or -1 once given back (player_keep_first) */
    uint64_t first_series_gen; /* the series' generation when it started */
    struct ext_volume still; /* without a series: the last step made on the caller's thread */

    pthread_mutex_t lock; /* guards look, look_gen, present */
    struct look look;
    uint64_t look_gen;
    bool present[SPECIES_COUNT];

    int shown;
    uint64_t shown_gen;
    int next_shown; /* effects.temporal: the step in the renderer's next volume, -1 none */
    uint64_t next_gen;
    bool field_warned[TRANSFER_FIELD_COUNT]; /* the series' thread only */
    bool histogram; /* player_desc.histogram */
};

void look_from_config(const struct config *cfg, struct look *look)
{
    memset(look, 0, sizeof(*look));
    for (int f = 0; f < SPECIES_COUNT; f++) {
        look->select.enabled[f] = cfg->optics.enabled[f];
        look->select.scale[f] = cfg->optics.scale[f];
        for (int c = 0; c < 3; c++)
            look->tint.rgb[f][c] = (float)cfg->look.tint[f][c];
    }
    const struct config_look *cl = &cfg->look;
    if (cl->has_layers) {
        look->layer_count = cl->layer_count;
        for (int i = 0; i < cl->layer_count; i++) {
            const struct config_layer *c = &cl->layers[i];
            struct transfer_layer *l = &look->layers[i];
            if (c->has_transfer)
                l->tf = c->transfer;
            else
                transfer_defaults(&l->tf, (enum transfer_field)c->field);
            l->enabled = c->enabled;
            l->mode = c->mode;
            l->opacity = c->opacity;
        }
    }
    look->slice_count = cl->slice_count;
    for (int i = 0; i < cl->slice_count; i++) {
        const struct config_slice *c = &cl->slices[i];
        struct transfer_slice *sl = &look->slices[i];
        if (c->has_transfer)
            sl->tf = c->transfer;
        else
            transfer_defaults(&sl->tf, (enum transfer_field)c->field);
        sl->enabled = c->enabled;
        sl->opacity = c->opacity;
        sl->contour_every = c->contour_every;
        sl->level = c->level;
        sl->contour_count = c->contour_count;
        for (int k = 0; k < c->contour_count; k++)
            sl->contour_values[k] = c->contours[k];
        double n[3] = {0.0, 0.0, 0.0}, len = 0.0;
        if (c->axis < 3) {
            n[c->axis] = 1.0;
            for (int a = 0; a < 3; a++)
                sl->point[a] = a == c->axis ? c->position_km * 1000.0 : 0.0;
        } else {
            for (int a = 0; a < 3; a++) {
                n[a] = c->normal[a];
                sl->point[a] = c->point_km[a] * 1000.0;
            }
        }
        for (int a = 0; a < 3; a++)
            len += n[a] * n[a];
        len = sqrt(len);
        for (int a = 0; a < 3; a++)
            sl->normal[a] = len > 0.0 ? n[a] / len : (a == 2);
    }
    if (!cl->has_layers && cl->has_transfer) {
        /* An older file's one function: the first layer, emitting, fully opaque. */
        look->layer_count = 1;
        look->layers[0] = (struct transfer_layer){
            .enabled = cl->show_transfer, .mode = TRANSFER_LAYER_EMIT, .opacity = 1.0,
            .tf = cl->transfer};
    }
}

int look_edited_layer(const struct look *look)
{
    return look->edited >= 0 && look->edited < look->layer_count ? look->edited : 0;
}

void look_edited_transfer(const struct look *look, struct transfer_function *out)
{
    if (look->layer_count > 0)
        *out = look->layers[look_edited_layer(look)].tf;
    else
        transfer_defaults(out, TRANSFER_FIELD_QVAPOR);
}

/* The histogram of TF's field over its range on FV (owned by the caller), or NULL when out of
 * memory. */
static struct transfer_histogram *histogram_of(const struct field_volume *fv,
                                               const struct transfer_function *tf)
{
    struct transfer_histogram *h = malloc(sizeof(*h));
    float *s = malloc(grid3_count(&fv->grid) * sizeof(float));
    if (!h || !s) {
        free(h);
        free(s);
        return NULL;
    }
    transfer_histogram_init(h, tf->field, tf->lo, tf->hi);
    derived_field(fv, tf->field, s);
    for (size_t i = 0; i < grid3_count(&fv->grid); i++)
        transfer_histogram_add(h, s[i]);
    free(s);
    return h;
}

/* Mass ratios -> extinction with the look (on the series' thread). */
static bool convert(struct player *p, struct field_volume *fv, const struct look *look,
                    struct ext_volume *out)
{
    const struct player_load *ld = &p->ld;
    detail_apply_fields(&ld->detail, fv);
    bool ok = ext_volume_from_fields(fv, &ld->optics, &look->select, out) &&
              ext_volume_tint_from_fields(fv, &ld->optics, &look->select, &look->tint, out);
    /* Every layer's field, on or off (turning one on shows at once); classified on the GPU. */
    for (int i = 0; ok && i < look->layer_count; i++) {
        enum transfer_field f = look->layers[i].tf.field;
        if (!derived_field_available(fv, f) && !p->field_warned[f]) {
            log_warn("layer %d: %s is unavailable (the data lacks what it is made from): a "
                     "stand-in is shown (docs/analysis.md)",
                     i + 1, transfer_field_label(f));
            p->field_warned[f] = true;
        }
        out->layer[i] = malloc(grid3_count(&fv->grid) * sizeof(float));
        if (!out->layer[i]) {
            log_error("out of memory for layer %d's field", i + 1);
            ok = false;
            break;
        }
        derived_field(fv, f, out->layer[i]);
        out->layer_field[i] = f;
    }
    for (int i = 0; ok && i < look->slice_count; i++) {
        enum transfer_field f = look->slices[i].tf.field;
        out->slice[i] = malloc(grid3_count(&fv->grid) * sizeof(float));
        if (!out->slice[i]) {
            log_error("out of memory for slice %d's field", i + 1);
            ok = false;
            break;
        }
        derived_field(fv, f, out->slice[i]);
        out->slice_field[i] = f;
        int level = look->slices[i].level;
        if (level > 0) {
            /* The surface of mass level LEVEL: the reader's heights per column (WRF), else the
             * grid's own level (height-level data), the top one for a level above them. */
            const struct grid3 *g = &fv->grid;
            size_t plane = (size_t)g->n[0] * (size_t)g->n[1];
            out->slice_surface[i] = malloc(plane * sizeof(float));
            if (!out->slice_surface[i]) {
                log_error("out of memory for slice %d's surface", i + 1);
                ok = false;
                break;
            }
            if (fv->level_z && fv->level_count > 0) {
                int k = level <= fv->level_count ? level - 1 : fv->level_count - 1;
                memcpy(out->slice_surface[i], fv->level_z + (size_t)k * plane,
                       plane * sizeof(float));
            } else {
                int k = level <= g->n[2] ? level - 1 : g->n[2] - 1;
                for (size_t c = 0; c < plane; c++)
                    out->slice_surface[i][c] = (float)grid3_centre_z(g, k);
            }
        }
    }
    if (ok && ld->height_k > 0.0)
        ext_volume_stretch_height(out, ld->height_k);
    if (ok && p->histogram) {
        struct transfer_function edited;
        look_edited_transfer(look, &edited);
        out->histogram = histogram_of(fv, &edited); /* NULL: out of memory, no bars */
    }
    return ok;
}

static bool load(void *user, int step, struct ext_volume *out, double *load_ms,
                 double *convert_ms)
{
    struct player *p = user;
    const struct player_load *ld = &p->ld;
    struct look *look = malloc(sizeof(*look));
    if (!look) {
        log_error("out of memory");
        return false;
    }
    pthread_mutex_lock(&p->lock);
    *look = p->look;
    pthread_mutex_unlock(&p->lock);
    double t0 = time_now_ms();
    bool ok = false;
    struct field_volume fv = {0};
    switch (ld->kind) {
    case PLAYER_TEST_SCENE:
        ok = scene_build_synth(&ld->synth, &ld->optics, &ld->select, &ld->detail, ld->height_k,
                               out);
        *load_ms += time_now_ms() - t0;
        free(look);
        return ok;
    case PLAYER_EXTINCTION:
        ok = data_source_load(p->src, step, out, load_ms, convert_ms);
        free(look);
        return ok;
    case PLAYER_STORM:
        ok = synth_storm_fields(&ld->synth, &fv);
        break;
    case PLAYER_FIELDS: {
        struct transfer_function edited;
        look_edited_transfer(look, &edited);
        if ((!p->histogram || edited.field == TRANSFER_FIELD_QVAPOR) && look->layer_count == 0 &&
            look->slice_count == 0 && species_tint_is_white(&look->tint) && !ld->detail.on &&
            data_source_can_load_ext(p->src)) {
            /* Nothing but extinction to make (and the water vapour's histogram for the
             * transfer editor): straight to it, the fields never held whole. */
            const struct wrf_meta *m = wrf_get_meta(data_source_wrf(p->src));
            pthread_mutex_lock(&p->lock);
            for (int f = 0; f < SPECIES_COUNT; f++)
                p->present[f] = m->has_species[f];
            pthread_mutex_unlock(&p->lock);
            struct transfer_histogram *h = p->histogram ? malloc(sizeof(*h)) : NULL;
            if (h) /* else out of memory: no bars */
                transfer_histogram_init(h, edited.field, edited.lo, edited.hi);
            ok = data_source_load_ext(p->src, step, &ld->optics, &look->select, h, out);
            if (ok) {
                out->histogram = h;
                h = NULL;
                if (ld->height_k > 0.0)
                    ext_volume_stretch_height(out, ld->height_k);
            }
            free(h);
            *load_ms += time_now_ms() - t0;
            free(look);
            return ok;
        }
        /* The fields the layers and slices show, and the transfer editor's (read while the
         * menu is there: its histogram shows it). */
        bool qvapor = false, temperature = false, wind = false, components = false;
        for (int i = p->histogram ? -1 : 0; i < look->layer_count + look->slice_count; i++) {
            const struct transfer_function *tf =
                i < 0                   ? &edited
                : i < look->layer_count ? &look->layers[i].tf
                                        : &look->slices[i - look->layer_count].tf;
            enum transfer_field f = tf->field;
            qvapor |= f == TRANSFER_FIELD_QVAPOR;
            temperature |= f == TRANSFER_FIELD_TEMPERATURE || f == TRANSFER_FIELD_THETA ||
                           f == TRANSFER_FIELD_RH;
            wind |= f == TRANSFER_FIELD_WIND;
            components |= f == TRANSFER_FIELD_W || f == TRANSFER_FIELD_VORTICITY;
        }
        bool levels = false;
        for (int i = 0; i < look->slice_count; i++)
            levels |= look->slices[i].level > 0;
        ok = data_source_load_fields_want(
            p->src, step,
            &(struct data_fields_want){.qvapor = qvapor, .temperature = temperature, .wind = wind,
                                       .wind_components = components,
                                       .level_heights = levels},
            &fv);
        break;
    }
    }
    double t1 = time_now_ms();
    *load_ms += t1 - t0;
    if (ok) {
        pthread_mutex_lock(&p->lock);
        for (int f = 0; f < SPECIES_COUNT; f++)
            p->present[f] = fv.q[f] != NULL;
        pthread_mutex_unlock(&p->lock);
        ok = convert(p, &fv, look, out);
    }
    *convert_ms += time_now_ms() - t1;
    field_volume_finish(&fv);
    free(look);
    return ok;
}

/* Copies what the loader needs out of CFG. */
static bool load_desc(const struct config *cfg, struct player_load *ld)
{
    if (cfg->scene.kind == SCENE_DATA)
        ld->kind = cfg->data.format == DATA_EXTINCTION ? PLAYER_EXTINCTION : PLAYER_FIELDS;
    else
        ld->kind = cfg->scene.kind == SCENE_STORM ? PLAYER_STORM : PLAYER_TEST_SCENE;
    if (ld->kind == PLAYER_STORM || ld->kind == PLAYER_TEST_SCENE) {
        if (!scene_synth_desc(cfg, &ld->synth))
            return false;
    }
    ld->optics = cfg->optics.params;
    scene_species_select(cfg, &ld->select);
    scene_detail_desc(cfg, &ld->detail);
    ld->height_k = cfg->scene.height_exaggeration;
    const char *ptrs[CONFIG_MAX_FILES];
    scene_source_desc(cfg, ptrs, &ld->source);
    for (int i = 0; i < ld->source.file_count; i++) {
        snprintf(ld->files[i], sizeof(ld->files[i]), "%s", ptrs[i]);
        ld->file_ptrs[i] = ld->files[i];
    }
    ld->source.files = ld->file_ptrs;
    return true;
}

/* The first step on the caller's thread, the way a still render makes it (scene_build_volume),
 * before the series' thread may touch the source. */
static bool make_first(struct player *p, int step)
{
    const struct player_load *ld = &p->ld;
    double load_ms = 0.0, convert_ms = 0.0;
    if (ld->kind == PLAYER_TEST_SCENE)
        return scene_build_synth(&ld->synth, &ld->optics, &ld->select, &ld->detail,
                                 ld->height_k, &p->first);
    /* Fields through the look (the config's: its tints, its transfer function), the way the
     * series makes every later step; extinction files as they are. */
    if (ld->kind == PLAYER_STORM) {
        if (!load(p, step, &p->first, &load_ms, &convert_ms))
            return false;
        return true;
    }
    if (!(ld->kind == PLAYER_FIELDS ? load(p, step, &p->first, &load_ms, &convert_ms)
                                    : data_source_load(p->src, step, &p->first, &load_ms,
                                                       &convert_ms)))
        return false;
    const char *date = data_source_step_date(p->src, step);
    log_info("time step %d%s%s%s read in %.0f ms, converted in %.0f ms", step, date[0] ? " (" : "",
             date, date[0] ? ")" : "", load_ms, convert_ms);
    return true;
}

struct player *player_create(const struct config *cfg, const struct player_desc *d)
{
    struct player *p = calloc(1, sizeof(*p));
    if (!p) {
        log_error("out of memory");
        return NULL;
    }
    p->first_step = -1;
    p->steps = 1;
    p->next_shown = -1;
    p->histogram = d && d->histogram;
    if (pthread_mutex_init(&p->lock, NULL) != 0) {
        free(p);
        return NULL;
    }
    look_from_config(cfg, &p->look);
    for (int f = 0; f < SPECIES_COUNT; f++)
        p->present[f] = cfg->scene.kind == SCENE_STORM || cfg->scene.kind == SCENE_DATA;
    if (!load_desc(cfg, &p->ld))
        goto error;
    if (cfg->scene.kind == SCENE_DATA) {
        p->src = data_source_open(&p->ld.source);
        if (!p->src)
            goto error;
        p->steps = data_source_step_count(p->src);
        struct wrf *w = data_source_wrf(p->src);
        if (w && wrf_moves(w)) {
            const struct wrf_meta *a = wrf_step_meta(w, 0), *b = wrf_step_meta(w, p->steps - 1);
            char first[96], last[96];
            geo_format_range(first, sizeof(first), 2, a->lat_min, a->lat_max, a->lon_min,
                             a->lon_max);
            geo_format_range(last, sizeof(last), 2, b->lat_min, b->lat_max, b->lon_min, b->lon_max);
            if (a != b)
                log_info("%s: a moving nest, at %s at its first step and %s at its last: each "
                         "step is drawn on its own map",
                         wrf_step_path(w, 0), first, last);
        }
    }
    p->dates = calloc((size_t)p->steps, sizeof(*p->dates));
    if (!p->dates)
        goto error;
    for (int i = 0; i < p->steps && p->src; i++)
        snprintf(p->dates[i], DATE_LEN, "%s", data_source_step_date(p->src, i));
    p->shown = cfg->scene.kind == SCENE_DATA ? cfg->data.step : 0;
    if (p->shown < 0 || p->shown >= p->steps) {
        log_error("%s: data.step: expected a time step in [0, %d], got %d", cfg->path,
                  p->steps - 1, cfg->data.step);
        goto error;
    }
    if (!(d && d->no_first) && !make_first(p, p->shown))
        goto error;
    if (d && d->still)
        return p;
    struct series_desc sd = {
        .step_count = p->steps,
        .load = load,
        .user = p,
        .memory_mb = d && d->memory_mb > 0 ? d->memory_mb : cfg->data.cache_memory_mb,
        .prefetch = d && d->prefetch ? d->prefetch : (cfg->data.prefetch > 0 ? cfg->data.prefetch
                                                                              : -1),
        .wrap = cfg->playback.loop,
        .delay_ms = d ? d->delay_ms : 0.0,
    };
    p->series = series_create(&sd);
    if (!p->series)
        goto error;
    /* The step on screen is the first volume: prefetching starts around it, and the series
     * keeps it once the caller is done with it (player_keep_first) rather than reading it
     * again. */
    p->first_step = p->first.beta ? p->shown : -1;
    p->first_series_gen = series_generation(p->series);
    if (p->first_step >= 0)
        series_prefetch_around(p->series, p->shown);
    else
        series_try_acquire(p->series, p->shown);
    return p;

error:
    player_destroy(p);
    return NULL;
}

bool player_take_first(struct player *p, struct ext_volume *out)
{
    if (!p->first.beta)
        return false;
    *out = p->first;
    memset(&p->first, 0, sizeof(p->first));
    return true;
}

void player_keep_first(struct player *p, struct ext_volume *vol)
{
    if (p->series && p->first_step >= 0) {
        series_adopt(p->series, p->first_step, p->first_series_gen, vol);
        p->first_step = -1;
    }
    ext_volume_finish(vol);
}

const struct wrf_meta *player_wrf_meta(struct player *p)
{
    struct wrf *w = p->src ? data_source_wrf(p->src) : NULL;
    return w ? wrf_get_meta(w) : NULL;
}

const struct wrf_meta *player_wrf_step_meta(struct player *p, int step, bool *moves)
{
    struct wrf *w = p->src ? data_source_wrf(p->src) : NULL;
    *moves = w && wrf_moves(w);
    return w ? wrf_step_meta(w, step) : NULL;
}

void player_destroy(struct player *p)
{
    if (!p)
        return;
    series_destroy(p->series); /* joins the thread before the source goes */
    data_source_close(p->src);
    ext_volume_finish(&p->first);
    ext_volume_finish(&p->still);
    pthread_mutex_destroy(&p->lock);
    free(p->dates);
    free(p);
}

int player_step_count(const struct player *p)
{
    return p->steps;
}

const char *player_step_date(struct player *p, int step)
{
    return step >= 0 && step < p->steps ? p->dates[step] : "";
}

bool player_ready(struct player *p, int step)
{
    return p->series ? series_ready(p->series, step) : step == p->shown;
}

void player_want(struct player *p, int step)
{
    if (p->series)
        series_want(p->series, step);
}

bool player_has_fields(const struct player *p)
{
    return p->ld.kind == PLAYER_STORM || p->ld.kind == PLAYER_FIELDS;
}

void player_species_present(const struct player *p, bool present[SPECIES_COUNT])
{
    pthread_mutex_lock((pthread_mutex_t *)&p->lock);
    memcpy(present, p->present, sizeof(p->present));
    pthread_mutex_unlock((pthread_mutex_t *)&p->lock);
}

void player_set_look(struct player *p, const struct look *look)
{
    pthread_mutex_lock(&p->lock);
    p->look = *look;
    p->look_gen++;
    pthread_mutex_unlock(&p->lock);
    if (p->series)
        series_invalidate(p->series);
}

/* Without a series (a still picture whose look or step changed anyway): the step made now, on
 * the caller's thread, which is then the only one reading the source. */
static const struct ext_volume *make_now(struct player *p, int want)
{
    ext_volume_finish(&p->still);
    double load_ms = 0.0, convert_ms = 0.0;
    if (!load(p, want, &p->still, &load_ms, &convert_ms))
        return NULL;
    p->shown = want;
    p->shown_gen = p->look_gen;
    return &p->still;
}

const struct ext_volume *player_poll(struct player *p, int want, int *shown)
{
    const struct ext_volume *v = NULL;
    if (!p->series && (want != p->shown || p->shown_gen != p->look_gen))
        v = make_now(p, want);
    if (p->series && (want != p->shown || p->shown_gen != p->look_gen)) {
        v = series_try_acquire(p->series, want);
        if (v) {
            p->shown = want;
            p->shown_gen = p->look_gen;
        }
    }
    if (shown)
        *shown = p->shown;
    return v;
}

const struct ext_volume *player_wait(struct player *p, int want, int *shown)
{
    const struct ext_volume *v = NULL;
    if (!p->series && (want != p->shown || p->shown_gen != p->look_gen))
        v = make_now(p, want);
    if (p->series && (want != p->shown || p->shown_gen != p->look_gen)) {
        v = series_acquire(p->series, want);
        if (v) {
            p->shown = want;
            p->shown_gen = p->look_gen;
        }
    }
    if (shown)
        *shown = p->shown;
    return v;
}

const struct ext_volume *player_poll_next(struct player *p, int want, bool wait,
                                              int *held)
{
    const struct ext_volume *v = NULL;
    if (p->series && want >= 0 && (want != p->next_shown || p->next_gen != p->look_gen)) {
        v = wait ? series_acquire(p->series, want) : series_try_acquire(p->series, want);
        if (v) {
            p->next_shown = want;
            p->next_gen = p->look_gen;
        }
    }
    if (held)
        *held = p->next_shown;
    return v;
}

const struct ext_volume *player_promote_next(struct player *p)
{
    if (!p->series || p->next_shown < 0 || p->next_gen != p->look_gen)
        return NULL;
    /* The series made the next step current when it was acquired: this finds it at once. */
    const struct ext_volume *v = series_try_acquire(p->series, p->next_shown);
    if (!v)
        return NULL;
    p->shown = p->next_shown;
    p->shown_gen = p->next_gen;
    p->next_shown = -1;
    return v;
}

int player_next_step(const struct player *p)
{
    return p->next_shown >= 0 && p->next_gen == p->look_gen ? p->next_shown : -1;
}

uint64_t player_step_id(const struct player *p, bool next)
{
    if (next)
        return p->next_shown < 0 || p->next_gen != p->look_gen
                   ? 0
                   : lightmaps_step_id(p->next_shown, p->next_gen);
    return lightmaps_step_id(p->shown, p->shown_gen);
}

bool player_settled(const struct player *p, int want)
{
    return want == p->shown && p->shown_gen == p->look_gen;
}

void player_stats(struct player *p, struct session_stats *st)
{
    if (!p->series)
        return;
    struct series_stats ss;
    series_get_stats(p->series, &ss);
    st->cache_hits = ss.hits;
    st->cache_misses = ss.misses;
    st->cache_loads = ss.loads;
    st->cache_steps = ss.cached_steps;
    st->frames_waited = ss.frame_waits;
    st->load_ms = ss.load_ms;
    st->convert_ms = ss.convert_ms;
    st->wait_ms = ss.wait_ms;
}
