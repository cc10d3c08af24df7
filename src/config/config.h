/*
 * config: scene files (libconfig syntax) and command-line overrides to one plain struct.
 * This is the only part that includes libconfig.h.  Every setting has a default, a type and
 * a valid range in one table (config.c) that the settings engine shared with display files
 * (config_table.c) reads; every error names the file, the line, the setting and what was
 * expected.
 *
 * Units in files: lengths of the scene in km (positions, extents), ray steps in metres,
 * angles in degrees.  The struct below stores what the file says, in those units.
 *
 * Must not know: GL, windows, data files, the session; the struct is plain data.
 */
#ifndef ANVIL_CONFIG_H
#define ANVIL_CONFIG_H

#include <stdbool.h>
#include <stdio.h>

#include "optics/optics.h"
#include "optics/transfer.h"

#define CONFIG_PATH_MAX 1024
#define CONFIG_MAX_FILES 64

enum scene_kind {
    SCENE_STORM,  /* procedural storm with all five species */
    SCENE_SLAB,   /* homogeneous box filling the volume; tau measured vertically */
    SCENE_SPHERE, /* homogeneous ball; tau measured along a diameter */
    SCENE_EMPTY,  /* nothing */
    SCENE_VOXEL,  /* one voxel at the centre; tau measured vertically through it */
    SCENE_DATA,   /* from data.* (WRF, CM1, CF, Isabel bricks, extinction files) */
};

enum data_format { DATA_WRF, DATA_ISABEL, DATA_EXTINCTION, DATA_CM1, DATA_CF };
enum data_vertical { DATA_VERTICAL_NATIVE, DATA_VERTICAL_UNIFORM };

/* How the light map is stored; whether there is one at all is effects.shadows. */
enum lightmap_mode { LIGHTMAP_DENSE, LIGHTMAP_COMPRESSED };
enum render_precision { PRECISION_FLOAT, PRECISION_HALF };

/* What the renderer simulates (docs/effects.md).  Each is on, off, or decided from the scene
 * (app/effects.h); an effect that is off is compiled out of the shaders. */
enum effect {
    EFFECT_SHADOWS,       /* effects.shadows: self-shadowing through the deep light map */
    EFFECT_FORWARD,       /* effects.forward: central forward scattering in the light map */
    EFFECT_PERIPHERAL,    /* effects.peripheral: peripheral forward scattering */
    EFFECT_MULTIPLE,      /* effects.multiple: multiple scattering, the light map's diffuse
                             two-stream term */
    EFFECT_LATERAL,       /* effects.lateral: diffuse light escapes through narrow clouds'
                             sides (needs multiple) */
    EFFECT_PHASE,         /* effects.phase: per-species phase (off: one phase for all) */
    EFFECT_GROUND_SHADOW, /* effects.ground_shadow: the ground reads the light map */
    EFFECT_DETAIL,        /* effects.detail: procedural detail (docs/terrain.md) */
    EFFECT_TEMPORAL,      /* effects.temporal: interpolation between time steps (not yet) */
    EFFECT_DISTORTION,    /* effects.distortion: HMD lens pre-distortion */
    EFFECT_COUNT
};

/* EFFECT_VOLUME: effects.multiple only, the 3-D diffuse light volume (docs/lightmap.md). */
enum effect_mode { EFFECT_AUTO, EFFECT_ON, EFFECT_OFF, EFFECT_VOLUME };

enum phase_choice { PHASE_WATER, PHASE_ICE };

struct config_scene {
    enum scene_kind kind;       /* scene.kind: "storm" | "slab" | "sphere" | "empty" | "voxel" | "data" */
    int size[3];                /* scene.size: voxels [nx, ny, nz] of synthetic scenes */
    double extent_km[3];        /* scene.extent: physical size of synthetic scenes, km */
    double tau;                 /* scene.tau: optical depth of the test scenes */
    enum phase_choice phase;    /* scene.phase: phase of the test scenes' medium */
    unsigned seed;              /* scene.seed: procedural storm seed */
    double time;                /* scene.time: storm evolution time in [0, 1] */
    double height_exaggeration; /* scene.height_exaggeration: z scale of volume, light map,
                                   terrain and map (Nes Fig. 5.18) */
};

struct config_data {
    enum data_format format;                  /* data.format */
    char files[CONFIG_MAX_FILES][CONFIG_PATH_MAX]; /* data.files (resolved against the config) */
    int file_count;
    int step;                                 /* data.step: time step index to show */
    enum data_vertical vertical;              /* data.vertical: native or uniform levels */
    int levels;                               /* data.levels: regular height levels */
    double top_km;                            /* data.top: top of the height grid, km (0 = auto) */
    int stride[3];                            /* data.stride: subsampling per axis */
    int crop[6];                              /* data.crop: [x0, x1, y0, y1, z0, z1], -1 = all */
    double memory_mb;                         /* data.memory: budget for one step, MiB */
    double cache_memory_mb;                   /* data.cache_memory: time series cache, MiB */
    int prefetch;                             /* data.prefetch: steps loaded ahead and behind */
    int isabel_size[3];                       /* data.isabel_size */
    double isabel_extent_km[3];               /* data.isabel_extent */
};

