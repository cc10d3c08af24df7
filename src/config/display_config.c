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
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "config/config_table.h"

/* Enums are stored through int pointers. */
static_assert(sizeof(enum display_type) == sizeof(int), "enum size");
static_assert(sizeof(enum display_stereo) == sizeof(int), "enum size");
static_assert(sizeof(enum display_head_source) == sizeof(int), "enum size");
static_assert(sizeof(enum display_openxr_binding) == sizeof(int), "enum size");
static_assert(sizeof(enum display_openxr_space) == sizeof(int), "enum size");
static_assert(sizeof(enum display_wand_source) == sizeof(int), "enum size");
static_assert(sizeof(enum display_units) == sizeof(int), "enum size");

static const char *const type_names[] = {"headless", "desktop", "stereo", "cave",
                                         "hmd",      "orbit",   "openxr", NULL};
static const char *const stereo_names[] = {"mono",        "side-by-side", "anaglyph",
                                           "quad-buffer", "passive",      NULL};
static const char *const head_names[] = {"fixed", "path", "openhmd", "dtrack", "vrpn", NULL};
static const char *const wand_names[] = {"none", "openhmd", "dtrack", "vrpn", NULL};
static const char *const unit_names[] = {"auto", "m", "cm", "mm", NULL};
static const char *const openxr_binding_names[] = {"auto", "egl", "xlib", NULL};
static const char *const openxr_space_names[] = {"auto", "stage", "local", NULL};

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

const char *display_openxr_binding_name(enum display_openxr_binding b)
{
    return openxr_binding_names[b];
}

const char *display_openxr_space_name(enum display_openxr_space s)
{
    return openxr_space_names[s];
}

const char *display_wand_source_name(enum display_wand_source s)
{
    return wand_names[s];
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
/* navigation.*: any of them given means the display places the world itself (else a tracked
 * display fits the domain to its room, scene_frame_navigation). */
#define NAV(p, at, nn, lo, hi, fl, h, ...)                                                   \
    {.path = p, .type = T_DOUBLE, .n = nn, .offset = at, .min = lo, .max = hi,              \
     .flags = (fl) | F_GIVEN, .given = DC(navigation.given), .def = {__VA_ARGS__}, .help = h}
#define ENUM(p, at, nm, d, h) \
    {.path = p, .type = T_ENUM, .n = 1, .offset = at, .names = nm, .def = {d}, .help = h}
#define SIZEOF(m) sizeof(((struct display_config *)0)->m)
#define STRING(p, m, d, h)                                                                   \
    {.path = p, .type = T_STRING, .n = 1, .offset = DC(m), .size = SIZEOF(m), .def_text = d, \
     .help = h}

/* Buttons and channels a wand may name (input/tracker.h keeps 64 and 16). */
#define TRACKER_BUTTON_LAST 63
#define TRACKER_AXIS_LAST 15

/* The settings head.* and wand.* share: where a tracked thing comes from, and its
 * calibration into the room. */
#define TRACKING(g, m)                                                                        \
    {.path = g ".address", .type = T_STRING, .n = 1, .offset = DC(m.address),                 \
     .size = SIZEOF(m.address), .shown_default = "none",                                      \
     .help = "source = dtrack: \"PORT\" or \"HOST:PORT\" (a multicast group, or a local "    \
             "address), e.g. \"5000\"; vrpn: \"Device@host[:port]\" (port 3883)"},            \
    NUM(T_INT, g ".sensor", DC(m.sensor), 1, 0, 9999, 0,                                      \
        "DTrack id (DTrack's number minus one) or VRPN sensor", 0),                           \
    ENUM(g ".units", DC(m.units), unit_names, DISPLAY_UNITS_AUTO,                              \
         "unit of the tracker's positions: auto (DTrack mm, VRPN m), m, cm or mm"),           \
    STRING(g ".axes", m.axes, "x y z",                                                        \
           "room x, y, z as tracker axes (a rotation), e.g. \"x z -y\" for a z-up tracker"),  \
    NUM(T_DOUBLE, g ".offset", DC(m.offset), 3, -1e4, 1e4, 0,                                 \
        "where the tracker's origin lies in the room, tracker m", 0),                         \
    NUM(T_DOUBLE, g ".rotation", DC(m.rotation_deg), 3, -360, 360, 0,                         \
        "heading, pitch, roll of the tracker's axes in the room (after axes), degrees", 0)

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
    NUM(T_INT, "rank", WALL(rank), 1, -1, 4095, 0,
        "under mpirun, the rank that draws this wall; -1 = the walls dealt round the ranks in "
        "turn", -1),
    /* Outputs by name or place (a CAVE's projectors). */
    {.path = "output", .type = T_STRING, .n = 1, .offset = WALL(output),
     .size = sizeof(((struct display_wall *)0)->output), .shown_default = "none",
     .help = "fullscreen on the output of this name (xrandr's, e.g. \"DP-1\"; passive: the "
             "left eye's); none: by monitor"},
    {.path = "right_output", .type = T_STRING, .n = 1, .offset = WALL(right_output),
     .size = sizeof(((struct display_wall *)0)->right_output), .shown_default = "none",
     .help = "mode = passive: the right eye's output"},
    {.path = "window", .type = T_INT, .n = 4, .offset = WALL(window), .min = -65536,
     .max = 65536, .flags = F_GIVEN, .given = WALL(window_set), .shown_default = "none",
     .help = "[x, y, w, h] on the desktop: fullscreen on the output exactly there, else a "
             "borderless window there (passive: the left eye's)"},
    {.path = "right_window", .type = T_INT, .n = 4, .offset = WALL(right_window),
     .min = -65536, .max = 65536, .flags = F_GIVEN, .given = WALL(right_window_set),
     .shown_default = "none", .help = "mode = passive: the right eye's [x, y, w, h]"},
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
     .upper_left = {-0.26, 0.16, 0.0}, .monitor = -1, .rank = -1},
};

