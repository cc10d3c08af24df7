/*
 * Display files.  A small table per group lists the settings it may hold; the walker checks
 * each setting the file has against it (unknown names, types, ranges) and stores it, so every
 * message can name the file, the line and the setting.
 */
#include "config/display_config.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <libconfig.h>

#include "common/log.h"

static const char *const type_names[] = {"headless", "desktop", "stereo", "cave",
                                         "hmd",      "orbit",   NULL};
static const char *const stereo_names[] = {"mono", "side-by-side", "anaglyph", "quad-buffer",
                                           NULL};
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

static void set3(double *d, double a, double b, double c)
{
    d[0] = a;
    d[1] = b;
    d[2] = c;
}

static void default_wall(struct display_wall *w)
{
    memset(w, 0, sizeof(*w));
    w->monitor = -1;
}

void display_config_defaults(struct display_config *cfg)
{
    memset(cfg, 0, sizeof(*cfg));
    cfg->type = DISPLAY_TYPE_DESKTOP;
    cfg->stereo = DISPLAY_STEREO_MONO;
    cfg->eye_separation = 0.065;
    cfg->near_m = 0.01;
    cfg->far_m = 1000.0;
    cfg->window_size[0] = 960;
    cfg->window_size[1] = 600;
    cfg->monitor = -1;
    cfg->head.source = DISPLAY_HEAD_FIXED;
    set3(cfg->head.position, 0.0, 0.0, 0.6);
    snprintf(cfg->head.device, sizeof(cfg->head.device), "null");
    cfg->navigation.scale = 1e-5;
    set3(cfg->navigation.origin_km, 30.0, 30.0, 0.0);
    set3(cfg->navigation.position, 0.0, -0.16, -0.45);
    snprintf(cfg->hmd.device, sizeof(cfg->hmd.device), "null");
    cfg->hmd.aberration[0] = cfg->hmd.aberration[1] = cfg->hmd.aberration[2] = 1.0;
    cfg->hmd.distortion[3] = 1.0;
    cfg->hmd.warp = true;
    cfg->wall_count = 1;
    struct display_wall *w = &cfg->walls[0];
    default_wall(w);
    snprintf(w->name, sizeof(w->name), "screen");
    set3(w->lower_left, -0.26, -0.16, 0.0);
    set3(w->lower_right, 0.26, -0.16, 0.0);
    set3(w->upper_left, -0.26, 0.16, 0.0);
}

/* ---- the walker ------------------------------------------------------------------------ */

enum kind { K_DOUBLE, K_INT, K_BOOL, K_ENUM, K_STRING, K_PATH };

struct field {
    const char *name;
    enum kind kind;
    int n;          /* numbers in a vector; 1 for a scalar */
    size_t offset;  /* into the struct the group fills */
    double min, max;
    bool min_open;
    const char *const *names; /* K_ENUM */
    size_t cap;               /* K_STRING, K_PATH: buffer size */
    const char *help;
};

struct reader {
    const char *file; /* the config's path, for messages */
    char dir[CONFIG_PATH_MAX];
};

static int line_of(const config_setting_t *s)
{
    return (int)config_setting_source_line(s);
}

/* "walls.[2].lower_left" for a setting inside a group named PREFIX. */
static void setting_path(const char *prefix, const char *name, char *out, size_t cap)
{
    if (prefix && *prefix)
        snprintf(out, cap, "%s.%s", prefix, name);
    else
        snprintf(out, cap, "%s", name);
}

static bool fail(const struct reader *rd, const config_setting_t *s, const char *path,
                 const char *expected)
{
    log_error("%s:%d: %s: expected %s", rd->file, s ? line_of(s) : 0, path, expected);
    return false;
}

static bool number_of(const config_setting_t *s, double *out)
{
    switch (config_setting_type(s)) {
    case CONFIG_TYPE_INT:
        *out = config_setting_get_int(s);
        return true;
    case CONFIG_TYPE_INT64:
        *out = (double)config_setting_get_int64(s);
        return true;
    case CONFIG_TYPE_FLOAT:
        *out = config_setting_get_float(s);
        return true;
    default:
        return false;
    }
}

static void describe_range(const struct field *f, char *out, size_t cap)
{
    const char *what = f->kind == K_INT ? "an integer" : "a number";
    if (f->n > 1)
        snprintf(out, cap, "[%d numbers] each %s in %s%g, %g]", f->n, what,
                 f->min_open ? "(" : "[", f->min, f->max);
    else
        snprintf(out, cap, "%s in %s%g, %g]", what, f->min_open ? "(" : "[", f->min, f->max);
}

