/*
 * session/scene: what a config describes, made real once: the volume of the scene's first
 * time step as extinction, the eye pass's lighting and background, the config's camera, and
 * the mapping from the config's data.* and optics settings to the data part's descriptions.
 * No GL; the data files are read only by scene_build_volume (and whoever opens the source
 * desc).  Nothing here writes a config.
 */
#ifndef ANVIL_SESSION_SCENE_H
#define ANVIL_SESSION_SCENE_H

#include <stdbool.h>

#include "config/config.h"
#include "data/detail.h"
#include "data/source.h"
#include "data/synth.h"
#include "data/volume.h"
#include "display/display.h"
#include "render/render.h"

/* Builds the volume the config describes as extinction (data: time step data.step). */
bool scene_build_volume(const struct config *cfg, struct ext_volume *out);

/* The synthetic scene of CFG's scene.* (the storm for scene.kind = "data" too).  False
 * (logged) when it would need more than data.memory. */
bool scene_synth_desc(const struct config *cfg, struct synth_desc *out);
/* Makes the synthetic scene D as extinction: the storm through the species selection SEL like
 * real data, the test scenes exactly; then DETAIL and the height exaggeration HEIGHT_K, as data
 * sources apply them. */
bool scene_build_synth(const struct synth_desc *d, const struct optics_params *optics,
                       const struct species_select *sel, const struct detail_desc *detail,
                       double height_k, struct ext_volume *out);
/* species.<name>.enabled and .scale. */
void scene_species_select(const struct config *cfg, struct species_select *out);

/* Time steps the config's scene has: 1 for synthetic scenes, the data files' count for data
 * (0 when they cannot be opened; the reason is logged). */
int scene_time_steps(const struct config *cfg);

/* The sun's transmittance through a clear atmosphere at ELEVATION_DEG, per R, G, B, relative to
 * the sun overhead (light.atmosphere; an approximation, docs/terrain.md). */
void scene_sun_transmittance(double elevation_deg, double rgb[3]);

/* Lighting and background from the config. */
void scene_render_settings(const struct config *cfg, struct render_settings *s);

/* The sun of the eye pass (direction and radiance, reddened by light.atmosphere) for the sun at
 * AZIMUTH_DEG, ELEVATION_DEG with CFG's intensity and colour. */
void scene_sun_settings(const struct config *cfg, double azimuth_deg, double elevation_deg,
                        struct render_settings *s);

/* The config's camera (camera.*) in metres. */
void scene_camera(const struct config *cfg, struct display_camera *out);

/* The config's camera at WIDTH x HEIGHT. */
void scene_camera_view(const struct config *cfg, int width, int height, struct render_view *view);

/* Fills OUT from CFG: format, files (pointers into CFG, which must outlive OUT), WRF reading
 * (data.levels, data.top, data.stride, data.crop, data.memory), Isabel sizes, optics, the
 * species toggles, procedural detail and the height exaggeration. */
void scene_source_desc(const struct config *cfg, const char **file_ptrs,
                       struct data_source_desc *out);

/* The procedural detail CFG asks for (effects.detail, detail.*). */
void scene_detail_desc(const struct config *cfg, struct detail_desc *out);

#endif