static const struct config_field display_fields[] = {
    ENUM("display.type", DC(type), type_names, DISPLAY_TYPE_DESKTOP,
         "backend: headless, desktop, stereo, cave, hmd, orbit or openxr"),
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
         "where the head pose comes from: fixed, path, openhmd, dtrack or vrpn"),
    NUM(T_DOUBLE, "head.position", DC(head.position), 3, -1e4, 1e4, 0,
        "head position (fixed; dtrack, vrpn: until the first pose), or offset added to the "
        "device's (openhmd), tracker m",
        0.0, 0.0, 0.6),
    NUM(T_DOUBLE, "head.orientation", DC(head.orientation_deg), 3, -360, 360, 0,
        "heading, pitch, roll of the head, degrees (0: looking along -z)", 0),
    {.path = "head.path", .type = T_PATH, .n = 1, .offset = DC(head.path),
     .size = SIZEOF(head.path),
     .help = "pose file (source = path), relative to the file that names it (from --set: to "
             "the working folder)"},
    STRING("head.device", head.device, "null",
           "OpenHMD device (source = openhmd): product name or \"null\""),
    TRACKING("head", head.tracking),

    NAV("navigation.scale", DC(navigation.scale), 1, 0, 1e6, F_MIN_OPEN,
        "tracker metres per world metre (60 km shown 3 m wide: 5e-5)", 1e-5),
    NAV("navigation.origin", DC(navigation.origin_km), 3, -1e5, 1e5, 0,
        "world point [x, y, z] (km) that is placed at position", 30.0, 30.0, 0.0),
    NAV("navigation.position", DC(navigation.position), 3, -1e6, 1e6, 0,
        "where origin lands in the room, tracker m", 0.0, -0.16, -0.45),
    NAV("navigation.orientation", DC(navigation.orientation_deg), 3, -360, 360, 0,
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

    ENUM("openxr.binding", DC(openxr.binding), openxr_binding_names, DISPLAY_OPENXR_BINDING_AUTO,
         "how the OpenXR runtime shares the GL context: auto (xlib with $DISPLAY set, else "
         "egl), egl (headless, XR_MNDX_egl_enable) or xlib (a GLX window mirroring the left "
         "eye)"),
    ENUM("openxr.space", DC(openxr.space), openxr_space_names, DISPLAY_OPENXR_SPACE_AUTO,
         "the runtime's space that is the room: auto (stage when there is one, else local), "
         "stage (origin on the floor) or local (origin at the starting head, placed at "
         "head.position)"),
    NUM(T_DOUBLE, "openxr.resolution_scale", DC(openxr.resolution_scale), 1, 0.05, 2,
        0, "eye image size as a fraction of the runtime's recommended size", 1.0),
    /* The wand: where it comes from, its calibration, its buttons and stick. */
    ENUM("wand.source", DC(wand.source), wand_names, DISPLAY_WAND_NONE,
         "where the wand comes from: none, openhmd, dtrack or vrpn (--wand NAME: openhmd)"),
    STRING("wand.device", wand.device, "null",
           "OpenHMD controller (source = openhmd): product name or \"null\""),
    TRACKING("wand", wand.tracking),
    {.path = "wand.flystick", .type = T_BOOL, .n = 1, .offset = DC(wand.flystick), .max = 1,
     .def = {1}, .help = "dtrack: a Flystick (6df2: buttons, joystick); false: a body (6d)"},
    {.path = "wand.controls", .type = T_STRING, .n = 1, .offset = DC(wand.controls),
     .size = SIZEOF(wand.controls), .shown_default = "the tracker's",
     .help = "vrpn: \"Device@host[:port]\" of the buttons and analog channels"},
    NUM(T_INT, "wand.buttons", DC(wand.buttons), 4, -1, TRACKER_BUTTON_LAST, 0,
        "device buttons for trigger, grab, menu, reset (-1: none)", 0, 1, 2, 3),
    NUM(T_INT, "wand.joystick", DC(wand.joystick), 2, -1, TRACKER_AXIS_LAST, 0,
        "analog channels for fly (forward > 0) and turn (right > 0); -1: none", 1, 0),
    NUM(T_DOUBLE, "wand.joystick_scale", DC(wand.joystick_scale), 2, -10, 10, 0,
        "factors on fly and turn (-1 reverses one)", 1.0, 1.0),
    NUM(T_DOUBLE, "wand.dead_zone", DC(wand.dead_zone), 1, 0, 0.9, 0,
        "|fly|, |turn| below this read 0", 0.1),

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
    const struct {
        bool set;
        const int *r;
        const char *name;
    } windows[2] = {{w->window_set, w->window, "window"},
                    {w->right_window_set, w->right_window, "right_window"}};
    for (int k = 0; k < 2; k++) {
        if (windows[k].set && (windows[k].r[2] < 1 || windows[k].r[3] < 1)) {
            snprintf(path, sizeof(path), "%s.%s", at, windows[k].name);
            return fail(cfg, trace, at, path, "[x, y, w, h] with w, h >= 1");
        }
    }
    if (w->stereo == DISPLAY_STEREO_PASSIVE && !w->right_output[0] && !w->right_window_set) {
        snprintf(path, sizeof(path), "%s.right_output", at);
        return fail(cfg, trace, at, path,
                    "the right eye's output (right_output or right_window) for mode = "
                    "\"passive\"");
    }
    if (w->stereo == DISPLAY_STEREO_PASSIVE && w->viewport_set) {
        snprintf(path, sizeof(path), "%s.viewport", at);
        return fail(cfg, trace, at, path,
                    "no viewport for mode = \"passive\" (each eye has a window of its own)");
    }
    if (w->stereo != DISPLAY_STEREO_PASSIVE && (w->right_output[0] || w->right_window_set)) {
        snprintf(path, sizeof(path), "%s.mode", at);
        return fail(cfg, trace, at, path,
                    "mode = \"passive\" for a wall with a right eye's output");
    }
    return true;
}

