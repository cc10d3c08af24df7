/* The session's ground and map: terrain, coastlines, graticule and labels as opaque meshes. */
#include "session/map.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "session/scene.h"
#include "common/log.h"
#include "data/coast.h"
#include "data/source.h"
#include "data/terrain.h"
#include "render/terrain.h"

#define FONT_PATH "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
#define GRATICULE_SAMPLES 240

static const float coast_albedo[3] = {0.85f, 0.80f, 0.55f};
static const float graticule_albedo[3] = {0.55f, 0.55f, 0.55f};
static const float label_albedo[3] = {0.9f, 0.9f, 0.9f};

struct scene_map {
    struct geo_map geo;
    struct terrain terrain;
    bool have_terrain;
    double k;            /* height exaggeration */
    double rect[4];      /* x0, x1, y0, y1: the part of the ground that gets a map */
    double lift;         /* lines float this high over the ground, metres */
    double max_segment;  /* lines are cut into pieces this long, to follow the terrain */
    struct render_mesh *terrain_mesh, *coast_mesh, *graticule_mesh;
    struct render_text *labels;
    struct scene_map_info info;
};

/* A growing list of segments (x0, y0, z0, x1, y1, z1). */
struct segments {
    float *v;
    int n, cap;
    bool failed;
};

static double ground_z(const struct scene_map *m, double x, double y)
{
    if (!m->have_terrain)
        return 0.0;
    const struct terrain *t = &m->terrain;
    if (x < t->x[0] || x > t->x[t->nx - 1] || y < t->y[0] || y > t->y[t->ny - 1])
        return 0.0; /* the skirt */
    return terrain_height_at(t, x, y) * m->k;
}

static void push(struct segments *s, const double a[2], const double b[2], double za, double zb)
{
    if (s->n == s->cap) {
        int cap = s->cap ? 2 * s->cap : 1024;
        float *v = realloc(s->v, (size_t)cap * 6 * sizeof(float));
        if (!v) {
            s->failed = true;
            return;
        }
        s->v = v;
        s->cap = cap;
    }
    float *o = s->v + 6 * (size_t)s->n++;
    o[0] = (float)a[0];
    o[1] = (float)a[1];
    o[2] = (float)za;
    o[3] = (float)b[0];
    o[4] = (float)b[1];
    o[5] = (float)zb;
}

/* Liang-Barsky: clips segment A-B to the rectangle; false when nothing is left. */
static bool clip(const double r[4], double a[2], double b[2])
{
    double t0 = 0.0, t1 = 1.0, d[2] = {b[0] - a[0], b[1] - a[1]};
    const double p[4] = {-d[0], d[0], -d[1], d[1]};
    const double q[4] = {a[0] - r[0], r[1] - a[0], a[1] - r[2], r[3] - a[1]};
    for (int i = 0; i < 4; i++) {
        if (p[i] == 0.0) {
            if (q[i] < 0.0)
                return false;
            continue;
        }
        double t = q[i] / p[i];
        if (p[i] < 0.0)
            t0 = fmax(t0, t);
        else
            t1 = fmin(t1, t);
        if (t0 > t1)
            return false;
    }
    double a0[2] = {a[0], a[1]};
    a[0] = a0[0] + t0 * d[0];
    a[1] = a0[1] + t0 * d[1];
    b[0] = a0[0] + t1 * d[0];
    b[1] = a0[1] + t1 * d[1];
    return true;
}

/* Adds segment A-B of a line on the ground: clipped to the map, cut to follow the terrain. */
static void add_ground_segment(const struct scene_map *m, struct segments *s, const double a_in[2],
                               const double b_in[2])
{
    double a[2] = {a_in[0], a_in[1]}, b[2] = {b_in[0], b_in[1]};
    if (!clip(m->rect, a, b))
        return;
    double len = hypot(b[0] - a[0], b[1] - a[1]);
    int pieces = (int)fmin(1000.0, ceil(len / m->max_segment));
    pieces = pieces < 1 ? 1 : pieces;
    double p0[2] = {a[0], a[1]}, z0 = ground_z(m, a[0], a[1]) + m->lift;
    for (int i = 1; i <= pieces; i++) {
        double t = (double)i / pieces;
        double p1[2] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
        double z1 = ground_z(m, p1[0], p1[1]) + m->lift;
        push(s, p0, p1, z0, z1);
        p0[0] = p1[0];
        p0[1] = p1[1];
        z0 = z1;
    }
}

