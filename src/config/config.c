/*
 * One table of settings drives everything here: the defaults, the file walker, the --set
 * parser and the markdown reference.  A file is read in three steps: @include lines are
 * expanded (Debian's libconfig 1.5 has no include hook) into texts that keep a map from their
 * lines back to (file, line), libconfig parses each text, and the walker checks every setting
 * it finds against the table, so each message names the real file and line.
 */
#include "config/config.h"

#include <assert.h>
#include <ctype.h>
#include <errno.h>
#include <glob.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include <libconfig.h>

#include "common/log.h"

/* Enums are stored through int pointers. */
static_assert(sizeof(enum scene_kind) == sizeof(int), "enum size");
static_assert(sizeof(enum data_format) == sizeof(int), "enum size");
static_assert(sizeof(enum lightmap_mode) == sizeof(int), "enum size");
static_assert(sizeof(enum phase_choice) == sizeof(int), "enum size");
static_assert(sizeof(enum effect_mode) == sizeof(int), "enum size");
static_assert(sizeof(enum coast_resolution) == sizeof(int), "enum size");

#define INCLUDE_DEPTH_MAX 16
#define NAME_MAX_LEN 256

/* ------------------------------------------------------------------------------------------ */
/* The table                                                                                   */

enum type {
    T_BOOL,
    T_INT,
    T_UINT,
    T_DOUBLE,
    T_ENUM,
    T_FILES, /* data.files: list of paths, resolved and glob-expanded */
};

enum {
    F_MIN_OPEN = 1 << 0,
    F_MAX_OPEN = 1 << 1,
    F_SPECIES = 1 << 2,        /* one setting per species; '*' in the path is species_name() */
    F_OPTICS_DEFAULT = 1 << 3, /* the default comes from optics_params_defaults() */
};

struct setting {
    const char *path;
    enum type type;
    int n;           /* numbers in a vector; 1 for a scalar */
    size_t offset;   /* into struct config (of species 0 with F_SPECIES) */
    size_t stride;   /* F_SPECIES: bytes from one species to the next */
    double min, max; /* of each number */
    unsigned flags;
    double scale;             /* stored = written * scale; 0 means 1 */
    const char *const *names; /* T_ENUM: NULL-terminated, in enum order */
    double def[6];            /* numbers, bools as 0/1, enums as their index */
    const char *help;
};

static const char *const scene_kind_names[] = {
    "storm", "slab", "sphere", "empty", "voxel", "data", NULL,
};
static const char *const data_format_names[] = {"wrf", "isabel", "extinction", NULL};
static const char *const lightmap_mode_names[] = {"dense", "compressed", NULL};
static const char *const lightmap_grid_names[] = {"auto", "upright", NULL}; /* light_grid_kind */
static const char *const effect_mode_names[] = {"auto", "on", "off", NULL};
static const char *const phase_names[] = {"water", "ice", NULL};
static const char *const coast_res_names[] = {"crude", "low", "intermediate", NULL};

/* clang-format off */
#define OFF(member) offsetof(struct config, member)

#define BOOL(p, m, d, h) \
    {.path = p, .type = T_BOOL, .n = 1, .offset = OFF(m), .max = 1, .def = {d}, .help = h}
#define INT(p, m, lo, hi, d, h)                                                              \
    {.path = p, .type = T_INT, .n = 1, .offset = OFF(m), .min = lo, .max = hi, .def = {d},  \
     .help = h}
#define DBL(p, m, lo, hi, fl, d, h)                                                          \
    {.path = p, .type = T_DOUBLE, .n = 1, .offset = OFF(m), .min = lo, .max = hi,           \
     .flags = fl, .def = {d}, .help = h}
#define INT3(p, m, lo, hi, d0, d1, d2, h)                                                    \
    {.path = p, .type = T_INT, .n = 3, .offset = OFF(m), .min = lo, .max = hi,              \
     .def = {d0, d1, d2}, .help = h}
#define DBL3(p, m, lo, hi, fl, d0, d1, d2, h)                                                \
    {.path = p, .type = T_DOUBLE, .n = 3, .offset = OFF(m), .min = lo, .max = hi,           \
     .flags = fl, .def = {d0, d1, d2}, .help = h}
#define ENUM(p, m, nm, d, h) \
    {.path = p, .type = T_ENUM, .n = 1, .offset = OFF(m), .names = nm, .def = {d}, .help = h}
#define EFFECT(p, e, h)                                                                      \
    {.path = p, .type = T_ENUM, .n = 1, .offset = OFF(effects.mode[e]),                      \
     .names = effect_mode_names, .def = {EFFECT_AUTO}, .help = h}
#define OPTICS(p, m, lo, hi, fl, sc, h)                                                      \
    {.path = p, .type = T_DOUBLE, .n = 1, .offset = OFF(m), .stride = sizeof(double),       \
     .min = lo, .max = hi, .flags = F_OPTICS_DEFAULT | (fl), .scale = sc, .help = h}