/* ---- tracked heads and wands ---------------------------------------------------------- */

/* "x y z", "x z -y": three signed tracker axes, each once, forming a rotation (no mirror). */
static bool parse_axes(const char *text, int out[3])
{
    int n = 0, used = 0;
    for (const char *p = text; *p;) {
        if (*p == ' ' || *p == ',') {
            p++;
            continue;
        }
        int sign = 1;
        if (*p == '-' || *p == '+')
            sign = *p++ == '-' ? -1 : 1;
        int axis = *p == 'x' ? 1 : *p == 'y' ? 2 : *p == 'z' ? 3 : 0;
        if (!axis || n == 3 || (used & (1 << axis)))
            return false;
        used |= 1 << axis;
        out[n++] = sign * axis;
        p++;
    }
    if (n != 3)
        return false;
    /* The determinant of the signed permutation: its parity times the signs. */
    int swaps = 0;
    int perm[3] = {abs(out[0]), abs(out[1]), abs(out[2])};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            swaps += perm[i] > perm[j];
    int det = (swaps % 2 ? -1 : 1) * (out[0] < 0 ? -1 : 1) * (out[1] < 0 ? -1 : 1) *
              (out[2] < 0 ? -1 : 1);
    return det > 0;
}

static bool parse_port(const char *s, int *port)
{
    char *end;
    long v = strtol(s, &end, 10);
    if (end == s || *end || v < 1 || v > 65535)
        return false;
    *port = (int)v;
    return true;
}

/* Dotted-quad IPv4 (DTrack's host: a multicast group or a local address). */
static bool is_ipv4(const char *s)
{
    for (int part = 0; part < 4; part++) {
        if (part > 0 && *s++ != '.')
            return false;
        int v = 0, digits = 0;
        while (*s >= '0' && *s <= '9' && digits < 4)
            v = 10 * v + (*s++ - '0'), digits++;
        if (digits == 0 || digits > 3 || v > 255)
            return false;
    }
    return *s == '\0';
}

