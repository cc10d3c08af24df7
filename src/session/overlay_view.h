/*
 * session/overlay_view: the information overlay in the scene.  The panel of menu/overlay.h
 * (date and time, the legend, a north arrow) on a quad: in the lower left of the orbit
 * camera's view and following it, or in a CAVE or HMD a panel in the room at arm's length,
 * left of the menu, readable in stereo; and the domain's box with km ticks along its floor
 * and their labels, in the world.  Needs the GL context current.
 */
#ifndef ANVIL_SESSION_OVERLAY_VIEW_H
#define ANVIL_SESSION_OVERLAY_VIEW_H

#include <stdbool.h>

#include "config/config.h"
#include "display/display.h"
#include "menu/overlay.h"
#include "render/render.h"

struct overlay_view;

/* The overlay CFG asks for (overlay.*), its meshes added to R (the box around R's volume).
 * NULL (logged) on failure. */
struct overlay_view *overlay_view_create(struct renderer *r, const struct config *cfg);
void overlay_view_destroy(struct overlay_view *v, struct renderer *r); /* NULL is fine */

/* Shows M: on the orbit CAMERA's view of W x H pixels, or (CAMERA NULL) in the room before
 * HEAD (tracker metres) with TO_WORLD mapping the room to the world. */
bool overlay_view_update(struct overlay_view *v, const struct overlay_model *m,
                         const struct display_camera *camera, int w, int h,
                         const double head[3], const float to_world[16], float exposure);

/* The world point where the panel, as last placed, shows its image's pixel (PX, PY) (row 0 at
 * the top). */
void overlay_view_point(const struct overlay_view *v, float px, float py, double world[3]);

/* The panel's image as last drawn (tests), OVERLAY_WIDTH x OVERLAY_HEIGHT. */
const uint8_t *overlay_view_pixels(struct overlay_view *v, const struct overlay_model *m);
const struct overlay *overlay_view_overlay(const struct overlay_view *v);

/* The km between the box's ticks for a side of EXTENT_KM: 1, 2 or 5 times a power of ten,
 * four to ten ticks a side. */
double overlay_tick_km(double extent_km);

#endif
