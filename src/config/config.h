/*
 * config: scene files (libconfig syntax) and command-line overrides to one plain struct.
 * This is the only part that includes libconfig.h.  Every setting has a default, a type and
 * a valid range in one table (config.c); every error names the file, the line, the setting
 * and what was expected.
 *
 * Units in files: lengths of the scene in km (positions, extents), ray steps in metres,
 * angles in degrees.  The struct below stores what the file says, in those units.
 */
#ifndef ANVIL_CONFIG_H
#define ANVIL_CONFIG_H

#include <stdbool.h>
#include <stdio.h>

#include "optics/optics.h"

#define CONFIG_PATH_MAX 1024
#define CONFIG_MAX_FILES 64

enum scene_kind {
    SCENE_STORM,  /* procedural storm with all five species */
    SCENE_SLAB,   /* homogeneous box filling the volume; tau measured vertically */
    SCENE_SPHERE, /* homogeneous ball; tau measured along a diameter */
    SCENE_EMPTY,  /* nothing */
    SCENE_VOXEL,  /* one voxel at the centre; tau measured vertically through it */
    SCENE_DATA,   /* from data.* (WRF, Isabel bricks, extinction files) */
};

enum data_format { DATA_WRF, DATA_ISABEL, DATA_EXTINCTION };

enum lightmap_mode { LIGHTMAP_OFF, LIGHTMAP_DENSE, LIGHTMAP_COMPRESSED };

enum phase_choice { PHASE_WATER, PHASE_ICE };

struct config_scene {
    enum scene_kind kind;       /* scene.kind: "storm" | "slab" | "sphere" | "empty" | "voxel" | "data" */
    int size[3];                /* scene.size: voxels [nx, ny, nz] of synthetic scenes */
    double extent_km[3];        /* scene.extent: physical size of synthetic scenes, km */
    double tau;                 /* scene.tau: optical depth of the test scenes */
    enum phase_choice phase;    /* scene.phase: phase of the test scenes' medium */
    unsigned seed;              /* scene.seed: procedural storm seed */
    double time;                /* scene.time: storm evolution time in [0, 1] */
};

struct config_data {
    enum data_format format;                  /* data.format */
    char files[CONFIG_MAX_FILES][CONFIG_PATH_MAX]; /* data.files (resolved against the config) */
    int file_count;
    int step;                                 /* data.step: time step index to show */
    int levels;                               /* data.levels: regular height levels */
    double top_km;                            /* data.top: top of the height grid, km (0 = auto) */
    int stride[3];                            /* data.stride: subsampling per axis */
    int crop[6];                              /* data.crop: [x0, x1, y0, y1, z0, z1], -1 = all */
    double memory_mb;                         /* data.memory: budget for one step, MiB */
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
};

struct config_camera {
    double position_km[3]; /* camera.position */
    double target_km[3];   /* camera.target */
    double up[3];          /* camera.up */
    double fov_deg;        /* camera.fov: vertical field of view */
    double near_m;         /* camera.near: near plane distance, metres */
    double far_km;         /* camera.far */
};

struct config_render {
    int width, height;     /* render.width, render.height */
    double step_m;         /* render.step: ray step in metres; 0 = half the smallest voxel side */
    double exposure;       /* render.exposure: multiplies radiance before tone mapping */
    double sky[3];         /* render.sky: background radiance, linear RGB */
    double ground[3];      /* render.ground: ground albedo, linear RGB */
    bool ground_on;        /* render.ground_on: draw the ground plane */
    double termination;    /* render.termination: stop a ray below this transmittance */
};

struct config_lightmap {
    enum lightmap_mode mode; /* lightmap.mode: "off" | "dense" | "compressed" */
    int resolution[3];       /* lightmap.resolution: [across x, across y, along the light] */
    double epsilon;          /* lightmap.epsilon: compression error bound */
    double forward_angle_deg;/* lightmap.forward_angle: theta */
    bool forward;            /* lightmap.forward: forward scattering on/off */
    bool peripheral;         /* lightmap.peripheral: peripheral scattering on/off */
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
};

/* Fills every setting with its default: the built-in procedural storm seen from the south-west
 * with the sun in the south-east. */
void config_defaults(struct config *cfg);

/* Reads PATH (with @include resolved relative to the including file) on top of the
 * defaults.  On failure logs one message "FILE:LINE: SETTING: expected ..." and returns
 * false; CFG then holds defaults plus whatever was read. */
bool config_load(const char *path, struct config *cfg);

/* Applies one "path=value" override (the --set option), e.g. "light.elevation=10.0",
 * "scene.size=[64,64,32]", "lightmap.mode=dense".  Same types and ranges as the file.  On
 * failure logs "--set PATH: expected ..." and returns false. */
bool config_set(struct config *cfg, const char *assignment);

/* Checks cross-setting constraints (e.g. camera position differs from target; data.files
 * present when scene.kind = "data").  Logs and returns false on the first problem. */
bool config_validate(const struct config *cfg);

/* Writes the whole table of settings with types, defaults, ranges and descriptions as
 * markdown (docs/config-reference.md is generated from it). */
void config_write_reference(FILE *out);

#endif
