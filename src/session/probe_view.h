/*
 * session/probe_view: the probe in the scene (docs/analysis.md): its panel of values (the
 * readout of menu/readout.h on a quad: the upper left of the orbit camera's view, following
 * it, or in a CAVE or HMD a panel in the room above the overlay's, readable in stereo at arm's
 * length) and a small cross at the point it reads.  Needs the GL context current.
 */
#ifndef ANVIL_SESSION_PROBE_VIEW_H
#define ANVIL_SESSION_PROBE_VIEW_H

#include <stdbool.h>

#include "display/display.h"
#include "menu/readout.h"
#include "render/render.h"

struct probe_view;

/* The panel and the cross, hidden, their meshes added to R.  NULL (logged) on failure. */
struct probe_view *probe_view_create(struct renderer *r);
void probe_view_destroy(struct probe_view *v, struct renderer *r); /* NULL is fine */

/* Shows M: on the orbit CAMERA's view of W x H pixels, or (CAMERA NULL) in the room before
 * HEAD (tracker metres) with TO_WORLD mapping the room to the world; the cross at POINT (world
 * metres; NULL: none), SIZE_M world metres across. */
bool probe_view_update(struct probe_view *v, const struct readout_model *m,
                       const double *point, double size_m, const struct display_camera *camera,
                       int w, int h, const double head[3], const float to_world[16],
                       float exposure);
void probe_view_hide(struct probe_view *v);

/* The panel's image as last drawn (tests), READOUT_WIDTH x READOUT_HEIGHT. */
const uint8_t *probe_view_pixels(struct probe_view *v, const struct readout_model *m);
/* The world point where the panel, as last placed, shows its image's pixel (PX, PY). */
void probe_view_point(const struct probe_view *v, float px, float py, double world[3]);

#endif
