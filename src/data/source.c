#include "data/source.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "data/cf.h"
#include "data/cm1.h"
#include "data/extfile.h"
#include "data/geo.h"
#include "data/nest.h"

struct data_source {
    struct data_source_desc desc;
    struct wrf *wrf;        /* the outermost domain's where there are nests (owned by nest) */
    struct nest_set *nest;  /* NULL unless the files are several domains (data/nest.h) */
    struct extfile *ext;
    struct hgrid *hg;
    int isabel_steps;
};

/* Missing species read as zero: said once, at open. */
static void absent_species_note(const struct hgrid *h)
{
    const struct hgrid_meta *m = hgrid_get_meta(h);
    char list[128] = "";
    for (int f = 0; f < SPECIES_COUNT; f++)
        if (m->field[f].varid < 0)
            snprintf(list + strlen(list), sizeof(list) - strlen(list), "%s%s",
                     list[0] ? ", " : "", species_name((enum species)f));
    if (list[0])
        log_info("%s: no %s in the file: read as zero", hgrid_step_path(h, 0), list);
}

struct data_source *data_source_open(const struct data_source_desc *d)
{
    if (d->file_count < 1 || !d->files || !d->files[0]) {
        log_error("no data files given (data.files)");
        return NULL;
    }
    struct data_source *s = calloc(1, sizeof(*s));
    if (!s) {
        log_error("out of memory");
        return NULL;
    }
    s->desc = *d;
    switch (d->format) {
    case DATA_SOURCE_WRF: {
        bool single;
        s->nest = nest_open(d->files, d->file_count, d->wrf.memory_mb, &single);
        if (!s->nest && !single)
            goto error;
        s->wrf = s->nest ? nest_outer(s->nest) : wrf_open(d->files, d->file_count,
                                                           d->wrf.memory_mb);
        if (!s->wrf)
            goto error;
        /* The selection is checked now rather than at the first step. */
        struct nest_layout l;
        if (s->nest && !nest_layout(s->nest, &d->wrf, &l)) {
            nest_close(s->nest);
            goto error;
        }
        break;
    }
    case DATA_SOURCE_ISABEL:
        s->desc.isabel.dir = d->files[0];
        s->isabel_steps = isabel_step_count(&s->desc.isabel);
        if (s->isabel_steps == 0)
            goto error;
        break;
    case DATA_SOURCE_CM1:
    case DATA_SOURCE_CF:
        s->hg = (d->format == DATA_SOURCE_CM1 ? cm1_open : cf_open)(d->files, d->file_count,
                                                                    d->wrf.memory_mb);
        if (!s->hg)
            goto error;
        absent_species_note(s->hg);
        break;
    case DATA_SOURCE_EXTINCTION:
        if (d->file_count > 1)
            log_warn("%s: an extinction file holds the whole series: the other %d files are "
                     "ignored",
                     d->files[0], d->file_count - 1);
        s->ext = extfile_open(d->files[0], d->wrf.memory_mb);
        if (!s->ext)
            goto error;
        break;
    }
    return s;

error:
    free(s);
    return NULL;
}

void data_source_close(struct data_source *s)
{
    if (!s)
        return;
    if (s->nest)
        nest_close(s->nest);
    else
        wrf_close(s->wrf);
    extfile_close(s->ext);
    hgrid_close(s->hg);
    free(s);
}

int data_source_step_count(const struct data_source *s)
{
    if (s->wrf)
        return wrf_step_count(s->wrf);
    if (s->ext)
        return extfile_step_count(s->ext);
    if (s->hg)
        return hgrid_step_count(s->hg);
    return s->isabel_steps;
}

const char *data_source_step_date(const struct data_source *s, int step)
{
    if (s->wrf)
        return wrf_step_date(s->wrf, step);
    if (s->ext)
        return extfile_step_date(s->ext, step);
    if (s->hg)
        return hgrid_step_date(s->hg, step);
    return "";
}

struct wrf *data_source_wrf(struct data_source *s)
{
    return s->wrf;
}

enum wrf_point_result data_source_read_point(struct data_source *s, int step, const double p[3],
                                             struct wrf_point *out)
{
    if (s->nest)
        return nest_read_point(s->nest, step, &s->desc.wrf, p, out);
    if (s->wrf)
        return wrf_read_point(s->wrf, step, &s->desc.wrf, p, out);
    memset(out, 0, sizeof(*out));
    log_error("%s: only WRF output is read at a point", s->desc.files[0]);
    return WRF_POINT_ERROR;
}

struct nest_set *data_source_nests(struct data_source *s)
{
    return s->nest;
}

