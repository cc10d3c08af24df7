/*
 * render/terrain: the meshes that put the storm in its place (docs/terrain.md): the terrain's
 * height field as lit triangles with a flat skirt around it, polylines on the ground
 * (coastlines, graticule) and flat text labels (glyphs from common/glyphs.h).  All of them are
 * opaque geometry for renderer_add_mesh: lit Lambertian, so they receive the light map's
 * shadow.  It knows nothing of lat/lon or files other than the font.
 * Every function that returns a mesh or text needs the GL context current.
 */
#ifndef ANVIL_RENDER_TERRAIN_H
#define ANVIL_RENDER_TERRAIN_H

#include <stdbool.h>

#include "data/terrain.h"
#include "render/render.h"

/* The terrain T as triangles, heights times HEIGHT_SCALE, coloured by terrain_albedo, normals
 * from the scaled heights; a flat skirt at z = 0 reaching SKIRT_M metres beyond T's border
 * with albedo SKIRT_ALBEDO stands for the rest of the ground.  NULL (logged) on failure. */
struct render_mesh *render_terrain_mesh(const struct terrain *t, double height_scale,
                                        double skirt_m, const float skirt_albedo[3]);

/* N_SEGMENTS line segments, SEGMENTS[6 s .. 6 s + 5] = (x0, y0, z0, x1, y1, z1) in metres, as a
 * lit line mesh of albedo COLOR facing up.  NULL (logged) when there are none or on failure. */
struct render_mesh *render_lines_mesh(const float *segments, int n_segments,
                                      const float color[3]);

/* A label lying flat on the ground: text (ASCII and the degree sign, UTF-8) starting at
 * (x, y, z), its letters HEIGHT_M tall, reading toward +x with their tops toward +y. */
struct render_label {
    double pos[3];
    double height_m;
    char text[32];
};

struct render_text;

/* Bakes FONT_PATH (a TrueType file) and lays out N labels as one textured, lit mesh of albedo
 * COLOR.  NULL (logged) when the font cannot be read or on failure.  The text owns its mesh and
 * texture: destroy it after removing the mesh from the renderer. */
struct render_text *render_text_create(const char *font_path, const struct render_label *labels,
                                       int n, const float color[3]);
void render_text_destroy(struct render_text *t);
/* The mesh to add to the renderer; valid until render_text_destroy. */
struct render_mesh *render_text_mesh(struct render_text *t);

#endif