static const struct setting settings[] = {
    ENUM("scene.kind", scene.kind, scene_kind_names, SCENE_STORM,
         "what to show: the procedural storm, a test shape, nothing, or the data.* files"),
    INT3("scene.size", scene.size, 1, 500, 128, 128, 64,
         "voxels [nx, ny, nz] of the synthetic scenes"),
    DBL3("scene.extent", scene.extent_km, 0, 1e5, F_MIN_OPEN, 60.0, 60.0, 16.0,
         "physical size [x, y, z] of the synthetic scenes, km"),
    DBL("scene.tau", scene.tau, 0, 1e6, 0, 4.0,
        "optical depth of the test scenes (slab, voxel: vertical; sphere: along a diameter)"),
    ENUM("scene.phase", scene.phase, phase_names, PHASE_WATER,
         "phase function of the test scenes' medium"),
    {.path = "scene.seed", .type = T_UINT, .n = 1, .offset = OFF(scene.seed), .min = 0,
     .max = 4294967295.0, .def = {1}, .help = "random seed of the procedural storm"},
    DBL("scene.time", scene.time, 0, 1, 0, 0.5, "evolution time of the procedural storm"),
    DBL("scene.height_exaggeration", scene.height_exaggeration, 0, 100, F_MIN_OPEN, 1.0,
        "stretches heights (volume, light map, terrain, map) by this factor; extinction is "
        "divided by it so every column keeps its optical depth"),

    ENUM("data.format", data.format, data_format_names, DATA_WRF,
         "kind of the input files: WRF NetCDF output, Isabel raw bricks or extinction volumes"),
    {.path = "data.files", .type = T_FILES, .n = 1, .offset = OFF(data.files),
     .max = CONFIG_MAX_FILES,
     .help = "input files, relative to the config file that names them; a glob pattern "
             "must match a file and is expanded by the reader (WRF steps ordered by Times)"},
    INT("data.step", data.step, 0, 1000000, 0, "time step to show, counted over all files"),
    INT("data.levels", data.levels, 0, 4096, 0,
        "regular height levels to resample to; 0 = as many as the model has"),
    DBL("data.top", data.top_km, 0, 100, 0, 0.0, "top of the height grid, km; 0 = automatic"),
    INT3("data.stride", data.stride, 1, 64, 1, 1, 1, "keep every n-th voxel along x, y, z"),
    {.path = "data.crop", .type = T_INT, .n = 6, .offset = OFF(data.crop), .min = -1,
     .max = 1000000, .def = {-1, -1, -1, -1, -1, -1},
     .help = "voxel index ranges [x0, x1, y0, y1, z0, z1] to keep, inclusive; -1 = from the "
             "first / to the last"},
    DBL("data.memory", data.memory_mb, 0, 1048576, F_MIN_OPEN, 4096.0,
        "memory budget for one time step, MiB"),
    DBL("data.cache_memory", data.cache_memory_mb, 0, 1048576, F_MIN_OPEN, 1024.0,
        "memory budget of the time series cache (all cached steps), MiB"),
    INT("data.prefetch", data.prefetch, 0, 16, 1,
        "time steps loaded in the background ahead of and behind the one shown"),
    INT3("data.isabel_size", data.isabel_size, 1, 4096, 500, 500, 100,
         "voxels [nx, ny, nz] of an Isabel brick"),
    DBL3("data.isabel_extent", data.isabel_extent_km, 0, 1e5, F_MIN_OPEN, 2000.0, 2000.0, 19.8,
         "physical size [x, y, z] of the Isabel grid, km"),

    OPTICS("optics.radius_mm.*", optics.params.radius_m, 0, 100, F_MIN_OPEN | F_SPECIES, 1e-3,
           "mean particle radius, mm"),
    OPTICS("optics.density.*", optics.params.density, 0, 20000, F_MIN_OPEN | F_SPECIES, 0,
           "particle density, kg/m^3"),
    OPTICS("optics.g_water", optics.params.g_water, -0.9, 0.9, F_MIN_OPEN | F_MAX_OPEN, 0,
           "asymmetry (mean cosine) of the water phase: cloud, rain"),
    OPTICS("optics.g_ice", optics.params.g_ice, -0.9, 0.9, F_MIN_OPEN | F_MAX_OPEN, 0,
           "asymmetry (mean cosine) of the ice phase: ice, snow, graupel"),
    OPTICS("optics.eye_peak", optics.params.eye_peak_deg, 0, 180, 0, 0,
           "eye phase: forward peak truncated inside this angle, degrees"),
    {.path = "species.*.enabled", .type = T_BOOL, .n = 1, .offset = OFF(optics.enabled),
     .stride = sizeof(bool), .max = 1, .flags = F_SPECIES, .def = {1},
     .help = "show this species"},
    {.path = "species.*.scale", .type = T_DOUBLE, .n = 1, .offset = OFF(optics.scale),
     .stride = sizeof(double), .min = 0, .max = 1e6, .flags = F_SPECIES, .def = {1.0},
     .help = "multiplies this species' extinction"},

    DBL("light.azimuth", light.azimuth_deg, -360, 360, 0, 210.0,
        "sun azimuth, degrees clockwise from north"),
    DBL("light.elevation", light.elevation_deg, -90, 90, 0, 35.0,
        "sun elevation above the horizon, degrees"),
    DBL("light.intensity", light.intensity, 0, 1e6, 0, 6.0, "sun radiance scale"),
    DBL3("light.color", light.color, 0, 1e6, 0, 1.0, 0.97, 0.92, "sun colour, linear RGB"),
    BOOL("light.atmosphere", light.atmosphere, 0,
         "redden the sun by the air it crosses (Rayleigh, approximate; docs/terrain.md)"),

    DBL3("camera.position", camera.position_km, -1e5, 1e5, 0, 2.0, -14.0, 4.0,
         "eye position [x, y, z], km"),
    DBL3("camera.target", camera.target_km, -1e5, 1e5, 0, 30.0, 30.0, 7.0,
         "point looked at [x, y, z], km"),
    DBL3("camera.up", camera.up, -1e6, 1e6, 0, 0.0, 0.0, 1.0,
         "up direction; any length, not parallel to the view"),
    DBL("camera.fov", camera.fov_deg, 1, 179, F_MIN_OPEN | F_MAX_OPEN, 50.0,
        "vertical field of view, degrees"),
    DBL("camera.near", camera.near_m, 0, 1e6, F_MIN_OPEN, 10.0, "near plane distance, m"),
    DBL("camera.far", camera.far_km, 0, 1e6, F_MIN_OPEN, 2000.0, "far plane distance, km"),

    INT("render.width", render.width, 1, 16384, 640, "image width, pixels"),
    INT("render.height", render.height, 1, 16384, 480, "image height, pixels"),
    DBL("render.step", render.step_m, 0, 1e5, 0, 0.0,
        "ray step, m; 0 = half the voxel crossing along each ray, an optically thick step "
        "taken in parts of at most one light map node (at most 16384 steps a ray)"),
    DBL("render.exposure", render.exposure, 0, 1e6, F_MIN_OPEN, 1.0,
        "multiplies radiance before tone mapping"),
    DBL3("render.sky", render.sky, 0, 1e6, 0, 0.30, 0.45, 0.75, "background radiance, linear RGB"),
    DBL3("render.ground", render.ground, 0, 1, 0, 0.05, 0.05, 0.045, "ground albedo, linear RGB"),
    BOOL("render.ground_on", render.ground_on, 1, "draw the ground plane"),
    DBL("render.termination", render.termination, 0, 1, F_MAX_OPEN, 0.001,
        "stop a ray when its transmittance falls below this"),

    ENUM("lightmap.mode", lightmap.mode, lightmap_mode_names, LIGHTMAP_DENSE,
         "deep light map storage: a dense light volume or compressed light columns"),
    INT3("lightmap.resolution", lightmap.resolution, 2, 2048, 64, 64, 64,
         "light map cells [across x, across y, along the light]"),
    DBL("lightmap.epsilon", lightmap.epsilon, 0, 1, F_MIN_OPEN, 0.01,
        "error bound of the compressed light map"),
    DBL("lightmap.forward_angle", lightmap.forward_angle_deg, 0, 180, F_MIN_OPEN, 20.0,
        "forward scattering cone angle theta, degrees"),
    ENUM("lightmap.grid", lightmap.grid, lightmap_grid_names, 0,
         "light map node planes: auto = horizontal for a volume flat against the light's "
         "drift (a WRF domain), else across the light; upright = always across the light "
         "(docs/lightmap.md)"),

    DBL("playback.speed", playback.speed, 0, 1000, F_MIN_OPEN, 2.0,
        "playback speed, time steps per second"),
    BOOL("playback.loop", playback.loop, 1, "after the last time step, play from the first"),

    EFFECT("effects.shadows", EFFECT_SHADOWS,
           "self-shadowing (the deep light map); auto: on unless nothing casts a shadow"),
    EFFECT("effects.forward", EFFECT_FORWARD,
           "central forward scattering in the light map; auto: off when optically thin "
           "along the light"),
    EFFECT("effects.peripheral", EFFECT_PERIPHERAL,
           "peripheral forward scattering; auto: as effects.forward"),
    EFFECT("effects.multiple", EFFECT_MULTIPLE,
           "multiple scattering: diffuse light from a two-stream pass down each light column, "
           "solved as a layer lit at the sun's elevation (docs/lightmap.md); auto: on unless "
           "optically thin along the light"),
    EFFECT("effects.lateral", EFFECT_LATERAL,
           "lateral escape: multiple scattering lets diffuse light out of the sides of clouds "
           "narrower than a few transport mean free paths (docs/lightmap.md); auto: on when "
           "cloud that loses 1 % of its diffuse light per optical depth that way holds 0.5 % "
           "of the extinction or more"),
    EFFECT("effects.phase", EFFECT_PHASE,
           "per-species phase (ice vs water); auto: off (one phase) when one kind is absent"),
    EFFECT("effects.ground_shadow", EFFECT_GROUND_SHADOW,
           "clouds shadow the ground; auto: off when no view sees the ground"),
    EFFECT("effects.detail", EFFECT_DETAIL,
           "procedural detail (Riley §4.5, detail.*); auto: off"),
    EFFECT("effects.temporal", EFFECT_TEMPORAL,
           "blend time steps k and k + 1 during playback (docs/effects.md); auto: on with "
           "several steps when time can play (anvil run, a scripted render), off for one step "
           "or a still render"),
    EFFECT("effects.distortion", EFFECT_DISTORTION,
           "HMD lens pre-distortion; auto: on for an HMD display"),

    BOOL("map.terrain", map.terrain, 1,
         "ground mesh from the data's HGT, LANDMASK, LU_INDEX (else the flat ground plane)"),
    BOOL("map.coastlines", map.coastlines, 1, "GSHHG coastlines where the data is placed"),
    ENUM("map.coastline_resolution", map.coast_res, coast_res_names, COAST_INTERMEDIATE,
         "GSHHG resolution (files of Debian's gmt-gshhg-low)"),
    BOOL("map.graticule", map.graticule, 0, "latitude/longitude lines"),
    DBL("map.graticule_step", map.graticule_step_deg, 0, 90, 0, 0.0,
        "degrees between graticule lines; 0 = automatic"),
    BOOL("map.labels", map.labels, 1, "label the graticule lines"),
    DBL("map.margin", map.margin_km, 0, 1e4, 0, 300.0,
        "how far coastlines and graticule reach beyond the data, km"),
    {.path = "map.offset", .type = T_DOUBLE, .n = 2, .offset = OFF(map.offset_km),
     .min = -1e4, .max = 1e4, .def = {0, 0},
     .help = "moves the data [east, north] on the map, km (for data whose lat/lon are off)"},
    BOOL("map.use_origin", map.use_origin, 0,
         "place data without XLAT/XLONG (synthetic, Isabel, extinction) at map.origin"),
    {.path = "map.origin", .type = T_DOUBLE, .n = 2, .offset = OFF(map.origin_deg),
     .min = -360, .max = 360, .def = {25.0, -80.0},
     .help = "[latitude, longitude] of the volume frame's origin (x = y = 0), degrees"},

    {.path = "detail.*", .type = T_DOUBLE, .n = 1, .offset = OFF(detail.amount),
     .stride = sizeof(double), .min = 0, .max = 1, .flags = F_SPECIES, .def = {0.5},
     .help = "share of this species' extinction modulated by noise when effects.detail is on"},
    DBL("detail.scale", detail.scale_km, 0, 1e4, F_MIN_OPEN, 3.0,
        "wavelength of the coarsest noise octave, km"),
    {.path = "detail.seed", .type = T_UINT, .n = 1, .offset = OFF(detail.seed), .min = 0,
     .max = 4294967295.0, .def = {1}, .help = "random seed of the procedural detail"},
};
/* clang-format on */

