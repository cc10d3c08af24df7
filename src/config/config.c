/*
 * Scene files: the table of scene settings and what the engine (config_table.c) cannot know,
 * the checks between settings.  The one table drives the defaults, the file walker, the --set
 * parser and the markdown reference.
 */
#include "config/config.h"

#include <assert.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "common/log.h"
#include "config/config_table.h"

/* Enums are stored through int pointers. */
static_assert(sizeof(enum scene_kind) == sizeof(int), "enum size");
static_assert(sizeof(enum data_format) == sizeof(int), "enum size");
static_assert(sizeof(enum data_vertical) == sizeof(int), "enum size");
static_assert(sizeof(enum lightmap_mode) == sizeof(int), "enum size");
static_assert(sizeof(enum render_precision) == sizeof(int), "enum size");
static_assert(sizeof(enum phase_choice) == sizeof(int), "enum size");
static_assert(sizeof(enum effect_mode) == sizeof(int), "enum size");
static_assert(sizeof(enum coast_resolution) == sizeof(int), "enum size");

/* ------------------------------------------------------------------------------------------ */
/* The table                                                                                   */

static const char *const scene_kind_names[] = {
    "storm", "slab", "sphere", "empty", "voxel", "data", NULL,
};
static const char *const data_format_names[] = {"wrf", "isabel", "extinction", "cm1", "cf",
                                                NULL};
static const char *const data_vertical_names[] = {"native", "uniform", NULL};
static const char *const lightmap_mode_names[] = {"dense", "compressed", NULL};
static const char *const precision_names[] = {"float", "half", NULL}; /* render_precision */
static const char *const lightmap_grid_names[] = {"auto", "upright", NULL}; /* light_grid_kind */
static const char *const effect_mode_names[] = {"auto", "on", "off", NULL};
/* effects.multiple: the modes above, and the diffuse light volume in place of the columns'. */
static const char *const multiple_mode_names[] = {"auto", "on", "off", "volume", NULL};
static const char *const phase_names[] = {"water", "ice", NULL};
static const char *const coast_res_names[] = {"crude", "low", "intermediate", NULL};
static const char *const overlay_when_names[] = {"run", "always", "never", NULL};
static const char *const probe_mode_names[] = {"first_visible", "distance", NULL};

static const char *const layer_field_names[] = {
    "qvapor", "condensate", "temperature", "wind", "theta", "rh", "w", "vorticity", NULL};
static_assert(sizeof(layer_field_names) / sizeof(layer_field_names[0]) ==
                  TRANSFER_FIELD_COUNT + 1,
              "a name per transfer field");
static const char *const layer_mode_names[] = {"emit", "tint", NULL};

/* clang-format off */
#define LOFF(member) offsetof(struct config_layer, member)
static const struct config_field layer_fields[] = {
    {.path = "field", .type = T_ENUM, .n = 1, .offset = LOFF(field), .names = layer_field_names,
     .flags = F_GIVEN, .given = LOFF(has_field),
     .help = "the field shown: qvapor, condensate, temperature, wind (speed), theta (potential "
             "temperature), rh (relative humidity), w (vertical velocity, m/s) or vorticity "
             "(vertical, 1/s); default: the transfer function's"},
    {.path = "transfer", .type = T_TRANSFER, .n = 1, .offset = LOFF(transfer), .flags = F_GIVEN,
     .given = LOFF(has_transfer),
     .help = "its colour map: a transfer function file's name or its group in place "
             "(docs/menu.md); default: the field's default function"},
    {.path = "opacity", .type = T_DOUBLE, .n = 1, .offset = LOFF(opacity), .min = 0, .max = 1e3,
     .def = {1.0},
     .help = "multiplies the layer's extinction (emit) or the strength of its tint"},
    {.path = "mode", .type = T_ENUM, .n = 1, .offset = LOFF(mode), .names = layer_mode_names,
     .def = {0},
     .help = "\"emit\": the layer glows in its colour and hides what is behind it by its "
             "alpha; \"tint\": it colours the clouds' scattered light instead"},
    {.path = "enabled", .type = T_BOOL, .n = 1, .offset = LOFF(enabled), .max = 1, .def = {1},
     .help = "shown (false: kept for the menu)"},
};
static const struct config_table layer_table = {
    .fields = layer_fields,
    .count = (int)(sizeof(layer_fields) / sizeof(layer_fields[0])),
    .size = sizeof(struct config_layer),
    .example = "look.layers.[0].opacity=0.5",
    .elem_name = "layer",
};

