/*
 * Display files: the table of display settings (with the table of one wall) for the settings
 * engine (config_table.c), the names of the enums, and what the engine cannot know: the
 * checks between settings and the values derived from others.
 */
#include "config/display_config.h"

#include <assert.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include "common/log.h"
#include "config/config_table.h"

/* Enums are stored through int pointers. */
static_assert(sizeof(enum display_type) == sizeof(int), "enum size");
static_assert(sizeof(enum display_stereo) == sizeof(int), "enum size");
static_assert(sizeof(enum display_head_source) == sizeof(int), "enum size");

static const char *const type_names[] = {"headless", "desktop", "stereo", "cave",
                                         "hmd",      "orbit",   NULL};
static const char *const stereo_names[] = {"mono", "side-by-side", "anaglyph", "quad-buffer", NULL};
static const char *const head_names[] = {"fixed", "path", "openhmd", NULL};

const char *display_type_name(enum display_type t)
{
    return type_names[t];
}

const char *display_stereo_name(enum display_stereo s)
{
    return stereo_names[s];
}

const char *display_head_source_name(enum display_head_source s)
{
    return head_names[s];
}

/* ------------------------------------------------------------------------------------------ */
/* The tables                                                                                  */

#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))
#define DC(m) offsetof(struct display_config, m)
#define WALL(m) offsetof(struct display_wall, m)

/* clang-format off */
#define NUM(ty, p, at, nn, lo, hi, fl, h, ...)                                               \
    {.path = p, .type = ty, .n = nn, .offset = at, .min = lo, .max = hi, .flags = fl,       \
     .def = {__VA_ARGS__}, .help = h}
#define ENUM(p, at, nm, d, h) \
    {.path = p, .type = T_ENUM, .n = 1, .offset = at, .names = nm, .def = {d}, .help = h}
#define SIZEOF(m) sizeof(((struct display_config *)0)->m)
#define STRING(p, m, d, h)                                                                   \
    {.path = p, .type = T_STRING, .n = 1, .offset = DC(m), .size = SIZEOF(m), .def_text = d, \
     .help = h}

static const struct config_field wall_fields[] = {
    {.path = "name", .type = T_STRING, .n = 1, .offset = WALL(name),
     .size = sizeof(((struct display_wall *)0)->name),
     .flags = F_REQUIRED, .help = "the wall's name, used in image file names"},
    NUM(T_DOUBLE, "lower_left", WALL(lower_left), 3, -1e4, 1e4, F_REQUIRED,
        "lower-left corner of the screen, tracker m", 0),
    NUM(T_DOUBLE, "lower_right", WALL(lower_right), 3, -1e4, 1e4, F_REQUIRED,
        "lower-right corner, tracker m", 0),
    NUM(T_DOUBLE, "upper_left", WALL(upper_left), 3, -1e4, 1e4, F_REQUIRED,
        "upper-left corner, tracker m", 0),
    NUM(T_INT, "monitor", WALL(monitor), 1, -1, 64, 0,
        "fullscreen on this monitor; -1 = a window", -1),
    {.path = "viewport", .type = T_INT, .n = 4, .offset = WALL(viewport), .min = 0,
     .max = 16384, .flags = F_GIVEN, .given = WALL(viewport_set), .shown_default = "none",
     .help = "[x, y, w, h] of the wall in the shared window, w, h >= 1; none: its own window"},
    {.path = "size", .type = T_INT, .n = 2, .offset = WALL(size), .min = 1, .max = 16384,
     .shown_default = "none",
     .help = "image size, pixels; none: render.height and the wall's aspect ratio"},
    {.path = "mode", .type = T_ENUM, .n = 1, .offset = WALL(stereo), .names = stereo_names,
     .flags = F_GIVEN, .given = WALL(stereo_set), .shown_default = "display.mode",
     .help = "stereo mode of this wall"},
};

static const struct config_table wall_table = {
    .fields = wall_fields,
    .count = COUNT(wall_fields),
    .size = sizeof(struct display_wall),
    .elem_name = "wall",
    .list_known = true,
    .whole_vectors = true,
};

/* Without walls in the file: the desktop monitor, 0.52 x 0.32 m, its centre at the origin. */
static const struct display_wall default_walls[] = {
    {.name = "screen", .lower_left = {-0.26, -0.16, 0.0}, .lower_right = {0.26, -0.16, 0.0},
     .upper_left = {-0.26, 0.16, 0.0}, .monitor = -1},
};