/* Where the terrain and the map come from: the WRF metadata of a data scene. */
static void use_wrf_meta(const struct config *cfg, const struct wrf_meta *meta,
                         const struct grid3 *box, struct scene_map *m)
{
    if (cfg->map.terrain)
        m->have_terrain = terrain_from_wrf(meta, box, &m->terrain);
    if (meta->xlat && meta->xlong)
        geo_map_init_grid(&m->geo, meta->xlat, meta->xlong, meta->nx, meta->ny, meta->dx,
                          meta->dy);
}

/* The same when the caller has no open source: the files are opened for it. */
static void load_wrf_meta(const struct config *cfg, const struct grid3 *box, struct scene_map *m)
{
    const char *files[CONFIG_MAX_FILES];
    struct data_source_desc desc;
    scene_source_desc(cfg, files, &desc);
    struct data_source *src = data_source_open(&desc);
    if (!src)
        return; /* the volume was read, so this does not happen short of a race; logged */
    use_wrf_meta(cfg, wrf_get_meta(data_source_wrf(src)), box, m);
    data_source_close(src);
}

/* The georeference other formats carry (data_source_geo), the files opened for it. */
static void load_source_geo(const struct config *cfg, struct geo_map *geo)
{
    const char *files[CONFIG_MAX_FILES];
    struct data_source_desc desc;
    scene_source_desc(cfg, files, &desc);
    struct data_source *src = data_source_open(&desc);
    if (src)
        data_source_geo(src, geo);
    data_source_close(src);
}

static void build_coastlines(const struct config *cfg, struct scene_map *m)
{
    static const char res[] = {'c', 'l', 'i'};
    double box[4];
    if (!geo_map_box(&m->geo, m->rect, box))
        return;
    /* A little beyond the box: lines that leave it must still reach the map's edge. */
    const double pad = 0.5;
    const double query[4] = {box[0] - pad, box[1] + pad, box[2] - pad, box[3] + pad};
    struct coast_lines c;
    const char *path = coast_file(res[cfg->map.coast_res]);
    if (!coast_read(path, query, COAST_LAKE, &c)) {
        log_warn("no coastlines (map.coastlines = false hides this warning)");
        return;
    }
    struct segments s = {0};
    for (int l = 0; l < c.n_lines && !s.failed; l++) {
        double prev[2];
        bool have_prev = false;
        for (int p = c.first[l]; p < c.first[l] + c.count[l]; p++) {
            double q[2];
            if (!geo_map_to_frame(&m->geo, c.lat[p], c.lon[p], &q[0], &q[1])) {
                have_prev = false;
                continue;
            }
            if (have_prev)
                add_ground_segment(m, &s, prev, q);
            prev[0] = q[0];
            prev[1] = q[1];
            have_prev = true;
        }
    }
    coast_lines_finish(&c);
    if (s.failed)
        log_error("out of memory for the coastlines");
    else if (s.n > 0)
        m->coast_mesh = render_lines_mesh(s.v, s.n, coast_albedo);
    m->info.coast_segments = m->coast_mesh ? s.n : 0;
    log_info("map: %d coastline segments from %s", m->info.coast_segments, path);
    free(s.v);
}

static double auto_step(const double box[4])
{
    static const double steps[] = {0.05, 0.1, 0.25, 0.5, 1, 2, 5, 10, 15, 30};
    double span = fmax(box[1] - box[0], box[3] - box[2]);
    for (size_t i = 0; i < sizeof(steps) / sizeof(steps[0]); i++) {
        if (span / steps[i] <= 8.0)
            return steps[i];
    }
    return 30.0;
}

static void format_degrees(double v, bool lat, char *buf, size_t size)
{
    if (!lat)
        v = remainder(v, 360.0);
    char hemi = lat ? (v >= 0 ? 'N' : 'S') : (v >= 0 ? 'E' : 'W');
    if (fabs(v) < 1e-9)
        snprintf(buf, size, "0\xc2\xb0");
    else
        snprintf(buf, size, "%g\xc2\xb0%c", fabs(v), hemi);
}

static bool inside(const double r[4], const double p[2], double pad)
{
    return p[0] >= r[0] + pad && p[0] <= r[1] - pad && p[1] >= r[2] + pad && p[1] <= r[3] - pad;
}

