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

/* ---- framing: a view of the whole domain when the scene gives none (docs/data.md) ------ */

/* The box the scene's volume fills, world metres (LO, HI corners, the height exaggeration
 * applied), without reading a time step: the data's grid (data_source_grid) or the synthetic
 * scene's.  False (logged) when the data cannot be opened. */
bool scene_domain_box(const struct config *cfg, double lo[3], double hi[3]);

/* A camera that frames the box LO..HI: looking at its centre from the south-west at 30
 * degrees elevation, every corner inside the middle 90 % of an image of ASPECT (width /
 * height) with the vertical field of view FOV_DEG and the near plane NEAR_M; the far plane
 * beyond the farthest corner. */
void scene_frame_camera(const double lo[3], const double hi[3], double fov_deg, double aspect,
                        double near_m, struct display_camera *out);

/* CFG's camera.* (km) from C (metres), camera.given left as it was. */
void scene_camera_to_config(const struct display_camera *c, struct config_camera *out);

/* The navigation that fits the box LO..HI into the room of the tracked display CFG (cave:
 * its walls' bounding box; hmd, openxr: 3 m wide and 3.5 m deep ahead of head.position, the
 * floor at y = 0): north away from the viewer, the ground on the floor, the centre straight
 * ahead of head.position, the footprint within 80 % of the room's width and the room's depth
 * from the front wall to 0.2 m before the head, the top at least 0.3 m below the eyes. */
void scene_frame_navigation(const double lo[3], const double hi[3],
                            const struct display_config *cfg, struct display_navigation *out);

/* Fills OUT from CFG: format, files (pointers into CFG, which must outlive OUT), WRF reading
 * (data.levels, data.top, data.stride, data.crop, data.memory), Isabel sizes, optics, the
 * species toggles, procedural detail and the height exaggeration. */
void scene_source_desc(const struct config *cfg, const char **file_ptrs,
                       struct data_source_desc *out);

/* The procedural detail CFG asks for (effects.detail, detail.*). */
void scene_detail_desc(const struct config *cfg, struct detail_desc *out);

#endif