static const struct config_field display_fields[] = {
    ENUM("display.type", DC(type), type_names, DISPLAY_TYPE_DESKTOP,
         "backend: headless, desktop, stereo, cave, hmd or orbit"),
    ENUM("display.mode", DC(stereo), stereo_names, DISPLAY_STEREO_MONO,
         "stereo mode of every wall that does not name its own"),
    NUM(T_DOUBLE, "display.eye_separation", DC(eye_separation), 1, 0, 1, 0,
        "distance between the eyes, m (0 = both eyes at the head)", 0.065),
    NUM(T_DOUBLE, "display.near", DC(near_m), 1, 0, 1e3, F_MIN_OPEN,
        "near plane, tracker m: rays start here", 0.01),
    NUM(T_DOUBLE, "display.far", DC(far_m), 1, 0, 1e9, F_MIN_OPEN, "far plane, tracker m",
        1000.0),
    NUM(T_INT, "display.window_size", DC(window_size), 2, 1, 16384, 0,
        "size of the shared window (desktop, stereo, hmd, cave viewports), pixels", 960, 600),
    NUM(T_INT, "display.monitor", DC(monitor), 1, -1, 64, 0,
        "fullscreen monitor of the shared window; -1 = a window", -1),

    ENUM("head.source", DC(head.source), head_names, DISPLAY_HEAD_FIXED,
         "where the head pose comes from: fixed, path or openhmd"),
    NUM(T_DOUBLE, "head.position", DC(head.position), 3, -1e4, 1e4, 0,
        "head position (fixed), or offset added to the device's (openhmd), tracker m",
        0.0, 0.0, 0.6),
    NUM(T_DOUBLE, "head.orientation", DC(head.orientation_deg), 3, -360, 360, 0,
        "heading, pitch, roll of the head, degrees (0: looking along -z)", 0),
    {.path = "head.path", .type = T_PATH, .n = 1, .offset = DC(head.path),
     .size = SIZEOF(head.path),
     .help = "pose file (source = path), relative to the file that names it (from --set: to "
             "the working folder)"},
    STRING("head.device", head.device, "null",
           "OpenHMD device (source = openhmd): product name or \"null\""),

    NUM(T_DOUBLE, "navigation.scale", DC(navigation.scale), 1, 0, 1e6, F_MIN_OPEN,
        "tracker metres per world metre (60 km shown 3 m wide: 5e-5)", 1e-5),
    NUM(T_DOUBLE, "navigation.origin", DC(navigation.origin_km), 3, -1e5, 1e5, 0,
        "world point [x, y, z] (km) that is placed at position", 30.0, 30.0, 0.0),
    NUM(T_DOUBLE, "navigation.position", DC(navigation.position), 3, -1e6, 1e6, 0,
        "where origin lands in the room, tracker m", 0.0, -0.16, -0.45),
    NUM(T_DOUBLE, "navigation.orientation", DC(navigation.orientation_deg), 3, -360, 360, 0,
        "heading, pitch, roll of the world in the room, degrees (0: north along -z)", 0),

    STRING("hmd.device", hmd.device, "null",
           "OpenHMD HMD: product name (or a part of it), or \"null\" for the Null HMD"),
    {.path = "hmd.distortion", .type = T_DOUBLE, .n = 4, .offset = DC(hmd.distortion),
     .min = -10, .max = 10, .flags = F_GIVEN, .given = DC(hmd.distortion_set),
     .def = {0.0, 0.0, 0.0, 1.0}, .shown_default = "the device's",
     .help = "lens polynomial [a, b, c, d] replacing the device's UNIVERSAL_DISTORTION_K"},
    {.path = "hmd.aberration", .type = T_DOUBLE, .n = 3, .offset = DC(hmd.aberration),
     .min = 0.5, .max = 2, .flags = F_GIVEN, .given = DC(hmd.aberration_set),
     .def = {1.0, 1.0, 1.0}, .shown_default = "the device's",
     .help = "chromatic scale [r, g, b] replacing the device's UNIVERSAL_ABERRATION_K"},
    {.path = "hmd.warp", .type = T_BOOL, .n = 1, .offset = DC(hmd.warp), .max = 1, .def = {1},
     .help = "apply the lens distortion pass"},

    {.path = "walls", .type = T_GROUPS, .offset = DC(walls), .count_offset = DC(wall_count),
     .min = 1, .max = DISPLAY_MAX_WALLS, .elems = &wall_table, .def_elems = default_walls,
     .def_count = COUNT(default_walls),
     .help = "the screens, each a group of the walls.[i] settings; a file's list replaces the "
             "default one"},
};
/* clang-format on */

static const struct config_table display_table = {
    .fields = display_fields,
    .count = COUNT(display_fields),
    .size = sizeof(struct display_config),
    .example = "display.eye_separation=0.07",
    .list_known = true,
    .whole_vectors = true,
};

void display_config_defaults(struct display_config *cfg)
{
    config_table_defaults(&display_table, cfg);
}

bool display_config_set(struct display_config *cfg, const char *assignment)
{
    return config_table_set(&display_table, cfg, assignment);
}