static const char *const slice_axis_names[] = {"x", "y", "z", "plane", NULL};
#define SOFF(member) offsetof(struct config_slice, member)
static const struct config_field slice_fields[] = {
    {.path = "field", .type = T_ENUM, .n = 1, .offset = SOFF(field), .names = layer_field_names,
     .flags = F_GIVEN, .given = SOFF(has_field),
     .help = "the field shown (as look.layers.[i].field); default: the transfer function's"},
    {.path = "transfer", .type = T_TRANSFER, .n = 1, .offset = SOFF(transfer), .flags = F_GIVEN,
     .given = SOFF(has_transfer),
     .help = "its colour map (red, green, blue; alpha is not used): a file's name or a group "
             "in place; default: the field's default function"},
    {.path = "axis", .type = T_ENUM, .n = 1, .offset = SOFF(axis), .names = slice_axis_names,
     .def = {2},
     .help = "\"x\", \"y\", \"z\": the plane across that axis at position; \"plane\": "
             "through point, across normal"},
    {.path = "position", .type = T_DOUBLE, .n = 1, .offset = SOFF(position_km), .min = -1e5,
     .max = 1e5, .def = {5.0}, .help = "where the plane crosses its axis, world km"},
    {.path = "point", .type = T_DOUBLE, .n = 3, .offset = SOFF(point_km), .min = -1e5,
     .max = 1e5, .def = {0, 0, 5}, .help = "a point of the plane (axis = \"plane\"), world km"},
    {.path = "normal", .type = T_DOUBLE, .n = 3, .offset = SOFF(normal), .min = -1, .max = 1,
     .def = {0, 0, 1}, .help = "the plane's normal (axis = \"plane\"), not [0, 0, 0]"},
    {.path = "opacity", .type = T_DOUBLE, .n = 1, .offset = SOFF(opacity), .min = 0, .max = 1,
     .def = {1.0}, .help = "1: opaque; less lets the clouds behind show through"},
    {.path = "contour_every", .type = T_DOUBLE, .n = 1, .offset = SOFF(contour_every), .min = 0,
     .max = 1e9, .def = {0.0},
     .help = "contour lines at every multiple of this many field units (0: none)"},
    {.path = "contours", .type = T_DOUBLE, .n = TRANSFER_CONTOUR_MAX, .offset = SOFF(contours),
     .flags = F_UP_TO, .count_offset = SOFF(contour_count), .min = -1e9, .max = 1e9,
     .help = "contour lines at these field values too (up to 6, e.g. [273.15] for the "
             "freezing level on a temperature slice), beside contour_every"},
    {.path = "level", .type = T_INT, .n = 1, .offset = SOFF(level), .min = 0, .max = 9999,
     .def = {0},
     .help = "K >= 1: a horizontal slice following the model's mass level K (1 the lowest; "
             "terrain following on WRF data, the grid's level K on height-level data) in "
             "place of axis, position, point and normal; 0: the plane they give"},
    {.path = "enabled", .type = T_BOOL, .n = 1, .offset = SOFF(enabled), .max = 1, .def = {1},
     .help = "shown (false: kept)"},
};
static const struct config_table slice_table = {
    .fields = slice_fields,
    .count = (int)(sizeof(slice_fields) / sizeof(slice_fields[0])),
    .size = sizeof(struct config_slice),
    .example = "look.slices.[0].position=5.0",
    .elem_name = "slice",
};

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
/* camera.*: any of them given means the scene has a camera (else one framing the data). */
#define CAM(p, m, lo, hi, fl, d, h)                                                          \
    {.path = p, .type = T_DOUBLE, .n = 1, .offset = OFF(m), .min = lo, .max = hi,           \
     .flags = (fl) | F_GIVEN, .given = OFF(camera.given), .def = {d}, .help = h}
#define CAM3(p, m, lo, hi, fl, d0, d1, d2, h)                                                \
    {.path = p, .type = T_DOUBLE, .n = 3, .offset = OFF(m), .min = lo, .max = hi,           \
     .flags = (fl) | F_GIVEN, .given = OFF(camera.given), .def = {d0, d1, d2}, .help = h}
#define EFFECT(p, e, h)                                                                      \
    {.path = p, .type = T_ENUM, .n = 1, .offset = OFF(effects.mode[e]),                      \
     .names = effect_mode_names, .def = {EFFECT_AUTO}, .help = h}
#define OPTICS(p, m, lo, hi, fl, sc, h)                                                      \
    {.path = p, .type = T_DOUBLE, .n = 1, .offset = OFF(m), .stride = sizeof(double),       \
     .min = lo, .max = hi, .flags = F_OPTICS_DEFAULT | (fl), .scale = sc, .help = h}