static bool read_number(const struct reader *rd, const config_setting_t *s, const char *path,
                        const struct field *f, double *out)
{
    char range[160];
    describe_range(f, range, sizeof(range));
    double v;
    if (!number_of(s, &v))
        return fail(rd, s, path, range);
    if (f->kind == K_INT && config_setting_type(s) == CONFIG_TYPE_FLOAT)
        return fail(rd, s, path, range);
    if (!isfinite(v) || v > f->max || v < f->min || (f->min_open && v == f->min))
        return fail(rd, s, path, range);
    *out = v;
    return true;
}

static bool read_field(const struct reader *rd, const config_setting_t *s, const char *path,
                       const struct field *f, void *base)
{
    char *dst = (char *)base + f->offset;
    switch (f->kind) {
    case K_BOOL:
        if (config_setting_type(s) != CONFIG_TYPE_BOOL)
            return fail(rd, s, path, "true or false");
        *(bool *)dst = config_setting_get_bool(s);
        return true;
    case K_ENUM:
    case K_STRING:
    case K_PATH: {
        char expect[256] = "a string";
        if (f->kind == K_ENUM) {
            size_t len = (size_t)snprintf(expect, sizeof(expect), "one of");
            for (int i = 0; f->names[i]; i++)
                len += (size_t)snprintf(expect + len, sizeof(expect) - len, "%s \"%s\"",
                                        i ? "," : "", f->names[i]);
        }
        if (config_setting_type(s) != CONFIG_TYPE_STRING)
            return fail(rd, s, path, expect);
        const char *v = config_setting_get_string(s);
        if (f->kind == K_ENUM) {
            for (int i = 0; f->names[i]; i++) {
                if (strcmp(v, f->names[i]) == 0) {
                    *(int *)dst = i;
                    return true;
                }
            }
            return fail(rd, s, path, expect);
        }
        if (f->kind == K_PATH && v[0] != '/' && v[0] != '\0') {
            if ((size_t)snprintf(dst, f->cap, "%s/%s", rd->dir, v) >= f->cap)
                return fail(rd, s, path, "a shorter path");
            return true;
        }
        if (strlen(v) >= f->cap || (f->kind == K_STRING && v[0] == '\0')) {
            char what[64];
            snprintf(what, sizeof(what), "a string of 1 to %zu characters", f->cap - 1);
            return fail(rd, s, path, what);
        }
        snprintf(dst, f->cap, "%s", v);
        return true;
    }
    case K_DOUBLE:
    case K_INT:
        break;
    }
    double v[8];
    if (f->n == 1) {
        if (!read_number(rd, s, path, f, &v[0]))
            return false;
    } else {
        char range[160];
        describe_range(f, range, sizeof(range));
        if (!config_setting_is_array(s) && !config_setting_is_list(s))
            return fail(rd, s, path, range);
        if (config_setting_length(s) != f->n)
            return fail(rd, s, path, range);
        for (int i = 0; i < f->n; i++) {
            const config_setting_t *e = config_setting_get_elem(s, (unsigned)i);
            if (!read_number(rd, e, path, f, &v[i]))
                return false;
        }
    }
    for (int i = 0; i < f->n; i++) {
        if (f->kind == K_INT)
            ((int *)dst)[i] = (int)v[i];
        else
            ((double *)dst)[i] = v[i];
    }
    return true;
}

/* Reads every member of GROUP through FIELDS into BASE.  SEEN (may be NULL) receives a flag
 * per field that was present. */
static bool read_group(const struct reader *rd, const config_setting_t *group, const char *prefix,
                       const struct field *fields, int n_fields, void *base, bool *seen)
{
    char path[256];
    if (!config_setting_is_group(group))
        return fail(rd, group, prefix, "a group { ... }");
    int count = config_setting_length(group);
    for (int i = 0; i < count; i++) {
        const config_setting_t *s = config_setting_get_elem(group, (unsigned)i);
        const char *name = config_setting_name(s);
        setting_path(prefix, name ? name : "?", path, sizeof(path));
        int k = 0;
        while (k < n_fields && strcmp(fields[k].name, name ? name : "") != 0)
            k++;
        if (k == n_fields) {
            char expect[512];
            size_t len = (size_t)snprintf(expect, sizeof(expect), "a known setting (one of");
            for (int j = 0; j < n_fields; j++)
                len += (size_t)snprintf(expect + len, sizeof(expect) - len, " %s",
                                        fields[j].name);
            snprintf(expect + len, sizeof(expect) - len, ")");
            return fail(rd, s, path, expect);
        }
        if (!read_field(rd, s, path, &fields[k], base))
            return false;
        if (seen)
            seen[k] = true;
    }
    return true;
}

