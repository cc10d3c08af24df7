/*
 * session/menu_view: the menu in the scene: its panel (a textured emissive quad) and the
 * wand's ray (a line), as opaque meshes the renderer draws in every view.  Needs the GL
 * context current.
 */
#ifndef ANVIL_SESSION_MENU_VIEW_H
#define ANVIL_SESSION_MENU_VIEW_H

#include <stdbool.h>
#include <stdint.h>

#include "menu/menu.h"
#include "render/render.h"

/* ---- the menu in the scene (GL) -------------------------------------------------------- */

struct menu_view;
/* Meshes for the panel and the wand ray, added to R.  Needs the GL context. */
struct menu_view *menu_view_create(struct renderer *r);
void menu_view_destroy(struct menu_view *v, struct renderer *r);
/* What the menu's meshes show: its panel image and where it is, and the wand's ray (menu
 * space).  Plain data: a cluster's rank 0 sends it to the ranks without a menu. */
struct menu_view_state {
    bool visible;
    int width, height;    /* of the image */
    unsigned generation;  /* increases when the image does */
    float corners[4][3];  /* lower-left, lower-right, upper-right, upper-left */
    bool have_ray;
    float ray_origin[3], ray_direction[3], ray_hit; /* hit < 0: the ray misses the panel */
};

/* The state of menu M now; *PIXELS its image (valid until the next menu call). */
void menu_view_state_of(struct menu *m, struct menu_view_state *out, const uint8_t **pixels);

/* Uploads the menu's image when it changed and places the panel and the ray with TO_WORLD
 * (menu space -> world, column-major).  EXPOSURE: the tone mapping's, so the panel shows its
 * own colours. */
bool menu_view_update(struct menu_view *v, struct menu *m, const float to_world[16],
                      float exposure);
/* The same from a state and its image (PIXELS: the image of ST's generation). */
bool menu_view_show(struct menu_view *v, const struct menu_view_state *st,
                    const uint8_t *pixels, const float to_world[16], float exposure);
/* The radiance the panel shows for an image texel (what the view's pixel holds). */
void menu_view_texel_radiance(const uint8_t rgba[4], float exposure, float out[3]);

#endif
