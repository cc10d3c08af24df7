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
/* Uploads the menu's image when it changed and places the panel and the ray with TO_WORLD
 * (menu space -> world, column-major).  EXPOSURE: the tone mapping's, so the panel shows its
 * own colours. */
bool menu_view_update(struct menu_view *v, struct menu *m, const float to_world[16],
                          float exposure);
/* The radiance the panel shows for an image texel (what the view's pixel holds). */
void menu_view_texel_radiance(const uint8_t rgba[4], float exposure, float out[3]);

#endif
