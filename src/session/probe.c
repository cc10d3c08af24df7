/* Values at a point of a scene: the data's own reader, the placement, and their formatting. */
#include "session/probe.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "data/source.h"
#include "data/synth.h"
#include "data/wrf.h"
#include "data/wrf_write.h"
#include "session/map.h"
#include "session/scene.h"

enum probe_kind { KIND_WRF, KIND_FIELDS, KIND_NONE };

struct probe {
    enum probe_kind kind;
    double k; /* height exaggeration */
    const char *files[CONFIG_MAX_FILES];
    struct config_data data; /* the file names the source's desc points into */
    struct data_source_desc desc;
    struct data_source *src;  /* WRF, CM1, CF, Isabel */
    bool storm;               /* the procedural storm: its fields made once */
    struct synth_desc synth;
    struct field_volume fields; /* KIND_FIELDS: the step FIELDS_STEP, or none yet */
    int fields_step;
    struct geo_map geo;
    int geo_step; /* the step GEO places: a moving domain's own (geo_at) */
};

void probe_settings_from_config(const struct config *cfg, struct probe_settings *out)
{
    memset(out, 0, sizeof(*out));
    out->on = cfg->probe.on;
    out->mode = cfg->probe.mode;
    out->threshold = cfg->probe.threshold;
    out->distance_m = cfg->probe.distance_km * 1000.0;
}

const char *probe_mode_name(int mode)
{
    return mode == PROBE_AT_DISTANCE ? "at a distance" : "first visible";
}

struct probe *probe_create(const struct config *cfg)
{
    struct probe *p = calloc(1, sizeof(*p));
    if (!p) {
        log_error("probe: out of memory");
        return NULL;
    }
    p->k = cfg->scene.height_exaggeration > 0.0 ? cfg->scene.height_exaggeration : 1.0;
    p->fields_step = -1;
    p->kind = KIND_NONE;
    const struct wrf_meta *meta = NULL;
    if (cfg->scene.kind == SCENE_STORM) {
        p->kind = KIND_FIELDS;
        p->storm = true;
        if (!scene_synth_desc(cfg, &p->synth))
            goto error;
    } else if (cfg->scene.kind == SCENE_DATA && cfg->data.format != DATA_EXTINCTION) {
        /* The desc points into the probe's own copy of the file names. */
        p->data = cfg->data;
        scene_source_desc(cfg, p->files, &p->desc);
        for (int i = 0; i < p->desc.file_count; i++)
            p->files[i] = p->data.files[i];
        p->desc.files = p->files;
        p->desc.detail.on = false; /* the model's values, not the procedural detail */
        p->desc.wrf.qvapor = true; /* vapour where the files have it */
        p->desc.wind_components = true; /* the wind's direction (CM1, CF, Isabel) */
        p->desc.pressure = true;        /* the file's pressure (CM1, CF) */
        p->src = data_source_open(&p->desc);
        if (!p->src)
            goto error;
        struct wrf *w = data_source_wrf(p->src);
        p->kind = w ? KIND_WRF : KIND_FIELDS;
        meta = w ? wrf_get_meta(w) : NULL;
    }
    if (p->src && !meta)
        scene_geo_init_source(cfg, p->src, &p->geo);
    else
        scene_geo_init(cfg, meta, &p->geo);
    return p;

error:
    probe_destroy(p);
    return NULL;
}

void probe_destroy(struct probe *p)
{
    if (!p)
        return;
    data_source_close(p->src);
    field_volume_finish(&p->fields);
    geo_map_finish(&p->geo);
    free(p);
}

/* The placement at STEP: for a domain that moves, that step's (made again when the step
 * changes), else the one made with the probe. */
static const struct geo_map *geo_at(struct probe *p, int step)
{
    struct wrf *w = p->src ? data_source_wrf(p->src) : NULL;
    if (!w || !wrf_moves(w) || step == p->geo_step)
        return &p->geo;
    const struct wrf_meta *m = wrf_step_meta(w, step);
    struct geo_map g = {0};
    if (m->xlat && m->xlong &&
        geo_map_init_grid(&g, m->xlat, m->xlong, m->nx, m->ny, m->dx, m->dy)) {
        g.offset[0] = p->geo.offset[0];
        g.offset[1] = p->geo.offset[1];
        geo_map_finish(&p->geo);
        p->geo = g;
        p->geo_step = step;
    }
    return &p->geo;
}

int probe_step_count(const struct probe *p)
{
    return p->src ? data_source_step_count(p->src) : 1;
}

const struct geo_map *probe_geo(const struct probe *p)
{
    return &p->geo;
}