static const struct config_field settings[] = {
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
         "kind of the input files: WRF NetCDF output, Isabel raw bricks, extinction volumes, "
         "CM1 NetCDF output or CF NetCDF on height levels"),
    {.path = "data.files", .type = T_FILES, .n = 1, .offset = OFF(data.files),
     .count_offset = OFF(data.file_count), .max = CONFIG_MAX_FILES,
     .help = "input files, relative to the config file that names them; a glob pattern "
             "must match a file and is expanded by the reader (WRF steps ordered by Times)"},
    INT("data.step", data.step, 0, 1000000, 0, "time step to show, counted over all files"),
    ENUM("data.vertical", data.vertical, data_vertical_names, DATA_VERTICAL_NATIVE,
         "vertical grid: the model's own levels (stretched; WRF: on the domain's mean column, "
         "CM1 and CF: the file's heights), or uniform levels (data.levels > 0 always means "
         "uniform)"),
    INT("data.levels", data.levels, 0, 4096, 0,
        "regular height levels to resample to; 0 = as many as the model has (uniform grid) or "
        "the model's own levels (data.vertical = native)"),
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
         "physical size [x, y, z] of the Isabel grid, km; z from the lowest level (0.035 km) to the highest"),

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

    CAM3("camera.position", camera.position_km, -1e5, 1e5, 0, 2.0, -14.0, 4.0,
         "eye position [x, y, z], km"),
    CAM3("camera.target", camera.target_km, -1e5, 1e5, 0, 30.0, 30.0, 7.0,
         "point looked at [x, y, z], km"),
    CAM3("camera.up", camera.up, -1e6, 1e6, 0, 0.0, 0.0, 1.0,
         "up direction; any length, not parallel to the view"),
    CAM("camera.fov", camera.fov_deg, 1, 179, F_MIN_OPEN | F_MAX_OPEN, 50.0,
        "vertical field of view, degrees"),
    CAM("camera.near", camera.near_m, 0, 1e6, F_MIN_OPEN, 10.0, "near plane distance, m"),
    CAM("camera.far", camera.far_km, 0, 1e6, F_MIN_OPEN, 2000.0, "far plane distance, km"),

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
    DBL("render.lod", render.lod_pixels, 0, 64, 0, 0.0,
        "level of detail: 0 = off; N > 0 = a ray step is at least N pixels wide where it is "
        "(at most half a voxel's height along the ray), so that cloud whose voxels look "
        "smaller than a pixel is sampled at the picture's pace, not the volume's (fewer "
        "samples, a slightly different picture; docs/architecture.md)"),
    BOOL("render.skip", render.skip, 1,
         "empty-space skipping: rays leap macro cells that hold nothing (the same picture, "
         "faster; false for comparisons)"),
    ENUM("render.precision", render.precision, precision_names, PRECISION_FLOAT,
         "storage of the extinction volume and the dense light map: float, or half (half the "
         "memory, about three digits; extinction beyond 65504 per metre clamps to it)"),

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
    {.path = "effects.multiple", .type = T_ENUM, .n = 1,
     .offset = OFF(effects.mode[EFFECT_MULTIPLE]), .names = multiple_mode_names,
     .def = {EFFECT_AUTO},
     .help = "multiple scattering: diffuse light from a two-stream pass down each light column, "
             "solved as a layer lit at the sun's elevation (docs/lightmap.md); \"volume\": "
             "from a diffusion solve over the whole volume instead, light crossing columns "
             "(costlier to build); auto: the columns, on unless optically thin along the "
             "light"},
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

    ENUM("overlay.when", overlay.when, overlay_when_names, OVERLAY_RUN,
         "where the information overlay shows: \"run\" (windows), \"always\" (renders and "
         "movies too) or \"never\"; in a CAVE or HMD it is a panel in the room"),
    BOOL("overlay.date", overlay.date, 1, "the shown time step's date and time (WRF Times)"),
    BOOL("overlay.legend", overlay.legend, 1,
         "a colour legend for each colour-mapped layer and slice shown (at most 4), with "
         "its field's name and units"),
    BOOL("overlay.north", overlay.north, 1, "a north arrow"),
    BOOL("overlay.box", overlay.box, 1, "the domain's box, with km ticks along its floor"),

    {.path = "look.species.*.enabled", .type = T_BOOL, .n = 1, .offset = OFF(optics.enabled),
     .stride = sizeof(bool), .max = 1, .flags = F_SPECIES, .def = {1},
     .help = "show this species (the same setting as species.<name>.enabled)"},
    {.path = "look.species.*.scale", .type = T_DOUBLE, .n = 1, .offset = OFF(optics.scale),
     .stride = sizeof(double), .min = 0, .max = 1e6, .flags = F_SPECIES, .def = {1.0},
     .help = "multiplies this species' extinction (the same setting as species.<name>.scale)"},
    {.path = "look.species.*.tint", .type = T_DOUBLE, .n = 3, .offset = OFF(look.tint),
     .stride = sizeof(double[3]), .min = 0, .max = 1, .flags = F_SPECIES, .def = {1, 1, 1},
     .help = "the colour this species' scattered light takes, linear RGB (white: none)"},
    {.path = "look.layers", .type = T_GROUPS, .offset = OFF(look.layers),
     .count_offset = OFF(look.layer_count), .min = 0, .max = TRANSFER_LAYER_MAX,
     .flags = F_GIVEN, .given = OFF(look.has_layers), .elems = &layer_table,
     .def_elems = NULL, .def_count = 0,
     .help = "colour-mapped fields composited with the clouds (docs/analysis.md), each a group "
             "of the look.layers.[i] settings, at most 4"},
    {.path = "look.slices", .type = T_GROUPS, .offset = OFF(look.slices),
     .count_offset = OFF(look.slice_count), .min = 0, .max = TRANSFER_SLICE_MAX,
     .elems = &slice_table, .def_elems = NULL, .def_count = 0,
     .help = "planes through a field drawn in the volume (docs/analysis.md), each a group of "
             "the look.slices.[i] settings, at most 4"},
    {.path = "look.transfer", .type = T_TRANSFER, .n = 1, .offset = OFF(look.transfer),
     .flags = F_GIVEN, .given = OFF(look.has_transfer),
     .help = "older files' one transfer function (its file's name, or its group in place; "
             "\"none\": none): read as the first layer, in \"emit\" mode, when look.layers is "
             "not given (the two do not go together)"},
    BOOL("look.show_transfer", look.show_transfer, 1,
         "with look.transfer: whether that layer is on"),

    BOOL("probe.on", probe.on, 0,
         "start with the probe on (anvil run, scripted renders: the values at the wand or "
         "pointer, docs/analysis.md)"),
    ENUM("probe.mode", probe.mode, probe_mode_names, 0,
         "where along the wand's or pointer's ray the probe reads: the first point whose "
         "extinction passes probe.threshold, or probe.distance along it"),
    DBL("probe.threshold", probe.threshold, 0, 1, F_MIN_OPEN, 1e-4,
        "extinction that counts as visible for probe.mode = \"first_visible\", 1/m"),
    DBL("probe.distance", probe.distance_km, 0, 1e5, 0, 50.0,
        "how far along the ray probe.mode = \"distance\" reads, world km"),

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