struct hgrid *data_source_hgrid(struct data_source *s)
{
    return s->hg;
}

bool data_source_geo(struct data_source *s, struct geo_map *out)
{
    memset(out, 0, sizeof(*out));
    if (s->wrf) {
        const struct wrf_meta *m = wrf_get_meta(s->wrf);
        return m->xlat && m->xlong &&
               geo_map_init_grid(out, m->xlat, m->xlong, m->nx, m->ny, m->dx, m->dy);
    }
    if (s->desc.format == DATA_SOURCE_ISABEL)
        return isabel_geo(&s->desc.isabel, out);
    float *lat, *lon;
    if (s->hg && hgrid_latlon(s->hg, &lat, &lon)) {
        const struct hgrid_meta *m = hgrid_get_meta(s->hg);
        bool ok = m->nx >= 2 && m->ny >= 2 &&
                  geo_map_init_grid(out, lat, lon, m->nx, m->ny, m->dx, m->dy);
        free(lat);
        free(lon);
        return ok;
    }
    return false;
}

/* A WRF step that holds no condensate and some fill values is most likely a step the model
 * never wrote (a run that stopped, a file cut and padded): said, naming the step, since it
 * renders as clear sky.  (A variable all of whose values are fill is refused by the reader.) */
static void warn_empty_step(const struct data_source *s, int step, const struct wrf_stats *st)
{
    size_t fill = 0, count = 0;
    double top = 0.0;
    for (int v = 0; v < SPECIES_COUNT; v++) {
        const struct wrf_var_stats *vs = &st->var[v];
        if (!vs->read)
            continue;
        fill += vs->fill;
        count += vs->count;
        top = fmax(top, vs->max);
    }
    if (fill == 0 || top > 0.0)
        return;
    log_warn("%s: time step %d (%s): no condensate: of the species' %zu values %zu are fill "
             "values and the rest zero (a step the model did not write?): it shows clear sky",
             wrf_step_path(s->wrf, step), step, wrf_step_date(s->wrf, step), count, fill);
}

/* A step's mass ratios and air density, with vapour, temperature and wind where asked for
 * (or where the source's description asks for them). */
static bool load_fields(struct data_source *s, int step, bool qvapor, bool temperature,
                        bool wind, bool components, bool levels, struct field_volume *out)
{
    /* The description's components come with the wind when it is read; asked for here, they
     * bring the wind. */
    components = components || (s->desc.wind_components && (wind || s->desc.wrf.wind));
    if (s->wrf) {
        struct wrf_desc d = s->desc.wrf;
        d.qvapor = d.qvapor || qvapor;
        d.temperature = d.temperature || temperature;
        d.wind = d.wind || wind;
        d.wind_components = d.wind_components || components;
        d.level_heights = d.level_heights || levels;
        struct wrf_stats st;
        if (s->nest ? !nest_read_step(s->nest, step, &d, out, &st)
                    : !wrf_read_step(s->wrf, step, &d, out, &st))
            return false;
        warn_empty_step(s, step, &st);
        return true;
    }
    if (s->hg) {
        struct hgrid_desc hd = {.memory_mb = s->desc.wrf.memory_mb,
                                .qvapor = qvapor || s->desc.wrf.qvapor,
                                .temperature = temperature || s->desc.wrf.temperature,
                                .wind = wind || components || s->desc.wrf.wind,
                                .wind_components = components,
                                .pressure = s->desc.pressure,
                                .no_density = s->desc.wrf.no_density,
                                .native_levels = s->desc.wrf.native_levels};
        return hgrid_read_step(s->hg, step, &hd, out, NULL);
    }
    if (s->ext) {
        memset(out, 0, sizeof(*out));
        log_error("%s: an extinction file has no mass ratios", s->desc.files[0]);
        return false;
    }
    if (step < 0 || step >= s->isabel_steps) {
        memset(out, 0, sizeof(*out));
        log_error("%s: time step %d out of range (0 to %d)", s->desc.files[0], step,
                  s->isabel_steps - 1);
        return false;
    }
    struct isabel_desc id = s->desc.isabel;
    id.qvapor = id.qvapor || qvapor || s->desc.wrf.qvapor;
    id.temperature = id.temperature || temperature;
    id.wind = id.wind || wind || components;
    id.wind_components = id.wind_components || components;
    return isabel_read_step(&id, step, out, NULL);
}

bool data_source_load_fields(struct data_source *s, int step, struct field_volume *out)
{
    return load_fields(s, step, false, false, false, false, false, out);
}