#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))
#define DC(m) offsetof(struct display_config, m)
#define WALL(m) offsetof(struct display_wall, m)

/* clang-format off */
static const struct field display_fields[] = {
    {"type", K_ENUM, 1, DC(type), .names = type_names,
     .help = "backend: headless, desktop, stereo, cave, hmd or orbit"},
    {"mode", K_ENUM, 1, DC(stereo), .names = stereo_names,
     .help = "stereo mode of every wall that does not name its own"},
    {"eye_separation", K_DOUBLE, 1, DC(eye_separation), 0, 1,
     .help = "distance between the eyes, m (0 = both eyes at the head)"},
    {"near", K_DOUBLE, 1, DC(near_m), 0, 1e3, true,
     .help = "near plane, tracker m: rays start here"},
    {"far", K_DOUBLE, 1, DC(far_m), 0, 1e9, true, .help = "far plane, tracker m"},
    {"window_size", K_INT, 2, DC(window_size), 1, 16384,
     .help = "size of the shared window (desktop, stereo, hmd, cave viewports), pixels"},
    {"monitor", K_INT, 1, DC(monitor), -1, 64,
     .help = "fullscreen monitor of the shared window; -1 = a window"},
};

static const struct field head_fields[] = {
    {"source", K_ENUM, 1, DC(head.source), .names = head_names,
     .help = "where the head pose comes from: fixed, path or openhmd"},
    {"position", K_DOUBLE, 3, DC(head.position), -1e4, 1e4,
     .help = "head position (fixed), or offset added to the device's (openhmd), tracker m"},
    {"orientation", K_DOUBLE, 3, DC(head.orientation_deg), -360, 360,
     .help = "heading, pitch, roll of the head, degrees (0: looking along -z)"},
    {"path", K_PATH, 1, DC(head.path), .cap = CONFIG_PATH_MAX,
     .help = "pose file (source = path), relative to this file"},
    {"device", K_STRING, 1, DC(head.device), .cap = 128,
     .help = "OpenHMD device (source = openhmd): product name or \"null\""},
};

static const struct field navigation_fields[] = {
    {"scale", K_DOUBLE, 1, DC(navigation.scale), 0, 1e6, true,
     .help = "tracker metres per world metre (60 km shown 3 m wide: 5e-5)"},
    {"origin", K_DOUBLE, 3, DC(navigation.origin_km), -1e5, 1e5,
     .help = "world point [x, y, z] (km) that is placed at position"},
    {"position", K_DOUBLE, 3, DC(navigation.position), -1e6, 1e6,
     .help = "where origin lands in the room, tracker m"},
    {"orientation", K_DOUBLE, 3, DC(navigation.orientation_deg), -360, 360,
     .help = "heading, pitch, roll of the world in the room, degrees (0: north along -z)"},
};

static const struct field hmd_fields[] = {
    {"device", K_STRING, 1, DC(hmd.device), .cap = 128,
     .help = "OpenHMD HMD: product name (or a part of it), or \"null\" for the Null HMD"},
    {"distortion", K_DOUBLE, 4, DC(hmd.distortion), -10, 10,
     .help = "lens polynomial [a, b, c, d] replacing the device's UNIVERSAL_DISTORTION_K"},
    {"aberration", K_DOUBLE, 3, DC(hmd.aberration), 0.5, 2,
     .help = "chromatic scale [r, g, b] replacing the device's UNIVERSAL_ABERRATION_K"},
    {"warp", K_BOOL, 1, DC(hmd.warp), .help = "apply the lens distortion pass"},
};