static void build_graticule(const struct config *cfg, struct scene_map *m)
{
    double box[4];
    if (!geo_map_box(&m->geo, m->rect, box))
        return;
    double step = cfg->map.graticule_step_deg > 0 ? cfg->map.graticule_step_deg : auto_step(box);
    m->info.step_deg = step;
    double size = fmin(m->rect[1] - m->rect[0], m->rect[3] - m->rect[2]);
    double text_h = 0.025 * size, pad = 0.6 * text_h;
    struct segments s = {0};
    struct render_label labels[128];
    int n_labels = 0;
    for (int axis = 0; axis < 2; axis++) { /* 0: parallels (constant lat), 1: meridians */
        double lo = axis == 0 ? box[0] : box[2], hi = axis == 0 ? box[1] : box[3];
        double olo = axis == 0 ? box[2] : box[0], ohi = axis == 0 ? box[3] : box[1];
        for (double v = ceil(lo / step) * step; v <= hi + 1e-9 && !s.failed; v += step) {
            double prev[2];
            bool have_prev = false, labelled = false;
            for (int i = 0; i <= GRATICULE_SAMPLES; i++) {
                double o = olo + (ohi - olo) * i / GRATICULE_SAMPLES;
                double lat = axis == 0 ? v : o, lon = axis == 0 ? o : v;
                double q[2];
                if (!geo_map_to_frame(&m->geo, lat, lon, &q[0], &q[1])) {
                    have_prev = false;
                    continue;
                }
                if (have_prev)
                    add_ground_segment(m, &s, prev, q);
                /* The label where the line first comes well inside the map: at the west edge
                 * for parallels, the south edge for meridians. */
                if (!labelled && cfg->map.labels && n_labels < 128 && inside(m->rect, q, pad)) {
                    struct render_label *lb = &labels[n_labels++];
                    lb->pos[0] = q[0] + 0.3 * text_h;
                    lb->pos[1] = q[1] + 0.3 * text_h;
                    lb->pos[2] = ground_z(m, q[0], q[1]) + 2.0 * m->lift;
                    lb->height_m = text_h;
                    format_degrees(v, axis == 0, lb->text, sizeof(lb->text));
                    labelled = true;
                }
                prev[0] = q[0];
                prev[1] = q[1];
                have_prev = true;
            }
        }
    }
    if (s.failed)
        log_error("out of memory for the graticule");
    else if (s.n > 0)
        m->graticule_mesh = render_lines_mesh(s.v, s.n, graticule_albedo);
    m->info.graticule_segments = m->graticule_mesh ? s.n : 0;
    free(s.v);
    if (n_labels > 0) {
        m->labels = render_text_create(FONT_PATH, labels, n_labels, label_albedo);
        if (!m->labels)
            log_warn("graticule labels left out");
        m->info.labels = m->labels ? n_labels : 0;
    }
    log_info("map: graticule every %g degrees, %d labels", step, m->info.labels);
}

/* The map.use_origin placement and the offset, after the grid's (if any). */
static void scene_geo_finish_init(const struct config *cfg, struct geo_map *geo)
{
    if (geo->kind == GEO_NONE && cfg->map.use_origin)
        geo_map_init_local(geo, cfg->map.origin_deg[0], cfg->map.origin_deg[1]);
    geo->offset[0] = cfg->map.offset_km[0] * 1000.0;
    geo->offset[1] = cfg->map.offset_km[1] * 1000.0;
}

void scene_geo_init_source(const struct config *cfg, struct data_source *src,
                           struct geo_map *out)
{
    data_source_geo(src, out);
    scene_geo_finish_init(cfg, out);
}

void scene_geo_init(const struct config *cfg, const struct wrf_meta *meta, struct geo_map *out)
{
    memset(out, 0, sizeof(*out));
    if (meta && meta->xlat && meta->xlong)
        geo_map_init_grid(out, meta->xlat, meta->xlong, meta->nx, meta->ny, meta->dx, meta->dy);
    scene_geo_finish_init(cfg, out);
}

/* The map's four meshes, in their drawing order (NULL where absent). */
static void map_meshes(const struct scene_map *m, struct render_mesh *out[4])
{
    out[0] = m->terrain_mesh;
    out[1] = m->coast_mesh;
    out[2] = m->graticule_mesh;
    out[3] = m->labels ? render_text_mesh(m->labels) : NULL;
}