/* "outside the data (its columns lie at ...)" for a WRF scene (at STEP), else about the frame
 * point. */
static void outside_text(const struct probe *p, int step, const double world[2], char *why,
                         size_t size)
{
    const struct wrf *w = p->src ? data_source_wrf(p->src) : NULL;
    const struct wrf_meta *m = w ? wrf_step_meta(w, step) : NULL;
    char range[96];
    if (m && isfinite(m->lat_min)) {
        geo_format_range(range, sizeof(range), 2, m->lat_min, m->lat_max, m->lon_min, m->lon_max);
        snprintf(why, size, "outside the data (its columns lie at %s%s)", range,
                 wrf_moves(w) ? " at this step" : "");
    } else if (world)
        snprintf(why, size, "outside the data (x %.1f km, y %.1f km)", world[0] / 1000.0,
                 world[1] / 1000.0);
    else
        snprintf(why, size, "outside the data");
}

bool probe_world_at(struct probe *p, int step, double lat, double lon, double height_m,
                    double world[3], char *why, size_t why_size)
{
    const struct geo_map *geo = geo_at(p, step);
    if (geo->kind == GEO_NONE) {
        snprintf(why, why_size,
                 "the scene has no latitude and longitude (no XLAT/XLONG; map.use_origin and "
                 "map.origin place other data)");
        return false;
    }
    if (!geo_map_to_frame(geo, lat, lon, &world[0], &world[1])) {
        outside_text(p, step, NULL, why, why_size); /* too far out for the grid's inverse */
        return false;
    }
    world[2] = height_m * p->k;
    return true;
}

static void outside(struct probe_values *out, const char *fmt, double a, double b)
{
    out->valid = false;
    snprintf(out->why, sizeof(out->why), fmt, a, b);
}

bool probe_read(struct probe *p, int step, const double world[3], struct probe_values *out)
{
    memset(out, 0, sizeof(*out));
    out->step = step;
    memcpy(out->world, world, sizeof(out->world));
    out->data[0] = world[0];
    out->data[1] = world[1];
    out->data[2] = world[2] / p->k;
    const struct geo_map *geo = geo_at(p, step);
    out->placed =
        geo->kind != GEO_NONE && geo_map_to_latlon(geo, world[0], world[1], &out->lat, &out->lon);
    out->valid = true;
    if (p->kind == KIND_NONE)
        return true; /* an extinction file or a test scene: extinction and light only */
    if (p->kind == KIND_WRF) {
        struct wrf_point wp;
        switch (data_source_read_point(p->src, step, out->data, &wp)) {
        case WRF_POINT_OK:
            out->fields = true;
            probe_sample_from_wrf(&wp, out->data[2], &out->s);
            return true;
        case WRF_POINT_OUTSIDE:
            outside_text(p, step, world, out->why, sizeof(out->why));
            out->valid = false;
            return true;
        case WRF_POINT_BELOW:
            outside(out, "below the ground (%.0f m above sea level there; the point: %.0f m)",
                    wp.ground_m, out->data[2]);
            return true;
        case WRF_POINT_ABOVE: {
            /* The volume's box reaches the highest model top: between this column's top and
             * the box's the volume holds the column's top level (its voxels clamp to it), so a
             * point seen there (the first visible point along a ray) reads that level. */
            struct grid3 g;
            double at[3] = {out->data[0], out->data[1], wp.top_m - 1e-3};
            if (data_source_grid(p->src, &g) &&
                out->data[2] <= grid3_voxel_to_z(&g, (double)g.n[2]) + 0.01 &&
                data_source_read_point(p->src, step, at, &wp) == WRF_POINT_OK) {
                out->fields = true;
                out->at_top = true;
                out->top_m = at[2];
                probe_sample_from_wrf(&wp, at[2], &out->s);
                return true;
            }
            outside(out, "above the top of the data (%.0f m above sea level there; the point: "
                    "%.0f m)", wp.top_m, out->data[2]);
            return true;
        }
        case WRF_POINT_ERROR:
            return false;
        }
    }
    if (p->fields_step != (p->storm ? 0 : step)) {
        field_volume_finish(&p->fields);
        p->fields_step = -1;
        bool ok = p->storm ? synth_storm_fields(&p->synth, &p->fields)
                           : data_source_load_fields_extra(p->src, step, true, true,
                                                           &p->fields);
        if (!ok)
            return false;
        p->fields_step = p->storm ? 0 : step;
    }
    if (!probe_sample_fields(&p->fields, out->data, &out->s)) {
        outside_text(p, step, world, out->why, sizeof(out->why));
        out->valid = false;
        return true;
    }
    out->fields = true;
    return true;
}

/* ---- formatting ---------------------------------------------------------------------- */