struct config_optics {
    struct optics_params params; /* optics.radius_mm.<species>, optics.density.<species>,
                                    optics.g_water, optics.g_ice, optics.eye_peak */
    bool enabled[SPECIES_COUNT]; /* species.<name>.enabled */
    double scale[SPECIES_COUNT]; /* species.<name>.scale */
};

struct config_light {
    double azimuth_deg;   /* light.azimuth: sun azimuth, degrees clockwise from north */
    double elevation_deg; /* light.elevation: sun elevation above the horizon, degrees */
    double intensity;     /* light.intensity: sun radiance scale */
    double color[3];      /* light.color: linear RGB */
    bool atmosphere;      /* light.atmosphere: redden the sun near the horizon */
};

struct config_camera {
    double position_km[3]; /* camera.position */
    double target_km[3];   /* camera.target */
    double up[3];          /* camera.up */
    double fov_deg;        /* camera.fov: vertical field of view */
    double near_m;         /* camera.near: near plane distance, metres */
    double far_km;         /* camera.far */
    bool given;            /* a camera.* setting was given (file or --set); else a scene of
                              data gets a camera framing its domain (scene_frame_camera) */
};

struct config_render {
    int width, height;     /* render.width, render.height */
    double step_m;         /* render.step: ray step in metres; 0 = half the voxel crossing along each ray */
    double exposure;       /* render.exposure: multiplies radiance before tone mapping */
    double sky[3];         /* render.sky: background radiance, linear RGB */
    double ground[3];      /* render.ground: ground albedo, linear RGB */
    bool ground_on;        /* render.ground_on: draw the ground plane */
    double termination;    /* render.termination: stop a ray below this transmittance */
    double lod_pixels;     /* render.lod: a step at least this many pixels wide; 0 = off */
    bool skip;             /* render.skip: empty-space skipping (macro cells) */
    enum render_precision precision; /* render.precision: float | half storage */
};

struct config_lightmap {
    enum lightmap_mode mode; /* lightmap.mode: "dense" | "compressed" */
    int resolution[3];       /* lightmap.resolution: [across x, across y, along the light] */
    double epsilon;          /* lightmap.epsilon: compression error bound */
    double forward_angle_deg;/* lightmap.forward_angle: theta */
    int grid;                /* lightmap.grid: enum light_grid_kind (auto, upright) */
};

enum coast_resolution { COAST_CRUDE, COAST_LOW, COAST_INTERMEDIATE };

/* The storm in its place (docs/terrain.md). */
struct config_map {
    bool terrain;                   /* map.terrain: ground mesh from HGT / LANDMASK / LU_INDEX */
    bool coastlines;                /* map.coastlines: GSHHG shorelines */
    enum coast_resolution coast_res; /* map.coastline_resolution */
    bool graticule;                 /* map.graticule: latitude/longitude lines */
    double graticule_step_deg;      /* map.graticule_step: degrees; 0 = automatic */
    bool labels;                    /* map.labels: label the graticule lines */
    double margin_km;               /* map.margin: how far the map reaches beyond the data */
    double offset_km[2];            /* map.offset: moves the data east/north on the map */
    bool use_origin;                /* map.use_origin: place data without XLAT/XLONG ... */
    double origin_deg[2];           /* map.origin: ... with its frame origin at [lat, lon] */
};

/* Procedural detail (Riley §4.5); whether it is on is effects.detail. */
struct config_detail {
    double amount[SPECIES_COUNT]; /* detail.<species>: share of the field modulated, [0, 1] */
    double scale_km;              /* detail.scale: wavelength of the coarsest octave, km */
    unsigned seed;                /* detail.seed */
};

struct config_playback {
    double speed; /* playback.speed: time steps per second */
    bool loop;    /* playback.loop: after the last step comes the first */
};

/* The information overlay (docs/user-guide.md): where it shows and what it holds. */
enum overlay_when { OVERLAY_RUN, OVERLAY_ALWAYS, OVERLAY_NEVER };

struct config_overlay {
    enum overlay_when when; /* overlay.when: "run" | "always" (renders and movies too) | "never" */
    bool date;              /* overlay.date: the shown step's date and time */
    bool legend;            /* overlay.legend: colour legends of colour-mapped fields */
    bool north;             /* overlay.north: a north arrow */
    bool box;               /* overlay.box: the domain's box with km ticks */
};