/* "Device@host[:port]" into DEVICE, HOST, PORT (3883 by default). */
static bool parse_vrpn(const char *text, char *device, size_t device_size, char *host,
                       size_t host_size, int *port)
{
    const char *at = strchr(text, '@');
    if (!at || at == text || (size_t)(at - text) >= device_size || strchr(at + 1, '@'))
        return false;
    for (const char *p = text; p < at; p++) {
        if (*p <= ' ' || *p > '~')
            return false;
    }
    snprintf(device, device_size, "%.*s", (int)(at - text), text);
    const char *h = at + 1, *colon = strrchr(h, ':');
    size_t hl = colon ? (size_t)(colon - h) : strlen(h);
    if (hl == 0 || hl >= host_size)
        return false;
    for (size_t i = 0; i < hl; i++) {
        char c = h[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '.' || c == '-' || c == '_'))
            return false;
    }
    snprintf(host, host_size, "%.*s", (int)hl, h);
    *port = 3883;
    return !colon || parse_port(colon + 1, port);
}

static bool check_tracking(const struct display_config *cfg, const struct config_trace *trace,
                           const char *group, bool vrpn, struct display_tracking *t)
{
    char path[32], source[32];
    snprintf(source, sizeof(source), "%s.source", group);
    snprintf(path, sizeof(path), "%s.axes", group);
    if (!parse_axes(t->axes, t->axis_map))
        return fail(cfg, trace, path, path,
                    "three tracker axes that form a rotation, each once (\"x y z\", "
                    "\"x z -y\", \"-z y x\"), got \"%s\"",
                    t->axes);
    snprintf(path, sizeof(path), "%s.address", group);
    const char *at = t->address[0] ? path : source;
    t->host[0] = t->device[0] = '\0';
    if (vrpn) {
        if (!parse_vrpn(t->address, t->device, sizeof(t->device), t->host, sizeof(t->host),
                        &t->port))
            return fail(cfg, trace, at, path,
                        "\"Device@host\" or \"Device@host:port\" when %s = \"vrpn\" "
                        "(e.g. \"Tracker0@localhost\"), got \"%s\"",
                        source, t->address);
        return true;
    }
    const char *colon = strrchr(t->address, ':');
    bool ok;
    if (colon) {
        size_t hl = (size_t)(colon - t->address);
        ok = hl < sizeof(t->host);
        if (ok)
            snprintf(t->host, sizeof(t->host), "%.*s", (int)hl, t->address);
        ok = ok && is_ipv4(t->host) && parse_port(colon + 1, &t->port);
    } else {
        ok = parse_port(t->address, &t->port);
    }
    if (!ok)
        return fail(cfg, trace, at, path,
                    "\"PORT\" or \"ADDRESS:PORT\" (an IPv4 multicast group or local address) "
                    "when %s = \"dtrack\", e.g. \"5000\", got \"%s\"",
                    source, t->address);
    return true;
}

static bool check_trackers(struct display_config *cfg, const struct config_trace *trace)
{
    enum display_head_source hs = cfg->head.source;
    if ((hs == DISPLAY_HEAD_DTRACK || hs == DISPLAY_HEAD_VRPN) &&
        !check_tracking(cfg, trace, "head", hs == DISPLAY_HEAD_VRPN, &cfg->head.tracking))
        return false;
    struct display_wand *w = &cfg->wand;
    if (w->source != DISPLAY_WAND_DTRACK && w->source != DISPLAY_WAND_VRPN)
        return true;
    if (!check_tracking(cfg, trace, "wand", w->source == DISPLAY_WAND_VRPN, &w->tracking))
        return false;
    w->controls_host[0] = w->controls_device[0] = '\0';
    w->controls_port = 0;
    if (w->controls[0] && w->source != DISPLAY_WAND_VRPN)
        return fail(cfg, trace, "wand.controls", "wand.controls",
                    "no controls device unless wand.source = \"vrpn\" (a Flystick brings "
                    "its own buttons)");
    if (w->controls[0] &&
        !parse_vrpn(w->controls, w->controls_device, sizeof(w->controls_device),
                    w->controls_host, sizeof(w->controls_host), &w->controls_port))
        return fail(cfg, trace, "wand.controls", "wand.controls",
                    "\"Device@host\" or \"Device@host:port\", got \"%s\"", w->controls);
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
    if (!check_trackers(cfg, trace))
        return false;
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

int display_config_walls_of_rank(struct display_config *cfg, int rank, int size)
{
    int n = 0;
    if (cfg->room_wall_count == 0)
        cfg->room_wall_count = cfg->wall_count;
    for (int w = 0; w < cfg->wall_count; w++) {
        int owner = cfg->walls[w].rank >= 0 ? cfg->walls[w].rank : w % (size > 0 ? size : 1);
        if (owner == rank)
            cfg->walls[n++] = cfg->walls[w];
    }
    cfg->wall_count = n;
    return n;
}