#define SETTING_COUNT ((int)(sizeof(settings) / sizeof(settings[0])))

static int instances(const struct setting *s)
{
    return (s->flags & F_SPECIES) ? SPECIES_COUNT : 1;
}

/* The path of one instance of S: '*' replaced by the species name. */
static void instance_path(const struct setting *s, int sp, char *buf, size_t size)
{
    const char *star = strchr(s->path, '*');
    if (!star) {
        snprintf(buf, size, "%s", s->path);
        return;
    }
    snprintf(buf, size, "%.*s%s%s", (int)(star - s->path), s->path, species_name(sp), star + 1);
}

static bool find_setting(const char *path, const struct setting **out, int *sp_out)
{
    char buf[NAME_MAX_LEN];
    for (int i = 0; i < SETTING_COUNT; i++) {
        for (int sp = 0; sp < instances(&settings[i]); sp++) {
            instance_path(&settings[i], sp, buf, sizeof(buf));
            if (strcmp(buf, path) == 0) {
                *out = &settings[i];
                *sp_out = sp;
                return true;
            }
        }
    }
    return false;
}

/* True when PATH names a group of settings, e.g. "light" or "species.rain"; then EXAMPLE (may
 * be NULL) receives the first setting in it. */
static bool is_group_path(const char *path, char *example, size_t size)
{
    char buf[NAME_MAX_LEN];
    size_t len = strlen(path);
    for (int i = 0; i < SETTING_COUNT; i++) {
        for (int sp = 0; sp < instances(&settings[i]); sp++) {
            instance_path(&settings[i], sp, buf, sizeof(buf));
            if (strncmp(buf, path, len) == 0 && buf[len] == '.') {
                if (example)
                    snprintf(example, size, "%s", buf);
                return true;
            }
        }
    }
    return false;
}

static size_t element_size(const struct setting *s)
{
    switch (s->type) {
    case T_BOOL:
        return sizeof(bool);
    case T_INT:
    case T_ENUM:
        return sizeof(int);
    case T_UINT:
        return sizeof(unsigned);
    case T_DOUBLE:
        return sizeof(double);
    case T_FILES:
        break;
    }
    return 0;
}

static void *field(const struct setting *s, int sp, int k, struct config *cfg)
{
    return (char *)cfg + s->offset + (size_t)sp * s->stride + (size_t)k * element_size(s);
}

static double scale_of(const struct setting *s)
{
    return s->scale != 0 ? s->scale : 1.0;
}

/* Stores number K of setting S as written in a file (before scaling). */
static void store(const struct setting *s, int sp, int k, double v, struct config *cfg)
{
    void *p = field(s, sp, k, cfg);
    switch (s->type) {
    case T_BOOL:
        *(bool *)p = v != 0;
        break;
    case T_INT:
    case T_ENUM:
        *(int *)p = (int)v;
        break;
    case T_UINT:
        *(unsigned *)p = (unsigned)v;
        break;
    case T_DOUBLE:
        *(double *)p = v * scale_of(s);
        break;
    case T_FILES:
        assert(!"not a number");
    }
}

/* Number K of setting S in the units of a file. */
static double fetch(const struct setting *s, int sp, int k, const struct config *cfg)
{
    const void *p = field(s, sp, k, (struct config *)cfg);
    switch (s->type) {
    case T_BOOL:
        return *(const bool *)p;
    case T_INT:
    case T_ENUM:
        return *(const int *)p;
    case T_UINT:
        return *(const unsigned *)p;
    case T_DOUBLE:
        return *(const double *)p / scale_of(s);
    case T_FILES:
        break;
    }
    return 0;
}