/* How the volume looks (docs/analysis.md, "Look blocks"): what the menu's Fields and Transfer
 * pages change, so that a scene file renders what a menu session showed.  The species'
 * enabled and scale are config_optics' (look.species.<name>.enabled and .scale are the same
 * settings as species.<name>.enabled and .scale). */
/* One colour-mapped layer, look.layers.[i] (optics/transfer.h, struct transfer_layer). */
struct config_layer {
    int field;                         /* .field: enum transfer_field */
    bool has_field;                    /* .field was given (else the transfer's field) */
    struct transfer_function transfer; /* .transfer: a file name or a group in place */
    bool has_transfer;                 /* .transfer was given (else the field's default) */
    double opacity;                    /* .opacity */
    int mode;                          /* .mode: enum transfer_layer_mode */
    bool enabled;                      /* .enabled */
};

/* One slice, look.slices.[i] (optics/transfer.h, struct transfer_slice). */
struct config_slice {
    int field;                         /* .field: enum transfer_field */
    bool has_field;
    struct transfer_function transfer; /* .transfer */
    bool has_transfer;
    int axis;                          /* .axis: 0 x, 1 y, 2 z, 3 "plane" (point, normal) */
    double position_km;                /* .position: along the axis, world km */
    double point_km[3];                /* .point (axis = "plane"), world km */
    double normal[3];                  /* .normal (axis = "plane") */
    double opacity;                    /* .opacity */
    double contour_every;              /* .contour_every: field units, 0 none */
    double contours[TRANSFER_CONTOUR_MAX]; /* .contours: lines at these values ... */
    int contour_count;                 /* ... this many */
    int level;                         /* .level: the model level followed (1 the lowest), 0 none */
    bool enabled;                      /* .enabled */
};

struct config_look {
    double tint[SPECIES_COUNT][3]; /* look.species.<name>.tint: linear RGB in [0, 1] */
    bool has_transfer;             /* look.transfer was given */
    struct transfer_function transfer; /* look.transfer: layer 0 of files without look.layers */
    bool show_transfer;            /* look.show_transfer: whether that layer is on */
    struct config_layer layers[TRANSFER_LAYER_MAX]; /* look.layers */
    int layer_count;
    bool has_layers;               /* look.layers was given */
    struct config_slice slices[TRANSFER_SLICE_MAX]; /* look.slices */
    int slice_count;
};

/* The probe (docs/analysis.md): how it starts; the menu changes it while running. */
struct config_probe {
    bool on;            /* probe.on */
    int mode;           /* probe.mode: "first_visible" | "distance" (enum probe_mode) */
    double threshold;   /* probe.threshold: extinction that counts as visible, 1/m */
    double distance_km; /* probe.distance: along the wand or pointer, world km */
};

struct config_effects {
    enum effect_mode mode[EFFECT_COUNT]; /* effects.<name>: "auto" | "on" | "off"; multiple
                                            also "volume" */
};

struct config {
    char path[CONFIG_PATH_MAX]; /* the file it came from ("" for built-in defaults) */
    struct config_scene scene;
    struct config_data data;
    struct config_optics optics;
    struct config_light light;
    struct config_camera camera;
    struct config_render render;
    struct config_lightmap lightmap;
    struct config_effects effects;
    struct config_playback playback;
    struct config_map map;
    struct config_detail detail;
    struct config_overlay overlay;
    struct config_look look;
    struct config_probe probe;
};

/* Fills every setting with its default: the built-in procedural storm seen from the south-west
 * with the sun in the south-south-west, behind the camera. */
void config_defaults(struct config *cfg);

/* Reads PATH (with @include resolved relative to the including file) on top of the
 * defaults.  On failure logs one message "FILE:LINE: SETTING: expected ..." and returns
 * false; CFG then holds defaults plus whatever was read. */
bool config_load(const char *path, struct config *cfg);

/* Applies one "path=value" override (the --set option), e.g. "light.elevation=10.0",
 * "scene.size=[64,64,32]", "lightmap.mode=dense".  Same types and ranges as the file.  On
 * failure logs "--set PATH: expected ..." and returns false. */
bool config_set(struct config *cfg, const char *assignment);

/* Loads CONFIG_PATH (or the defaults alone when NULL), applies the N_SETS --set overrides SETS
 * and validates: config_load, config_set, config_validate in turn.  False (logged) on the first
 * problem. */
bool config_load_overrides(const char *config_path, char **sets, int n_sets, struct config *cfg);

/* Checks cross-setting constraints (e.g. camera position differs from target; data.files
 * present when scene.kind = "data").  Logs and returns false on the first problem. */
bool config_validate(const struct config *cfg);

/* Writes the whole table of settings with types, defaults, ranges and descriptions as
 * markdown (docs/config-reference.md is generated from it). */
void config_write_reference(FILE *out);

#endif