static const struct config_table scene_table = {
    .fields = settings,
    .count = (int)(sizeof(settings) / sizeof(settings[0])),
    .size = sizeof(struct config),
    .example = "light.elevation=10",
};

void config_defaults(struct config *cfg)
{
    config_table_defaults(&scene_table, cfg);
    optics_params_defaults(&cfg->optics.params);
}

bool config_load(const char *path, struct config *cfg)
{
    config_defaults(cfg);
    if (strlen(path) >= sizeof(cfg->path)) {
        log_error("%s: path too long", path);
        return false;
    }
    snprintf(cfg->path, sizeof(cfg->path), "%s", path);
    return config_table_read(&scene_table, path, cfg, NULL);
}

bool config_set(struct config *cfg, const char *assignment)
{
    return config_table_set(&scene_table, cfg, assignment);
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
    if (cfg->look.has_layers && cfg->look.has_transfer) {
        log_error("%s%slook.transfer: give the layers' functions in look.layers (look.transfer "
                  "is the one function of older files), not both",
                  file, colon);
        return false;
    }
    for (int i = 0; i < cfg->look.layer_count; i++) {
        const struct config_layer *l = &cfg->look.layers[i];
        if (l->has_field && l->has_transfer && (int)l->transfer.field != l->field) {
            log_error("%s%slook.layers.[%d].field: \"%s\" differs from its transfer "
                      "function's field \"%s\"",
                      file, colon, i, transfer_field_name((enum transfer_field)l->field),
                      transfer_field_name(l->transfer.field));
            return false;
        }
    }
    for (int i = 0; i < cfg->look.slice_count; i++) {
        const struct config_slice *sl = &cfg->look.slices[i];
        if (sl->has_field && sl->has_transfer && (int)sl->transfer.field != sl->field) {
            log_error("%s%slook.slices.[%d].field: \"%s\" differs from its transfer "
                      "function's field \"%s\"",
                      file, colon, i, transfer_field_name((enum transfer_field)sl->field),
                      transfer_field_name(sl->transfer.field));
            return false;
        }
        if (sl->axis == 3 && length3(sl->normal) < 1e-9) {
            log_error("%s%slook.slices.[%d].normal: must not be [0, 0, 0]", file, colon, i);
            return false;
        }
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

void config_write_reference(FILE *out)
{
    struct config def;
    config_defaults(&def);
    config_table_write_reference(&scene_table, &def, out);
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