void config_defaults(struct config *cfg)
{
    memset(cfg, 0, sizeof(*cfg));
    optics_params_defaults(&cfg->optics.params);
    for (int i = 0; i < SETTING_COUNT; i++) {
        const struct setting *s = &settings[i];
        if (s->type == T_FILES || (s->flags & F_OPTICS_DEFAULT))
            continue;
        for (int sp = 0; sp < instances(s); sp++)
            for (int k = 0; k < s->n; k++)
                store(s, sp, k, s->def[k], cfg);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Formatting                                                                                  */

/* A double the way a libconfig file would spell it: always with a point or an exponent. */
static void format_double(double v, char *buf, size_t size)
{
    snprintf(buf, size, "%.10g", v);
    if (!strpbrk(buf, ".eni"))
        strncat(buf, ".0", size - strlen(buf) - 1);
}

static void format_range(const struct setting *s, char *buf, size_t size)
{
    snprintf(buf, size, "%c%.15g, %.15g%c", (s->flags & F_MIN_OPEN) ? '(' : '[', s->min, s->max,
             (s->flags & F_MAX_OPEN) ? ')' : ']');
}

static void format_names(const struct setting *s, char *buf, size_t size)
{
    buf[0] = '\0';
    for (int i = 0; s->names[i]; i++) {
        size_t len = strlen(buf);
        snprintf(buf + len, size - len, "%s\"%s\"", i ? ", " : "", s->names[i]);
    }
}

/* What one value of S must be: "a number in [-90, 90]", "true or false", ... */
static void expectation(const struct setting *s, bool plural, char *buf, size_t size)
{
    char range[96];
    switch (s->type) {
    case T_BOOL:
        snprintf(buf, size, "true or false");
        break;
    case T_INT:
    case T_UINT:
    case T_DOUBLE:
        format_range(s, range, sizeof(range));
        if (plural)
            snprintf(buf, size, "%s in %s", s->type == T_DOUBLE ? "numbers" : "integers", range);
        else
            snprintf(buf, size, "%s in %s", s->type == T_DOUBLE ? "a number" : "an integer", range);
        break;
    case T_ENUM:
        snprintf(buf, size, "one of ");
        format_names(s, buf + strlen(buf), size - strlen(buf));
        break;
    case T_FILES:
        snprintf(buf, size, "a file name (a string)");
        break;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Values as written, from a file or from --set, before they are checked                      */

enum raw_kind { RAW_INT, RAW_FLOAT, RAW_BOOL, RAW_STRING, RAW_OTHER };

struct where {
    const char *file; /* NULL: the --set option */
    int line;         /* 0: unknown */
};

struct raw {
    enum raw_kind kind;
    long long i;
    double d;
    bool b;
    const char *s; /* RAW_STRING: the text; RAW_OTHER: what it is ("a group") */
    struct where where;
};

#define ELEMS_MAX (CONFIG_MAX_FILES + 1)

struct value {
    struct raw one; /* the setting itself; RAW_OTHER for arrays and lists */
    bool is_list;   /* written as an array or a list */
    int count;      /* is_list: its length (only ELEMS_MAX are kept) */
    struct raw elems[ELEMS_MAX];
};

static void describe(const struct raw *r, char *buf, size_t size)
{
    switch (r->kind) {
    case RAW_INT:
        snprintf(buf, size, "%lld", r->i);
        break;
    case RAW_FLOAT:
        format_double(r->d, buf, size);
        break;
    case RAW_BOOL:
        snprintf(buf, size, "%s", r->b ? "true" : "false");
        break;
    case RAW_STRING:
        snprintf(buf, size, "\"%s\"", r->s);
        break;
    case RAW_OTHER:
        snprintf(buf, size, "%s", r->s);
        break;
    }
}

static void report(const struct where *w, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void report(const struct where *w, const char *path, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    if (!w->file)
        log_error("--set %s: %s", path, msg);
    else if (w->line > 0)
        log_error("%s:%d: %s: %s", w->file, w->line, path, msg);
    else
        log_error("%s: %s: %s", w->file, path, msg);
}

/* Checks one written value against S; on success *OUT is the number to store. */
static bool convert(const struct setting *s, const struct raw *r, const char *path, double *out)
{
    char expect[256], got[NAME_MAX_LEN + 8];
    bool ok = false;
    double v = 0;
    switch (s->type) {
    case T_BOOL:
        ok = r->kind == RAW_BOOL;
        v = r->b;
        break;
    case T_INT:
    case T_UINT:
    case T_DOUBLE:
        if (r->kind == RAW_INT)
            v = (double)r->i;
        else if (r->kind == RAW_FLOAT && s->type == T_DOUBLE)
            v = r->d;
        else
            break;
        ok = isfinite(v) && ((s->flags & F_MIN_OPEN) ? v > s->min : v >= s->min) &&
             ((s->flags & F_MAX_OPEN) ? v < s->max : v <= s->max);
        break;
    case T_ENUM:
        if (r->kind != RAW_STRING)
            break;
        for (int i = 0; s->names[i]; i++) {
            if (strcmp(s->names[i], r->s) == 0) {
                ok = true;
                v = i;
            }
        }
        break;
    case T_FILES:
        assert(!"not a scalar");
    }
    if (ok) {
        *out = v;
        return true;
    }
    expectation(s, false, expect, sizeof(expect));
    describe(r, got, sizeof(got));
    report(&r->where, path, "expected %s, got %s", expect, got);
    return false;
}

static void dir_of(const char *file, char *buf, size_t size)
{
    const char *slash = strrchr(file, '/');
    if (!slash)
        snprintf(buf, size, "%s", "");
    else if (slash == file)
        snprintf(buf, size, "/");
    else
        snprintf(buf, size, "%.*s", (int)(slash - file), file);
}

/* DIR/NAME, or NAME alone when it is absolute or DIR is empty.  False when too long. */
static bool join_path(const char *dir, const char *name, char *buf, size_t size)
{
    int n;
    if (name[0] == '/' || !dir[0])
        n = snprintf(buf, size, "%s", name);
    else if (dir[strlen(dir) - 1] == '/')
        n = snprintf(buf, size, "%s%s", dir, name);
    else
        n = snprintf(buf, size, "%s/%s", dir, name);
    return n >= 0 && (size_t)n < size;
}

typedef char file_list[CONFIG_MAX_FILES][CONFIG_PATH_MAX];

/* Resolves one entry of data.files against BASE_DIR and appends what it names to LIST. */
static bool add_files(const struct raw *r, const char *path, const char *base_dir, file_list list,
                      int *count)
{
    char full[CONFIG_PATH_MAX];
    if (!r->s[0]) {
        report(&r->where, path, "expected a file name, got an empty string");
        return false;
    }
    if (!join_path(base_dir, r->s, full, sizeof(full))) {
        report(&r->where, path, "path longer than %d characters", CONFIG_PATH_MAX - 1);
        return false;
    }
    if (!strpbrk(r->s, "*?[")) {
        if (*count >= CONFIG_MAX_FILES)
            goto error_too_many;
        memcpy(list[(*count)++], full, sizeof(full));
        return true;
    }
    glob_t g;
    int rc = glob(full, 0, NULL, &g);
    if (rc == GLOB_NOMATCH) {
        report(&r->where, path, "no file matches \"%s\"", full);
        return false;
    }
    if (rc != 0) {
        report(&r->where, path, "cannot expand \"%s\"", full);
        globfree(&g);
        return false;
    }
    /* The pattern stays one entry: the data reader expands it (and orders the files by
     * their time steps), so a glob may match any number of files. */
    if (*count >= CONFIG_MAX_FILES) {
        globfree(&g);
        goto error_too_many;
    }
    memcpy(list[(*count)++], full, sizeof(full));
    globfree(&g);
    return true;

error_too_many:
    report(&r->where, path, "expected at most %d files", CONFIG_MAX_FILES);
    return false;
}

static bool apply_files(const struct value *val, const char *path, struct config *cfg)
{
    const struct raw *elems = val->elems;
    int n = val->count;
    if (!val->is_list) {
        if (val->one.kind != RAW_STRING) {
            char got[NAME_MAX_LEN + 8];
            describe(&val->one, got, sizeof(got));
            report(&val->one.where, path, "expected a list of file names, got %s", got);
            return false;
        }
        elems = &val->one;
        n = 1;
    }
    if (n > CONFIG_MAX_FILES) {
        report(&val->one.where, path, "expected at most %d files, got %d", CONFIG_MAX_FILES, n);
        return false;
    }
    file_list *list = malloc(sizeof(file_list));
    if (!list) {
        report(&val->one.where, path, "out of memory");
        return false;
    }
    int count = 0;
    for (int i = 0; i < n; i++) {
        char elem_path[NAME_MAX_LEN + 16];
        snprintf(elem_path, sizeof(elem_path), "%s[%d]", path, i);
        if (elems[i].kind != RAW_STRING) {
            char got[NAME_MAX_LEN + 8];
            describe(&elems[i], got, sizeof(got));
            report(&elems[i].where, elem_path, "expected a file name (a string), got %s", got);
            goto error_list;
        }
        char base[CONFIG_PATH_MAX] = "";
        if (elems[i].where.file)
            dir_of(elems[i].where.file, base, sizeof(base));
        if (!add_files(&elems[i], elem_path, base, *list, &count))
            goto error_list;
    }
    memcpy(cfg->data.files, *list, (size_t)count * CONFIG_PATH_MAX);
    cfg->data.file_count = count;
    free(list);
    return true;

error_list:
    free(list);
    return false;
}

/* Checks VAL against S and stores it; nothing is stored unless all of it is valid. */
static bool apply(const struct setting *s, int sp, const char *path, const struct value *val,
                  struct config *cfg)
{
    if (s->type == T_FILES)
        return apply_files(val, path, cfg);

    double v[6];
    if (s->n == 1) {
        if (!convert(s, &val->one, path, &v[0]))
            return false;
        store(s, sp, 0, v[0], cfg);
        return true;
    }

    char expect[256], got[NAME_MAX_LEN + 8];
    expectation(s, true, expect, sizeof(expect));
    if (!val->is_list) {
        describe(&val->one, got, sizeof(got));
        report(&val->one.where, path, "expected an array of %d %s, got %s", s->n, expect, got);
        return false;
    }
    if (val->count != s->n) {
        report(&val->one.where, path, "expected an array of %d %s, got %d element%s", s->n, expect,
               val->count, val->count == 1 ? "" : "s");
        return false;
    }
    for (int k = 0; k < s->n; k++) {
        char elem_path[NAME_MAX_LEN + 16];
        snprintf(elem_path, sizeof(elem_path), "%s[%d]", path, k);
        if (!convert(s, &val->elems[k], elem_path, &v[k]))
            return false;
    }
    for (int k = 0; k < s->n; k++)
        store(s, sp, k, v[k], cfg);
    return true;
}

/* ------------------------------------------------------------------------------------------ */
/* Unknown names                                                                               */

static size_t edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la >= NAME_MAX_LEN || lb >= NAME_MAX_LEN)
        return SIZE_MAX;
    size_t row[NAME_MAX_LEN + 1];
    for (size_t j = 0; j <= lb; j++)
        row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t up = row[j];
            size_t best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best)
                best = up + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

/* The known name closest to PATH (a setting or a group), or "" when none is close. */
static void suggest(const char *path, char *best, size_t size)
{
    char buf[NAME_MAX_LEN];
    size_t best_d = SIZE_MAX, len = strlen(path);
    best[0] = '\0';
    for (int i = 0; i < SETTING_COUNT; i++) {
        for (int sp = 0; sp < instances(&settings[i]); sp++) {
            instance_path(&settings[i], sp, buf, sizeof(buf));
            /* "elevation" at the top level: the setting of that name in its group. */
            size_t bl = strlen(buf);
            if (bl > len && buf[bl - len - 1] == '.' && strcmp(buf + bl - len, path) == 0) {
                snprintf(best, size, "%s", buf);
                return;
            }
            /* The setting itself and each group above it. */
            for (char *end = buf + bl; end; end = strrchr(buf, '.')) {
                *end = '\0';
                size_t d = edit_distance(path, buf);
                if (d < best_d) {
                    best_d = d;
                    snprintf(best, size, "%s", buf);
                }
            }
        }
    }
    if (best_d > 2 && best_d > len / 4)
        best[0] = '\0';
}

static void report_unknown(const struct where *w, const char *path)
{
    char near[NAME_MAX_LEN];
    suggest(path, near, sizeof(near));
    if (near[0])
        report(w, path, "unknown setting (did you mean %s?)", near);
    else
        report(w, path, "unknown setting");
}

/* ------------------------------------------------------------------------------------------ */
/* --set                                                                                       */

static char *trim(char *s)
{
    while (isspace((unsigned char)*s))
        s++;
    char *end = s + strlen(s);
    while (end > s && isspace((unsigned char)end[-1]))
        *--end = '\0';
    return s;
}

static char *strip_quotes(char *s)
{
    size_t len = strlen(s);
    if (len >= 2 && s[0] == '"' && s[len - 1] == '"') {
        s[len - 1] = '\0';
        return s + 1;
    }
    return s;
}

/* One value from command-line text, read the way setting S expects. */
static void raw_from_text(const struct setting *s, char *text, struct raw *r)
{
    memset(r, 0, sizeof(*r));
    text = trim(text);
    if (s->type == T_ENUM || s->type == T_FILES) {
        r->kind = RAW_STRING;
        r->s = strip_quotes(text);
        return;
    }
    if (!text[0]) {
        r->kind = RAW_OTHER;
        r->s = "nothing";
        return;
    }
    static const char *const truths[] = {"true", "yes", "on"};
    static const char *const falsehoods[] = {"false", "no", "off"};
    for (int i = 0; i < 3; i++) {
        if (strcasecmp(text, truths[i]) == 0 || strcasecmp(text, falsehoods[i]) == 0) {
            r->kind = RAW_BOOL;
            r->b = strcasecmp(text, truths[i]) == 0;
            return;
        }
    }
    char *end;
    errno = 0;
    long long i = strtoll(text, &end, 10);
    if (!*end && errno == 0) {
        r->kind = RAW_INT;
        r->i = i;
        return;
    }
    errno = 0;
    double d = strtod(text, &end);
    if (!*end && isfinite(d)) {
        r->kind = RAW_FLOAT;
        r->d = d;
        return;
    }
    r->kind = RAW_STRING;
    r->s = text;
}

bool config_set(struct config *cfg, const char *assignment)
{
    char *copy = strdup(assignment);
    if (!copy) {
        log_error("--set %s: out of memory", assignment);
        return false;
    }
    bool ok = false;
    char *eq = strchr(copy, '=');
    if (!eq) {
        log_error("--set %s: expected SETTING=VALUE, e.g. light.elevation=10", assignment);
        goto done;
    }
    *eq = '\0';
    char *path = trim(copy), *text = trim(eq + 1);
    const struct setting *s;
    int sp;
    struct where w = {NULL, 0};
    if (!find_setting(path, &s, &sp)) {
        char example[NAME_MAX_LEN];
        if (is_group_path(path, example, sizeof(example)))
            report(&w, path, "expected a setting, not a group (e.g. %s)", example);
        else
            report_unknown(&w, path);
        goto done;
    }

    struct value val;
    memset(&val, 0, sizeof(val));
    if (s->n > 1 || s->type == T_FILES) {
        size_t len = strlen(text);
        if (len >= 2 && ((text[0] == '[' && text[len - 1] == ']') ||
                         (text[0] == '(' && text[len - 1] == ')'))) {
            text[len - 1] = '\0';
            text = trim(text + 1);
        }
        val.is_list = true;
        val.one.kind = RAW_OTHER;
        val.one.s = "an array";
        if (text[0]) {
            for (char *item = text;;) {
                char *comma = strchr(item, ',');
                if (comma)
                    *comma = '\0';
                if (val.count < ELEMS_MAX)
                    raw_from_text(s, item, &val.elems[val.count]);
                val.count++;
                if (!comma)
                    break;
                item = comma + 1;
            }
        }
    } else {
        raw_from_text(s, text, &val.one);
    }
    ok = apply(s, sp, path, &val, cfg);

done:
    free(copy);
    return ok;
}

/* ------------------------------------------------------------------------------------------ */
/* Files: @include expansion with a line map                                                   */

/* An @include at the top level (outside any group) starts a new chunk, and the rest of the
 * including file another one.  Chunks are parsed one after the other, so a group written in a
 * later chunk adds to and overrides the same group of an earlier one instead of being a
 * duplicate; an @include inside a group is plain text substitution. */

struct origin {
    int file; /* index into source.files */
    int line;
};

struct chunk {
    char *text;
    size_t len, cap;
    struct origin *lines; /* lines[i]: where line i + 1 of TEXT came from */
    int line_count, line_cap;
};

struct source {
    struct chunk *chunks;
    int chunk_count;
    int depth; /* of brackets open at the end of the text so far */
    char **files;
    int file_count;
    struct stat chain[INCLUDE_DEPTH_MAX + 1]; /* the files being expanded, outermost first */
};

static bool new_chunk(struct source *src)
{
    struct chunk *grown = realloc(src->chunks, (size_t)(src->chunk_count + 1) * sizeof(*grown));
    if (!grown)
        return false;
    src->chunks = grown;
    memset(&src->chunks[src->chunk_count++], 0, sizeof(struct chunk));
    return true;
}

static bool append_text(struct chunk *ch, const char *s, size_t n)
{
    if (ch->len + n + 1 > ch->cap) {
        size_t cap = ch->cap ? ch->cap : 4096;
        while (ch->len + n + 1 > cap)
            cap *= 2;
        char *grown = realloc(ch->text, cap);
        if (!grown)
            return false;
        ch->text = grown;
        ch->cap = cap;
    }
    memcpy(ch->text + ch->len, s, n);
    ch->len += n;
    ch->text[ch->len] = '\0';
    return true;
}

static bool append_line(struct source *src, const char *s, size_t n, int file, int line)
{
    struct chunk *ch = &src->chunks[src->chunk_count - 1];
    if (ch->line_count == ch->line_cap) {
        int cap = ch->line_cap ? ch->line_cap * 2 : 256;
        struct origin *grown = realloc(ch->lines, (size_t)cap * sizeof(*grown));
        if (!grown)
            return false;
        ch->lines = grown;
        ch->line_cap = cap;
    }
    ch->lines[ch->line_count++] = (struct origin){file, line};
    return append_text(ch, s, n) && append_text(ch, "\n", 1);
}

static int add_file_name(struct source *src, const char *path)
{
    char **grown = realloc(src->files, (size_t)(src->file_count + 1) * sizeof(*grown));
    if (!grown)
        return -1;
    src->files = grown;
    src->files[src->file_count] = strdup(path);
    if (!src->files[src->file_count])
        return -1;
    return src->file_count++;
}

static void source_finish(struct source *src)
{
    for (int i = 0; i < src->file_count; i++)
        free(src->files[i]);
    free(src->files);
    for (int i = 0; i < src->chunk_count; i++) {
        free(src->chunks[i].lines);
        free(src->chunks[i].text);
    }
    free(src->chunks);
}

/* File and line of line LINE (from 1) of chunk CH. */
static struct where locate(const struct source *src, const struct chunk *ch, int line)
{
    if (ch->line_count == 0)
        return (struct where){src->files[0], 0};
    if (line < 1)
        line = 1;
    if (line > ch->line_count)
        line = ch->line_count;
    const struct origin *o = &ch->lines[line - 1];
    return (struct where){src->files[o->file], o->line};
}

/* Reads a whole file; NULL with errno set on failure. */
static char *read_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 4096, len = 0;
    char *buf = malloc(cap);
    while (buf) {
        len += fread(buf + len, 1, cap - len - 1, f);
        if (ferror(f) || feof(f))
            break;
        char *grown = realloc(buf, cap * 2);
        if (!grown) {
            free(buf);
            buf = NULL;
            errno = ENOMEM;
            break;
        }
        buf = grown;
        cap *= 2;
    }
    int err = ferror(f) ? (errno ? errno : EIO) : 0;
    fclose(f);
    if (buf && err) {
        free(buf);
        errno = err;
        return NULL;
    }
    if (buf)
        buf[len] = '\0';
    return buf;
}

/* Follows block comments and open brackets through line L..END. */
static void scan_line(const char *l, const char *end, bool *in_comment, int *depth)
{
    bool in_string = false;
    for (const char *p = l; p < end; p++) {
        if (*in_comment) {
            if (p[0] == '*' && p + 1 < end && p[1] == '/') {
                *in_comment = false;
                p++;
            }
        } else if (in_string) {
            if (*p == '\\' && p + 1 < end)
                p++;
            else if (*p == '"')
                in_string = false;
        } else if (*p == '"') {
            in_string = true;
        } else if (*p == '#' || (p[0] == '/' && p + 1 < end && p[1] == '/')) {
            break;
        } else if (p[0] == '/' && p + 1 < end && p[1] == '*') {
            *in_comment = true;
            p++;
        } else if (*p == '{' || *p == '(' || *p == '[') {
            (*depth)++;
        } else if (*p == '}' || *p == ')' || *p == ']') {
            (*depth)--;
        }
    }
}

static bool expand_file(struct source *src, const char *path, int depth, const struct where *from);

/* An @include line: expands the named file relative to the one that names it. */
static bool expand_include(struct source *src, const char *line, const char *end, int depth,
                           const struct where *here)
{
    const char *p = line + strlen("@include");
    while (p < end && (*p == ' ' || *p == '\t'))
        p++;
    const char *name = p + 1, *close = NULL;
    if (p < end && *p == '"')
        close = memchr(name, '"', (size_t)(end - name));
    if (!close) {
        log_error("%s:%d: syntax error: expected @include \"FILE\"", here->file, here->line);
        return false;
    }
    for (p = close + 1; p < end && (*p == ' ' || *p == '\t' || *p == '\r'); p++)
        ;
    if (p < end && *p != '#' && !(p[0] == '/' && p + 1 < end && p[1] == '/')) {
        log_error("%s:%d: syntax error: unexpected text after @include \"FILE\"", here->file,
                  here->line);
        return false;
    }
    char rel[CONFIG_PATH_MAX], dir[CONFIG_PATH_MAX], full[CONFIG_PATH_MAX];
    snprintf(rel, sizeof(rel), "%.*s", (int)(close - name), name);
    dir_of(here->file, dir, sizeof(dir));
    if (!join_path(dir, rel, full, sizeof(full))) {
        log_error("%s:%d: @include \"%s\": path too long", here->file, here->line, rel);
        return false;
    }
    return expand_file(src, full, depth + 1, here);
}

/* Appends PATH, with its @include lines expanded, to SRC.  FROM is the @include that names it
 * (NULL for the top file). */
static bool expand_file(struct source *src, const char *path, int depth, const struct where *from)
{
    if (depth > INCLUDE_DEPTH_MAX) {
        log_error("%s:%d: @include: nested more than %d deep (an include cycle?)", from->file,
                  from->line, INCLUDE_DEPTH_MAX);
        return false;
    }
    char *text = read_file(path);
    if (!text) {
        if (from)
            log_error("%s:%d: @include: cannot read %s: %s", from->file, from->line, path,
                      strerror(errno));
        else
            log_error("%s: cannot read: %s", path, strerror(errno));
        return false;
    }
    struct stat st;
    if (stat(path, &st) == 0) {
        for (int i = 0; i < depth; i++) {
            if (src->chain[i].st_dev == st.st_dev && src->chain[i].st_ino == st.st_ino) {
                log_error("%s:%d: @include: include cycle through %s", from->file, from->line,
                          path);
                free(text);
                return false;
            }
        }
        src->chain[depth] = st;
    }
    int file = add_file_name(src, path);
    if (file < 0) {
        log_error("%s: out of memory", path);
        free(text);
        return false;
    }

    bool ok = true, in_comment = false;
    int number = 0;
    for (const char *l = text; ok && *l;) {
        const char *end = strchr(l, '\n');
        const char *next = end ? end + 1 : l + strlen(l);
        if (!end)
            end = next;
        number++;
        const char *p = l;
        while (p < end && (*p == ' ' || *p == '\t'))
            p++;
        if (!in_comment && (size_t)(end - p) >= 8 && strncmp(p, "@include", 8) == 0) {
            struct where here = {src->files[file], number};
            bool top = src->depth <= 0;
            if (top && !new_chunk(src))
                goto error_memory;
            ok = expand_include(src, p, end, depth, &here);
            if (ok && top && !new_chunk(src))
                goto error_memory;
        } else {
            scan_line(l, end, &in_comment, &src->depth);
            if (!append_line(src, l, (size_t)(end - l), file, number))
                goto error_memory;
        }
        l = next;
    }
    free(text);
    return ok;

error_memory:
    log_error("%s: out of memory", path);
    free(text);
    return false;
}

/* ------------------------------------------------------------------------------------------ */
/* Files: the walker                                                                           */

static void raw_from_setting(const struct source *src, const struct chunk *ch,
                             const config_setting_t *st, struct raw *r)
{
    memset(r, 0, sizeof(*r));
    switch (config_setting_type(st)) {
    case CONFIG_TYPE_INT:
    case CONFIG_TYPE_INT64:
        r->kind = RAW_INT;
        r->i = config_setting_get_int64(st);
        break;
    case CONFIG_TYPE_FLOAT:
        r->kind = RAW_FLOAT;
        r->d = config_setting_get_float(st);
        break;
    case CONFIG_TYPE_BOOL:
        r->kind = RAW_BOOL;
        r->b = config_setting_get_bool(st);
        break;
    case CONFIG_TYPE_STRING:
        r->kind = RAW_STRING;
        r->s = config_setting_get_string(st);
        break;
    case CONFIG_TYPE_GROUP:
        r->kind = RAW_OTHER;
        r->s = "a group";
        break;
    case CONFIG_TYPE_ARRAY:
        r->kind = RAW_OTHER;
        r->s = "an array";
        break;
    default:
        r->kind = RAW_OTHER;
        r->s = "a list";
        break;
    }
    r->where = locate(src, ch, config_setting_source_line(st));
}

static bool walk_group(const struct source *src, const struct chunk *ch,
                       const config_setting_t *group, const char *prefix, struct config *cfg)
{
    struct value val;
    int n = config_setting_length(group);
    for (int i = 0; i < n; i++) {
        const config_setting_t *child = config_setting_get_elem(group, i);
        char path[NAME_MAX_LEN];
        snprintf(path, sizeof(path), "%s%s%s", prefix, prefix[0] ? "." : "",
                 config_setting_name(child));
        const struct setting *s;
        int sp;
        memset(&val, 0, sizeof(val));
        raw_from_setting(src, ch, child, &val.one);
        if (find_setting(path, &s, &sp)) {
            val.is_list = config_setting_is_array(child) || config_setting_is_list(child);
            if (val.is_list) {
                val.count = config_setting_length(child);
                for (int k = 0; k < val.count && k < ELEMS_MAX; k++)
                    raw_from_setting(src, ch, config_setting_get_elem(child, k), &val.elems[k]);
            }
            if (!apply(s, sp, path, &val, cfg))
                return false;
        } else if (is_group_path(path, NULL, 0)) {
            if (!config_setting_is_group(child)) {
                char got[NAME_MAX_LEN + 8];
                describe(&val.one, got, sizeof(got));
                report(&val.one.where, path, "expected a group { ... }, got %s", got);
                return false;
            }
            if (!walk_group(src, ch, child, path, cfg))
                return false;
        } else {
            report_unknown(&val.one.where, path);
            return false;
        }
    }
    return true;
}

/* Parses one chunk and applies what it sets. */
static bool read_chunk(const struct source *src, const struct chunk *ch, struct config *cfg)
{
    if (ch->line_count > USHRT_MAX) {
        /* config_setting_source_line() is an unsigned short */
        struct where w = locate(src, ch, 1);
        log_error("%s: more than %d lines in one piece with its includes", w.file, USHRT_MAX);
        return false;
    }
    config_t lc;
    config_init(&lc);
    bool ok = false;
    if (!config_read_string(&lc, ch->text ? ch->text : "")) {
        struct where w = locate(src, ch, config_error_line(&lc));
        const char *text = config_error_text(&lc);
        if (strcmp(text, "syntax error") == 0)
            log_error("%s:%d: syntax error", w.file, w.line);
        else if (strstr(text, "mismatched element type"))
            log_error("%s:%d: syntax error: %s (write every number of an array alike: 1.0, "
                      "not 1)",
                      w.file, w.line, text);
        else
            log_error("%s:%d: syntax error: %s", w.file, w.line, text);
        goto done;
    }
    ok = walk_group(src, ch, config_root_setting(&lc), "", cfg);
done:
    config_destroy(&lc);
    return ok;
}

bool config_load(const char *path, struct config *cfg)
{
    config_defaults(cfg);
    if (strlen(path) >= sizeof(cfg->path)) {
        log_error("%s: path too long", path);
        return false;
    }
    snprintf(cfg->path, sizeof(cfg->path), "%s", path);

    struct source src = {0};
    bool ok = new_chunk(&src);
    if (!ok)
        log_error("%s: out of memory", path);
    ok = ok && expand_file(&src, path, 0, NULL);
    for (int i = 0; ok && i < src.chunk_count; i++)
        ok = read_chunk(&src, &src.chunks[i], cfg);
    source_finish(&src);
    return ok;
}

/* ------------------------------------------------------------------------------------------ */
/* Cross-setting checks                                                                        */

static double length3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

bool config_validate(const struct config *cfg)
{
    /* "FILE: " before each message, or nothing for settings without a file */
    const char *file = cfg->path[0] ? cfg->path : "";
    const char *colon = cfg->path[0] ? ": " : "";
    const struct config_camera *cam = &cfg->camera;
    double view[3], cross[3];
    for (int k = 0; k < 3; k++)
        view[k] = cam->target_km[k] - cam->position_km[k];
    double dist = length3(view), up = length3(cam->up);
    if (dist < 1e-9) {
        log_error("%s%scamera.target: must differ from camera.position", file, colon);
        return false;
    }
    if (up < 1e-12) {
        log_error("%s%scamera.up: must not be [0, 0, 0]", file, colon);
        return false;
    }
    cross[0] = view[1] * cam->up[2] - view[2] * cam->up[1];
    cross[1] = view[2] * cam->up[0] - view[0] * cam->up[2];
    cross[2] = view[0] * cam->up[1] - view[1] * cam->up[0];
    if (length3(cross) < 1e-6 * dist * up) {
        log_error("%s%scamera.up: must not be parallel to the view direction "
                  "(camera.target - camera.position)",
                  file, colon);
        return false;
    }
    if (cfg->scene.kind != SCENE_DATA && cfg->scene.size[2] > 100) {
        log_error("%s%sscene.size: expected at most 100 levels for a synthetic scene (the "
                  "largest is Isabel's 500 x 500 x 100), got %d",
                  file, colon, cfg->scene.size[2]);
        return false;
    }
    if (cam->near_m >= cam->far_km * 1000.0) {
        log_error("%s%scamera.near: must be closer than camera.far (%g m >= %g km)", file, colon,
                  cam->near_m, cam->far_km);
        return false;
    }
    if (cfg->scene.kind == SCENE_DATA && cfg->data.file_count == 0) {
        log_error("%s%sdata.files: scene.kind = \"data\" needs at least one file", file, colon);
        return false;
    }
    static const char axes[] = "xyz";
    for (int a = 0; a < 3; a++) {
        int lo = cfg->data.crop[2 * a], hi = cfg->data.crop[2 * a + 1];
        if (lo >= 0 && hi >= 0 && lo > hi) {
            log_error("%s%sdata.crop: %c range [%d, %d] is reversed", file, colon, axes[a], lo, hi);
            return false;
        }
    }
    return true;
}

/* ------------------------------------------------------------------------------------------ */
/* Reference                                                                                   */

static void format_default(const struct setting *s, int sp, const struct config *def, char *buf,
                           size_t size)
{
    if (s->type == T_FILES) {
        snprintf(buf, size, "[]");
        return;
    }
    buf[0] = '\0';
    if (s->n > 1)
        strncat(buf, "[", size - 1);
    for (int k = 0; k < s->n; k++) {
        char num[64];
        double v = fetch(s, sp, k, def);
        if (s->type == T_DOUBLE)
            format_double(v, num, sizeof(num));
        else if (s->type == T_BOOL)
            snprintf(num, sizeof(num), "%s", v != 0 ? "true" : "false");
        else if (s->type == T_ENUM)
            snprintf(num, sizeof(num), "\"%s\"", s->names[(int)v]);
        else
            snprintf(num, sizeof(num), "%.0f", v);
        if (k)
            strncat(buf, ", ", size - strlen(buf) - 1);
        strncat(buf, num, size - strlen(buf) - 1);
    }
    if (s->n > 1)
        strncat(buf, "]", size - strlen(buf) - 1);
}

void config_write_reference(FILE *out)
{
    static const char *const type_names[] = {
        [T_BOOL] = "bool",    [T_INT] = "int",     [T_UINT] = "int",
        [T_DOUBLE] = "float", [T_ENUM] = "string", [T_FILES] = "list of strings",
    };
    struct config def;
    config_defaults(&def);
    fprintf(out, "| setting | type | default | range | description |\n");
    fprintf(out, "|---|---|---|---|---|\n");
    for (int i = 0; i < SETTING_COUNT; i++) {
        const struct setting *s = &settings[i];
        char type[32], range[160], value[160];
        if (s->n > 1)
            snprintf(type, sizeof(type), "%s[%d]", type_names[s->type], s->n);
        else
            snprintf(type, sizeof(type), "%s", type_names[s->type]);
        if (s->type == T_ENUM)
            format_names(s, range, sizeof(range));
        else if (s->type == T_BOOL)
            snprintf(range, sizeof(range), "true, false");
        else if (s->type == T_FILES)
            snprintf(range, sizeof(range), "up to %d", CONFIG_MAX_FILES);
        else
            format_range(s, range, sizeof(range));
        for (int sp = 0; sp < instances(s); sp++) {
            char path[NAME_MAX_LEN];
            instance_path(s, sp, path, sizeof(path));
            format_default(s, sp, &def, value, sizeof(value));
            fprintf(out, "| `%s` | %s | `%s` | %s | %s |\n", path, type, value, range, s->help);
        }
    }
}

bool config_load_overrides(const char *config_path, char **sets, int n_sets, struct config *cfg)
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
