/*
 * app/map: the storm in its place (docs/terrain.md).  From the config and the data's metadata
 * it builds the session's ground: the terrain mesh (WRF HGT, LANDMASK, LU_INDEX) with a flat
 * skirt, GSHHG coastlines and a labelled latitude/longitude graticule, in the volume's frame
 * and scaled with scene.height_exaggeration, and adds them to the renderer as opaque geometry.
 * Missing pieces (no HGT, no XLAT/XLONG, no GSHHG file, no font) are reported with a warning
 * and left out; the built-in flat ground plane remains.
 */
#ifndef ANVIL_SESSION_MAP_H
#define ANVIL_SESSION_MAP_H

#include <stdbool.h>

#include "config/config.h"
#include "data/geo.h"
#include "data/wrf.h"
#include "render/render.h"

struct scene_map;

/* Builds the map for the volume the renderer holds (renderer_grid: already stretched by the
 * height exaggeration) and adds its meshes to R.  META: the WRF metadata of the open data
 * (player_wrf_meta), or NULL to read it from the config's files.  Returns NULL only when out
 * of memory or GL fails (logged); a map with nothing in it is fine.  Needs the GL context
 * current.  Destroy it with scene_map_destroy before the renderer. */
struct scene_map *scene_map_create(const struct config *cfg, struct renderer *r,
                                   const struct wrf_meta *meta);
void scene_map_destroy(struct scene_map *m, struct renderer *r); /* NULL is fine */
/* A map made again with META (a moving domain's step, wrf_step_meta) in place of OLD: its
 * meshes take the old ones' places in R's drawing order and OLD is destroyed.  NULL (logged)
 * when it could not be made; OLD then stands as it was. */
struct scene_map *scene_map_remake(struct scene_map *old, const struct config *cfg,
                                   struct renderer *r, const struct wrf_meta *meta);

/* Turns the analytic ground plane off where the terrain mesh (with its skirt) replaces it.
 * Call after every scene_render_settings. */
void scene_map_apply_settings(const struct scene_map *m, struct render_settings *s);

/* What the map holds, for tests and --verbose. */
struct scene_map_info {
    bool terrain;          /* a terrain mesh from HGT */
    bool placed;           /* lat/lon known (XLAT/XLONG or map.use_origin) */
    int coast_segments;    /* line segments drawn */
    int graticule_segments;
    int labels;
    double step_deg;       /* graticule spacing */
};
void scene_map_get_info(const struct scene_map *m, struct scene_map_info *out);
/* The placement from an open data source SRC: its own georeference (data_source_geo: WRF's XLAT/XLONG,
 * Isabel's published box, a CF lat/lon grid), then map.use_origin and the offset. */
struct data_source;
void scene_geo_init_source(const struct config *cfg, struct data_source *src,
                           struct geo_map *out);
/* The lat/lon placement a map of CFG makes, without the map: from META's XLAT/XLONG (NULL:
 * none), else map.origin with map.use_origin, with map.offset.  No GL.  Finish OUT with
 * geo_map_finish. */
void scene_geo_init(const struct config *cfg, const struct wrf_meta *meta, struct geo_map *out);
/* The lat/lon placement (kind GEO_NONE when not placed); valid until scene_map_destroy. */
const struct geo_map *scene_map_geo(const struct scene_map *m);

#endif