static struct readout_row *row(struct readout_model *m, const char *label, bool dim)
{
    if (m->count >= READOUT_ROWS)
        return NULL;
    struct readout_row *r = &m->rows[m->count++];
    snprintf(r->label, sizeof(r->label), "%s", label);
    r->value[0] = '\0';
    r->dim = dim;
    return r;
}

#define ROW(m, label, dim, ...)                                                                \
    do {                                                                                       \
        struct readout_row *r_ = row(m, label, dim);                                           \
        if (r_)                                                                                \
            snprintf(r_->value, sizeof(r_->value), __VA_ARGS__);                               \
    } while (0)

static void latlon_text(double lat, double lon, char *buf, size_t size)
{
    double lo = fmod(lon + 540.0, 360.0) - 180.0;
    snprintf(buf, size, "%.3f %c, %.3f %c", fabs(lat), lat >= 0.0 ? 'N' : 'S', fabs(lo),
             lo >= 0.0 ? 'E' : 'W');
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

void probe_values_readout(const struct probe_values *v, struct readout_model *m)
{
    memset(m, 0, sizeof(*m));
    char when[48] = "";
    if (v->date[0])
        date_text(v->date, when, sizeof(when));
    snprintf(m->title, sizeof(m->title), "Probe%s%s", when[0] ? "  " : "", when);
    if (!v->valid) {
        /* The reason, cut into lines at spaces. */
        const char *why = v->why[0] ? v->why : "no point";
        while (*why && m->count < READOUT_ROWS) {
            size_t n = strlen(why);
            if (n > 44) {
                n = 44;
                while (n > 0 && why[n] != ' ')
                    n--;
                if (n == 0)
                    n = 44;
            }
            ROW(m, "", true, "%.*s", (int)n, why);
            why += n;
            while (*why == ' ')
                why++;
        }
        return;
    }
    char where[64];
    if (v->placed) {
        latlon_text(v->lat, v->lon, where, sizeof(where));
        ROW(m, "position", false, "%s", where);
    } else {
        ROW(m, "position", false, "x %.1f km, y %.1f km", v->data[0] / 1000.0,
            v->data[1] / 1000.0);
    }
    if (v->fields && v->at_top)
        ROW(m, "height", false, "%.0f m (above the model top here: the values at %.0f m)",
            v->data[2], v->top_m);
    else if (v->fields && v->s.has_ground)
        ROW(m, "height", false, "%.0f m (%.0f m above ground)", v->data[2],
            v->data[2] - v->s.ground_m);
    else
        ROW(m, "height", false, "%.0f m above sea level", v->data[2]);
    if (!v->fields) {
        ROW(m, "mass ratios", true, "not in the data (extinction only)");
    } else {
        for (int f = 0; f < SPECIES_COUNT; f++) {
            if (v->s.has_species[f])
                ROW(m, species_name((enum species)f), false, "%.4f g/kg", v->s.q[f] * 1e3);
            else
                ROW(m, species_name((enum species)f), true, "not in the data");
        }
        ROW(m, "condensate", false, "%.4f g/kg", probe_sample_condensate(&v->s) * 1e3);
        if (v->s.has_qvapor)
            ROW(m, "vapour", false, "%.2f g/kg", v->s.qvapor * 1e3);
        bool std_t = v->s.temperature_from == PROBE_STANDARD;
        ROW(m, "temperature", std_t, "%.1f C%s", v->s.temperature_k - 273.15,
            std_t ? " (standard atmosphere)" : "");
        bool std_p = v->s.pressure_from == PROBE_STANDARD;
        ROW(m, "pressure", std_p, "%.1f hPa%s", v->s.pressure_pa / 100.0,
            std_p ? " (standard atmosphere)" : "");
        if (v->s.has_wind) {
            double speed, from;
            probe_wind(v->s.u, v->s.v, &speed, &from);
            ROW(m, "wind", false, "%.1f m/s from %.0f deg%s", speed, from,
                v->s.wind_earth_relative ? "" : " (grid)");
            if (v->s.has_w)
                ROW(m, "vertical wind", false, "%+.2f m/s", v->s.w);
        } else {
            ROW(m, "wind", true, "not in the data");
        }
    }
    double beta = v->beta[0] + v->beta[1];
    ROW(m, "extinction", false, "%.3g /km (ice %.3g, water %.3g)", beta * 1e3, v->beta[0] * 1e3,
        v->beta[1] * 1e3);
    if (v->have_light)
        ROW(m, "sunlight", false, "%.3f of the sun's (light map)", v->light);
    else
        ROW(m, "sunlight", true, "no light map (effects.shadows off)");
    if (v->have_diffuse)
        ROW(m, "diffuse light", false, "%.3f (multiple scattering)", v->diffuse);
}

void probe_values_write_text(const struct probe_values *v, FILE *out)
{
    struct readout_model m;
    probe_values_readout(v, &m);
    fprintf(out, "%s\n", m.title);
    for (int i = 0; i < m.count; i++)
        fprintf(out, "  %-14s %s\n", m.rows[i].label, m.rows[i].value);
}

/* A number, or null when it is not finite. */
static void json_number(FILE *out, double v)
{
    if (isfinite(v))
        fprintf(out, "%.9g", v);
    else
        fprintf(out, "null");
}

void probe_values_write_json(const struct probe_values *v, FILE *out)
{
    fprintf(out, "{\n  \"valid\": %s,\n", v->valid ? "true" : "false");
    if (!v->valid) {
        fprintf(out, "  \"why\": \"%s\"\n}\n", v->why);
        return;
    }
    fprintf(out, "  \"step\": %d,\n  \"date\": \"%s\",\n", v->step, v->date);
    fprintf(out, "  \"latitude_deg\": ");
    json_number(out, v->placed ? v->lat : NAN);
    fprintf(out, ",\n  \"longitude_deg\": ");
    json_number(out, v->placed ? v->lon : NAN);
    fprintf(out, ",\n  \"x_m\": %.17g,\n  \"y_m\": %.17g,\n  \"height_m\": %.17g,\n", v->data[0],
            v->data[1], v->data[2]);
    fprintf(out, "  \"ground_m\": ");
    json_number(out, v->fields && v->s.has_ground ? v->s.ground_m : NAN);
    fprintf(out, ",\n  \"values_at_m\": "); /* the column's top, above it (at_top) */
    json_number(out, v->fields ? (v->at_top ? v->top_m : v->data[2]) : NAN);
    fprintf(out, ",\n  \"mass_ratio_g_per_kg\": {");
    for (int f = 0; f < SPECIES_COUNT; f++) {
        fprintf(out, "%s\"%s\": ", f ? ", " : "", species_name((enum species)f));
        json_number(out, v->fields && v->s.has_species[f] ? v->s.q[f] * 1e3 : NAN);
    }
    fprintf(out, "},\n  \"condensate_g_per_kg\": ");
    json_number(out, v->fields ? probe_sample_condensate(&v->s) * 1e3 : NAN);
    fprintf(out, ",\n  \"qvapor_g_per_kg\": ");
    json_number(out, v->fields && v->s.has_qvapor ? v->s.qvapor * 1e3 : NAN);
    fprintf(out, ",\n  \"temperature_c\": ");
    json_number(out, v->fields ? v->s.temperature_k - 273.15 : NAN);
    fprintf(out, ",\n  \"temperature_source\": \"%s\"",
            !v->fields ? "none"
            : v->s.temperature_from == PROBE_DATA ? "data"
                                                  : "standard atmosphere");
    fprintf(out, ",\n  \"pressure_hpa\": ");
    json_number(out, v->fields ? v->s.pressure_pa / 100.0 : NAN);
    fprintf(out, ",\n  \"pressure_source\": \"%s\"",
            !v->fields ? "none"
            : v->s.pressure_from == PROBE_DATA ? "data"
                                               : "standard atmosphere");
    bool wind = v->fields && v->s.has_wind;
    double speed = NAN, from = NAN;
    if (wind)
        probe_wind(v->s.u, v->s.v, &speed, &from);
    fprintf(out, ",\n  \"wind\": {\"u_m_s\": ");
    json_number(out, wind ? v->s.u : NAN);
    fprintf(out, ", \"v_m_s\": ");
    json_number(out, wind ? v->s.v : NAN);
    fprintf(out, ", \"w_m_s\": ");
    json_number(out, wind && v->s.has_w ? v->s.w : NAN);
    fprintf(out, ", \"speed_m_s\": ");
    json_number(out, speed);
    fprintf(out, ", \"from_deg\": ");
    json_number(out, from);
    fprintf(out, ", \"earth_relative\": %s}", wind && v->s.wind_earth_relative ? "true" : "false");
    fprintf(out, ",\n  \"extinction_per_m\": {\"ice\": %.9g, \"water\": %.9g, \"total\": %.9g}",
            v->beta[0], v->beta[1], v->beta[0] + v->beta[1]);
    fprintf(out, ",\n  \"light\": ");
    json_number(out, v->have_light ? v->light : NAN);
    fprintf(out, ",\n  \"diffuse\": ");
    json_number(out, v->have_diffuse ? v->diffuse : NAN);
    fprintf(out, "\n}\n");
}