bool data_source_load_fields_extra(struct data_source *s, int step, bool temperature, bool wind,
                                   struct field_volume *out)
{
    return load_fields(s, step, false, temperature, wind, false, false, out);
}

bool data_source_load_fields_want(struct data_source *s, int step,
                                  const struct data_fields_want *want, struct field_volume *out)
{
    return load_fields(s, step, want->qvapor, want->temperature, want->wind,
                       want->wind_components, want->level_heights, out);
}

bool data_source_can_load_ext(const struct data_source *s)
{
    return s->wrf && !s->nest;
}

bool data_source_load_ext(struct data_source *s, int step, const struct optics_params *optics,
                          const struct species_select *sel, struct transfer_histogram *vapour,
                          struct ext_volume *out)
{
    assert(data_source_can_load_ext(s));
    /* Straight to extinction, slab by slab: the step's fields are never held whole, and what
     * extinction does not use is not read. */
    struct wrf_stats st;
    bool ok = wrf_read_step_ext(s->wrf, step, &s->desc.wrf, optics, sel, vapour, out, &st);
    if (ok)
        warn_empty_step(s, step, &st);
    return ok;
}

bool data_source_load(struct data_source *s, int step, struct ext_volume *out, double *load_ms,
                      double *convert_ms)
{
    double t0 = time_now_ms();
    if (convert_ms)
        *convert_ms = 0.0;
    double k = s->desc.height_scale > 0.0 ? s->desc.height_scale : 1.0;
    if (s->ext) {
        bool ok = extfile_read_step(s->ext, step, out, NULL);
        if (load_ms)
            *load_ms = time_now_ms() - t0;
        if (ok) {
            double t1 = time_now_ms();
            detail_apply_ext(&s->desc.detail, out);
            ext_volume_stretch_height(out, k);
            if (convert_ms)
                *convert_ms = time_now_ms() - t1;
        }
        return ok;
    }
    if (data_source_can_load_ext(s) && !s->desc.detail.on) {
        bool ok = data_source_load_ext(s, step, &s->desc.optics, &s->desc.select, NULL, out);
        double t1 = time_now_ms();
        if (ok)
            ext_volume_stretch_height(out, k);
        if (load_ms)
            *load_ms = t1 - t0;
        if (convert_ms)
            *convert_ms = time_now_ms() - t1;
        return ok;
    }
    struct field_volume fv;
    bool ok = data_source_load_fields(s, step, &fv);
    double t1 = time_now_ms();
    if (load_ms)
        *load_ms = t1 - t0;
    if (!ok) {
        memset(out, 0, sizeof(*out));
        return false;
    }
    detail_apply_fields(&s->desc.detail, &fv);
    ok = ext_volume_from_fields(&fv, &s->desc.optics, &s->desc.select, out);
    field_volume_finish(&fv);
    if (ok)
        ext_volume_stretch_height(out, k);
    if (convert_ms)
        *convert_ms = time_now_ms() - t1;
    return ok;
}

bool data_file_is_netcdf(const char *path)
{
    unsigned char head[8] = {0};
    FILE *f = fopen(path, "rb");
    if (!f)
        return false;
    size_t n = fread(head, 1, sizeof(head), f);
    fclose(f);
    static const unsigned char hdf5[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    return (n >= 4 && head[0] == 'C' && head[1] == 'D' && head[2] == 'F' &&
            (head[3] == 1 || head[3] == 2 || head[3] == 5)) ||
           (n == 8 && memcmp(head, hdf5, 8) == 0);
}

bool data_source_grid(const struct data_source *s, struct grid3 *out)
{
    switch (s->desc.format) {
    case DATA_SOURCE_WRF:
        if (s->nest) {
            struct nest_layout l;
            if (!nest_layout(s->nest, &s->desc.wrf, &l))
                return false;
            *out = l.grid;
        } else if (!wrf_grid(s->wrf, &s->desc.wrf, out)) {
            return false;
        }
        break;
    case DATA_SOURCE_ISABEL:
        isabel_grid(&s->desc.isabel, out);
        break;
    case DATA_SOURCE_EXTINCTION:
        *out = *extfile_grid(s->ext);
        break;
    case DATA_SOURCE_CM1:
    case DATA_SOURCE_CF:
        hgrid_grid(s->hg, s->desc.wrf.native_levels, out);
        break;
    }
    double k = s->desc.height_scale > 0.0 ? s->desc.height_scale : 1.0;
    out->origin[2] *= k; /* as ext_volume_stretch_height */
    out->spacing[2] *= k;
    for (int l = 0; l < out->z_levels; l++)
        out->z_centre[l] *= k;
    return true;
}
