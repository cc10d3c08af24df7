/*
 * menu/overlay: the information panel.  What a forecaster reads off a picture besides the
 * clouds: the shown time step's date and time, a colour legend of the colour-mapped field
 * (with its name, units and values along the bar) and a north arrow, drawn into an RGBA8 image
 * (row 0 at the top) that the session puts on a quad in the scene: screen-fixed on the orbit
 * camera, a panel in the room in a CAVE or HMD.  Never reads a device, calls no GL.
 */
#ifndef ANVIL_MENU_OVERLAY_H
#define ANVIL_MENU_OVERLAY_H

#include <stdbool.h>
#include <stdint.h>

#include "optics/transfer.h"

#define OVERLAY_WIDTH 320
#define OVERLAY_HEIGHT 160
#define OVERLAY_LEGENDS 4 /* bars the panel holds */

struct overlay_model {
    bool date;
    char date_text[96];         /* "2005-08-28 06:00 UTC, step 3 of 4" */
    bool legend;                /* a colour-mapped field is shown */
    struct transfer_function transfer; /* the first one's colour map */
    /* Every colour-mapped field shown (layers, then slices), the first OVERLAY_LEGENDS of
     * them: one bar each; legends[0] is TRANSFER. */
    int legend_count;
    struct transfer_function legends[OVERLAY_LEGENDS];
    bool north;
    float north_deg;            /* where north points on the panel, clockwise from up */
};

struct overlay;

/* NULL (logged) when the font cannot be read (NULL: menu.h's MENU_FONT_PATH). */
struct overlay *overlay_create(const char *font_path);
void overlay_destroy(struct overlay *o); /* NULL is fine */

/* The panel for M: OVERLAY_WIDTH x OVERLAY_HEIGHT RGBA8, row 0 at the top, drawn again when M
 * changed; GENERATION (may be NULL) counts the drawings.  Valid until the next call. */
const uint8_t *overlay_pixels(struct overlay *o, const struct overlay_model *m,
                              unsigned *generation);

/* Where the legend shows the field's value at X in [0, 1] of its range: a pixel inside the
 * bar.  False without a legend. */
bool overlay_legend_pixel(const struct overlay *o, float x, int *px, int *py);
/* The same for legend I (0 .. legend_count - 1 of the model last drawn); false without it. */
bool overlay_legend_pixel_at(const struct overlay *o, int i, float x, int *px, int *py);

/* The legend's label of a transfer function's range end: the value in the field's display
 * units ("12.5 g/kg", "-20 C", "35 m/s") into BUF. */
void overlay_value_text(enum transfer_field field, double value, char *buf, int size);

#endif