/* scene_map_create without adding the meshes to R. */
static struct scene_map *map_build(const struct config *cfg, struct renderer *r,
                                   const struct wrf_meta *meta)
{
    struct scene_map *m = calloc(1, sizeof(*m));
    if (!m) {
        log_error("out of memory");
        return NULL;
    }
    const struct grid3 *g = renderer_grid(r);
    m->k = cfg->scene.height_exaggeration;
    if (cfg->scene.kind == SCENE_DATA && cfg->data.format == DATA_WRF) {
        if (meta)
            use_wrf_meta(cfg, meta, g, m);
        else
            load_wrf_meta(cfg, g, m);
    } else if (cfg->scene.kind == SCENE_DATA &&
               (cfg->data.format == DATA_ISABEL || cfg->data.format == DATA_CF)) {
        load_source_geo(cfg, &m->geo); /* Isabel's published box, a CF lat/lon grid */
    }
    scene_geo_finish_init(cfg, &m->geo);

    double w = g->n[0] * g->spacing[0], h = g->n[1] * g->spacing[1];
    double margin = cfg->map.margin_km * 1000.0;
    m->rect[0] = g->origin[0] - margin;
    m->rect[1] = g->origin[0] + w + margin;
    m->rect[2] = g->origin[1] - margin;
    m->rect[3] = g->origin[1] + h + margin;
    m->lift = (20.0 + 1e-4 * fmax(w, h)) * fmax(1.0, m->k);
    m->max_segment = 0.5 * fmin(g->spacing[0], g->spacing[1]);

    if (m->have_terrain) {
        float skirt[3];
        for (int c = 0; c < 3; c++)
            skirt[c] = (float)cfg->render.ground[c];
        m->terrain_mesh = render_terrain_mesh(&m->terrain, m->k, cfg->camera.far_km * 1000.0,
                                              skirt);
        if (!m->terrain_mesh)
            goto error;
        m->info.terrain = true;
        log_info("map: terrain %d x %d vertices (land/sea from %s), heights x %g",
                 m->terrain.nx, m->terrain.ny,
                 m->terrain.has_landmask   ? "LANDMASK"
                 : m->terrain.has_land_use ? "LU_INDEX"
                                           : "HGT > 0.5 m",
                 m->k);
    }
    m->info.placed = m->geo.kind != GEO_NONE;
    /* Synthetic scenes are unplaced by design and coastlines are on by default: say so for
     * real data or an explicit graticule, else only with --verbose. */
    if (!m->info.placed && (cfg->map.coastlines || cfg->map.graticule))
        log_msg(cfg->scene.kind == SCENE_DATA || cfg->map.graticule ? LOG_INFO : LOG_DEBUG,
                "map: the data has no XLAT/XLONG and map.use_origin is off: no coastlines "
                "or graticule");
    if (m->info.placed && cfg->map.coastlines)
        build_coastlines(cfg, m);
    if (m->info.placed && cfg->map.graticule)
        build_graticule(cfg, m);

    return m;

error:
    scene_map_destroy(m, NULL);
    return NULL;
}

struct scene_map *scene_map_create(const struct config *cfg, struct renderer *r,
                                   const struct wrf_meta *meta)
{
    struct scene_map *m = map_build(cfg, r, meta);
    if (!m)
        return NULL;
    struct render_mesh *meshes[4];
    map_meshes(m, meshes);
    for (int i = 0; i < 4; i++) {
        if (meshes[i] && !renderer_add_mesh(r, meshes[i])) {
            scene_map_destroy(m, r);
            return NULL;
        }
    }
    return m;
}

struct scene_map *scene_map_remake(struct scene_map *old, const struct config *cfg,
                                   struct renderer *r, const struct wrf_meta *meta)
{
    struct scene_map *m = map_build(cfg, r, meta);
    if (!m)
        return NULL;
    struct render_mesh *was[4], *now[4];
    map_meshes(old, was);
    map_meshes(m, now);
    for (int i = 0; i < 4; i++) {
        if (!renderer_replace_mesh(r, was[i], now[i])) {
            for (int j = 0; j < i; j++) /* the old meshes back where they were */
                renderer_replace_mesh(r, now[j], was[j]);
            scene_map_destroy(m, NULL);
            return NULL;
        }
    }
    scene_map_destroy(old, NULL); /* its meshes are out of R already */
    return m;
}

void scene_map_destroy(struct scene_map *m, struct renderer *r)
{
    if (!m)
        return;
    struct render_mesh *meshes[4];
    map_meshes(m, meshes);
    for (int i = 0; i < 4; i++) {
        if (meshes[i] && r)
            renderer_remove_mesh(r, meshes[i]);
    }
    render_mesh_destroy(m->terrain_mesh);
    render_mesh_destroy(m->coast_mesh);
    render_mesh_destroy(m->graticule_mesh);
    render_text_destroy(m->labels);
    terrain_finish(&m->terrain);
    geo_map_finish(&m->geo);
    free(m);
}

void scene_map_apply_settings(const struct scene_map *m, struct render_settings *s)
{
    if (m && m->terrain_mesh)
        s->ground_on = false; /* the terrain and its skirt are the ground */
}

void scene_map_get_info(const struct scene_map *m, struct scene_map_info *out)
{
    memset(out, 0, sizeof(*out));
    if (m)
        *out = m->info;
}

const struct geo_map *scene_map_geo(const struct scene_map *m)
{
    return &m->geo;
}