static const struct field wall_fields[] = {
    {"name", K_STRING, 1, WALL(name), .cap = DISPLAY_NAME_MAX,
     .help = "the wall's name, used in image file names"},
    {"lower_left", K_DOUBLE, 3, WALL(lower_left), -1e4, 1e4,
     .help = "lower-left corner of the screen, tracker m"},
    {"lower_right", K_DOUBLE, 3, WALL(lower_right), -1e4, 1e4,
     .help = "lower-right corner, tracker m"},
    {"upper_left", K_DOUBLE, 3, WALL(upper_left), -1e4, 1e4,
     .help = "upper-left corner, tracker m"},
    {"monitor", K_INT, 1, WALL(monitor), -1, 64,
     .help = "fullscreen on this monitor; -1 = a window"},
    {"viewport", K_INT, 4, WALL(viewport), 0, 16384,
     .help = "[x, y, w, h] of the wall in the shared window; absent: its own window"},
    {"size", K_INT, 2, WALL(size), 1, 16384,
     .help = "image size, pixels; absent: render.height and the wall's aspect ratio"},
    {"mode", K_ENUM, 1, WALL(stereo), .names = stereo_names,
     .help = "stereo mode of this wall (default display.mode)"},
};
/* clang-format on */

struct group {
    const char *name;
    const struct field *fields;
    int n;
};

static const struct group groups[] = {
    {"display", display_fields, COUNT(display_fields)},
    {"head", head_fields, COUNT(head_fields)},
    {"navigation", navigation_fields, COUNT(navigation_fields)},
    {"hmd", hmd_fields, COUNT(hmd_fields)},
};