bool display_config_has_setting(const char *path)
{
    return config_table_owns(&display_table, path);
}

void display_config_write_reference(FILE *out)
{
    struct display_config def;
    display_config_defaults(&def);
    config_table_write_reference(&display_table, &def, out);
}

/* ------------------------------------------------------------------------------------------ */
/* Checks between settings                                                                     */

/* Logs "WHERE: PATH: expected ...", WHERE being the file and line where the file put AT
 * (TRACE may be NULL), else the config's file, else nothing. */
static bool fail(const struct display_config *cfg, const struct config_trace *trace, const char *at,
                 const char *path, const char *fmt, ...) __attribute__((format(printf, 5, 6)));

static bool fail(const struct display_config *cfg, const struct config_trace *trace, const char *at,
                 const char *path, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    const char *file;
    int line;
    if (config_trace_find(trace, at, &file, &line) && line > 0)
        log_error("%s:%d: %s: expected %s", file, line, path, msg);
    else if (cfg->path[0])
        log_error("%s: %s: expected %s", cfg->path, path, msg);
    else
        log_error("%s: expected %s", path, msg);
    return false;
}

static double dist3(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

static bool check_wall(const struct display_config *cfg, const struct config_trace *trace, int i)
{
    const struct display_wall *w = &cfg->walls[i];
    char at[32], path[64];
    snprintf(at, sizeof(at), "walls.[%d]", i);
    for (int j = 0; j < i; j++) {
        if (strcmp(cfg->walls[j].name, w->name) == 0) {
            snprintf(path, sizeof(path), "%s.name", at);
            return fail(cfg, trace, at, path, "a name no other wall has");
        }
    }
    for (const char *p = w->name; *p; p++) {
        if (!(*p == '-' || *p == '_' || (*p >= '0' && *p <= '9') || (*p >= 'a' && *p <= 'z') ||
              (*p >= 'A' && *p <= 'Z'))) {
            snprintf(path, sizeof(path), "%s.name", at);
            return fail(cfg, trace, at, path, "letters, digits, '-' and '_' (it names files)");
        }
    }
    /* The three corners must span a rectangle: two non-zero, perpendicular edges. */
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = w->lower_right[k] - w->lower_left[k];
        e2[k] = w->upper_left[k] - w->lower_left[k];
    }
    double l1 = dist3(w->lower_right, w->lower_left), l2 = dist3(w->upper_left, w->lower_left);
    double cosang =
        l1 > 0 && l2 > 0 ? (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / (l1 * l2) : 1.0;
    if (l1 < 1e-6 || l2 < 1e-6 || fabs(cosang) > 1e-3) {
        snprintf(path, sizeof(path), "%s.upper_left", at);
        return fail(cfg, trace, at, path,
                    "corners of a rectangle (lower_left -> lower_right perpendicular to "
                    "lower_left -> upper_left, both longer than 1 um)");
    }
    if (w->viewport_set && (w->viewport[2] < 1 || w->viewport[3] < 1)) {
        snprintf(path, sizeof(path), "%s.viewport", at);
        return fail(cfg, trace, at, path, "[x, y, w, h] with w, h >= 1");
    }
    return true;
}

/* display_config_validate, with the lines of a file just read when TRACE is not NULL. */
static bool check(struct display_config *cfg, const struct config_trace *trace)
{
    for (int i = 0; i < cfg->wall_count; i++) {
        struct display_wall *w = &cfg->walls[i];
        if (!w->stereo_set)
            w->stereo = cfg->stereo;
        char at[32];
        const char *file;
        snprintf(at, sizeof(at), "walls.[%d]", i);
        if (trace)
            config_trace_find(trace, at, &file, &w->line);
    }
    if (!(cfg->near_m < cfg->far_m))
        return fail(cfg, trace, "display.far", "display.far",
                    "a far plane beyond display.near (%g m), got %g m", cfg->near_m, cfg->far_m);
    if (cfg->head.source == DISPLAY_HEAD_PATH && cfg->head.path[0] == '\0')
        return fail(cfg, trace, "head.source", "head.path",
                    "a pose file when head.source = \"path\"");
    for (int i = 0; i < cfg->wall_count; i++) {
        if (!check_wall(cfg, trace, i))
            return false;
    }
    return true;
}

bool display_config_validate(struct display_config *cfg)
{
    return check(cfg, NULL);
}

bool display_config_load(const char *path, struct display_config *cfg)
{
    display_config_defaults(cfg);
    if (strlen(path) >= sizeof(cfg->path)) {
        log_error("%s: path too long", path);
        return false;
    }
    snprintf(cfg->path, sizeof(cfg->path), "%s", path);
    struct config_trace trace = {0};
    bool ok = config_table_read(&display_table, path, cfg, &trace) && check(cfg, &trace);
    config_trace_finish(&trace);
    return ok;
}
