/*
 * session/panel: an image in the scene.  A textured emissive quad (an opaque mesh drawn in
 * every view before the ray cast) showing an RGBA8 image (row 0 at the top) in its own sRGB
 * colours whatever the exposure: the texels hold radiance that the tone mapping turns back
 * into them.  The menu's panel and the information panel (the overlay) are panels.  Needs the
 * GL context current.
 */
#ifndef ANVIL_SESSION_PANEL_H
#define ANVIL_SESSION_PANEL_H

#include <stdbool.h>
#include <stdint.h>

#include "render/render.h"

struct panel;

/* A hidden panel, its mesh added to R.  NULL (logged) on failure. */
struct panel *panel_create(struct renderer *r);
void panel_destroy(struct panel *p, struct renderer *r); /* NULL is fine */

/* Shows IMG (W x H RGBA8, row 0 at the top; uploaded again when GENERATION changes) on the
 * quad whose centre is C, whose edges are RIGHT (its whole width) and UP (its whole height),
 * in the frame TO_WORLD maps to the world (column-major).  EXPOSURE: the tone mapping's. */
bool panel_show(struct panel *p, const uint8_t *img, int w, int h, unsigned generation,
                const float c[3], const float right[3], const float up[3],
                const float to_world[16], float exposure);
void panel_hide(struct panel *p);

struct display_camera;

/* Where a panel ASPECT times as high as wide goes on the orbit camera CAM's W x H view: in its
 * upper (UPPER) or lower left corner at the menu's depth (three near planes out), as wide as
 * MAX_W of the view's half width allows and MAX_H of its half height.  C, RIGHT and UP as
 * panel_show takes them, in the world. */
void panel_in_view_corner(const struct display_camera *cam, int w, int h, float aspect,
                          float max_w, float max_h, bool upper, float c[3], float right[3],
                          float up[3]);

/* The radiance the panel shows for an image texel (what the view's pixel holds). */
void panel_texel_radiance(const uint8_t rgba[4], float exposure, float out[3]);

/* OUT = A * B and the matrix of the frame (X, Y, Z, origin O), column-major 4x4. */
void panel_mat4_mul(const float a[16], const float b[16], float out[16]);
void panel_basis(const float x[3], const float y[3], const float z[3], const float o[3],
                 float out[16]);

#endif