static double dist3(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

static bool read_walls(const struct reader *rd, const config_setting_t *list,
                       struct display_config *cfg)
{
    if (!config_setting_is_list(list))
        return fail(rd, list, "walls", "a list ( { ... }, { ... } ) of walls");
    int count = config_setting_length(list);
    if (count < 1 || count > DISPLAY_MAX_WALLS) {
        char what[64];
        snprintf(what, sizeof(what), "1 to %d walls", DISPLAY_MAX_WALLS);
        return fail(rd, list, "walls", what);
    }
    for (int i = 0; i < count; i++) {
        const config_setting_t *g = config_setting_get_elem(list, (unsigned)i);
        struct display_wall *w = &cfg->walls[i];
        default_wall(w);
        w->stereo = cfg->stereo;
        w->line = line_of(g);
        char prefix[32];
        snprintf(prefix, sizeof(prefix), "walls.[%d]", i);
        bool seen[COUNT(wall_fields)] = {false};
        if (!read_group(rd, g, prefix, wall_fields, COUNT(wall_fields), w, seen))
            return false;
        const char *required[] = {"name", "lower_left", "lower_right", "upper_left"};
        for (int k = 0; k < 4; k++) {
            if (!seen[k]) {
                char path[64], what[64];
                snprintf(path, sizeof(path), "%s.%s", prefix, required[k]);
                snprintf(what, sizeof(what), "a setting \"%s\" in every wall", required[k]);
                return fail(rd, g, path, what);
            }
        }
        for (int j = 0; j < i; j++) {
            if (strcmp(cfg->walls[j].name, w->name) == 0) {
                char path[64];
                snprintf(path, sizeof(path), "%s.name", prefix);
                return fail(rd, g, path, "a name no other wall has");
            }
        }
        for (const char *p = w->name; *p; p++) {
            if (!(*p == '-' || *p == '_' || (*p >= '0' && *p <= '9') ||
                  (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z'))) {
                char path[64];
                snprintf(path, sizeof(path), "%s.name", prefix);
                return fail(rd, g, path, "letters, digits, '-' and '_' (it names files)");
            }
        }
        /* The three corners must span a rectangle: two non-zero, perpendicular edges. */
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = w->lower_right[k] - w->lower_left[k];
            e2[k] = w->upper_left[k] - w->lower_left[k];
        }
        double l1 = dist3(w->lower_right, w->lower_left), l2 = dist3(w->upper_left, w->lower_left);
        double cosang = l1 > 0 && l2 > 0 ? (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) /
                                               (l1 * l2)
                                         : 1.0;
        if (l1 < 1e-6 || l2 < 1e-6 || fabs(cosang) > 1e-3) {
            char path[64];
            snprintf(path, sizeof(path), "%s.upper_left", prefix);
            return fail(rd, g, path,
                        "corners of a rectangle (lower_left -> lower_right perpendicular to "
                        "lower_left -> upper_left, both longer than 1 um)");
        }
        if (!seen[5])
            w->viewport[2] = w->viewport[3] = 0;
        else if (w->viewport[2] < 1 || w->viewport[3] < 1) {
            char path[64];
            snprintf(path, sizeof(path), "%s.viewport", prefix);
            return fail(rd, g, path, "[x, y, w, h] with w, h >= 1");
        }
    }
    cfg->wall_count = count;
    return true;
}

bool display_config_load(const char *path, struct display_config *cfg)
{
    display_config_defaults(cfg);
    snprintf(cfg->path, sizeof(cfg->path), "%s", path);
    struct reader rd = {.file = path};
    snprintf(rd.dir, sizeof(rd.dir), "%s", path);
    char *slash = strrchr(rd.dir, '/');
    if (slash)
        *slash = '\0';
    else
        snprintf(rd.dir, sizeof(rd.dir), ".");

    FILE *probe = fopen(path, "r");
    if (!probe) {
        log_error("%s: cannot open the display config: %s", path, strerror(errno));
        return false;
    }
    fclose(probe);
    config_t lc;
    config_init(&lc);
    bool ok = false;
    if (!config_read_file(&lc, path)) {
        const char *file = config_error_file(&lc);
        log_error("%s:%d: %s", file ? file : path, config_error_line(&lc),
                  config_error_text(&lc));
        goto done;
    }
    const config_setting_t *root = config_root_setting(&lc);
    /* display.mode first: walls default to it whatever the order in the file. */
    const config_setting_t *disp = config_setting_get_member(root, "display");
    if (disp && !read_group(&rd, disp, "display", display_fields, COUNT(display_fields), cfg,
                            NULL))
        goto done;
    cfg->walls[0].stereo = cfg->stereo;
    int count = config_setting_length(root);
    bool have_walls = false;
    for (int i = 0; i < count; i++) {
        const config_setting_t *s = config_setting_get_elem(root, (unsigned)i);
        const char *name = config_setting_name(s);
        if (strcmp(name, "walls") == 0) {
            if (!read_walls(&rd, s, cfg))
                goto done;
            have_walls = true;
            continue;
        }
        int g = 0;
        while (g < COUNT(groups) && strcmp(groups[g].name, name) != 0)
            g++;
        if (g == COUNT(groups)) {
            fail(&rd, s, name, "a known group (display, head, navigation, hmd, walls)");
            goto done;
        }
        if (g == 0)
            continue;
        if (!read_group(&rd, s, name, groups[g].fields, groups[g].n, cfg, NULL))
            goto done;
    }
    (void)have_walls;
    cfg->hmd.distortion_set = config_lookup(&lc, "hmd.distortion") != NULL;
    cfg->hmd.aberration_set = config_lookup(&lc, "hmd.aberration") != NULL;
    if (cfg->head.source == DISPLAY_HEAD_PATH && cfg->head.path[0] == '\0') {
        const config_setting_t *h = config_setting_get_member(root, "head");
        fail(&rd, h, "head.path", "a pose file when head.source = \"path\"");
        goto done;
    }
    ok = true;
done:
    config_destroy(&lc);
    return ok;
}

void display_config_write_reference(FILE *out)
{
    fprintf(out, "| setting | type | meaning |\n| --- | --- | --- |\n");
    for (int g = 0; g < COUNT(groups) + 1; g++) {
        const char *gname = g < COUNT(groups) ? groups[g].name : "walls.[i]";
        const struct field *fields = g < COUNT(groups) ? groups[g].fields : wall_fields;
        int n = g < COUNT(groups) ? groups[g].n : COUNT(wall_fields);
        for (int i = 0; i < n; i++) {
            const struct field *f = &fields[i];
            char type[160];
            switch (f->kind) {
            case K_DOUBLE:
            case K_INT:
                if (f->n > 1)
                    snprintf(type, sizeof(type), "%d %s in %s%g, %g]", f->n,
                             f->kind == K_INT ? "integers" : "numbers",
                             f->min_open ? "(" : "[", f->min, f->max);
                else
                    snprintf(type, sizeof(type), "%s in %s%g, %g]",
                             f->kind == K_INT ? "integer" : "number", f->min_open ? "(" : "[",
                             f->min, f->max);
                break;
            case K_BOOL:
                snprintf(type, sizeof(type), "bool");
                break;
            case K_ENUM: {
                size_t len = 0;
                for (int k = 0; f->names[k]; k++)
                    len += (size_t)snprintf(type + len, sizeof(type) - len, "%s`%s`",
                                            k ? " \\| " : "", f->names[k]);
                break;
            }
            case K_STRING:
                snprintf(type, sizeof(type), "string");
                break;
            case K_PATH:
                snprintf(type, sizeof(type), "path");
                break;
            }
            fprintf(out, "| `%s.%s` | %s | %s |\n", gname, f->name, type, f->help);
        }
    }
}
