/*
 * menu/readout: a panel of labelled values (the probe's, docs/analysis.md): a title and rows
 * of "label  value", drawn into an RGBA8 image (row 0 at the top) that the session puts on a
 * quad: screen-fixed on the orbit camera, a panel in the room in a CAVE or HMD.  Never reads
 * a device, calls no GL.
 */
#ifndef ANVIL_MENU_READOUT_H
#define ANVIL_MENU_READOUT_H

#include <stdbool.h>
#include <stdint.h>

#define READOUT_WIDTH 360
#define READOUT_HEIGHT 340
#define READOUT_ROWS 18

struct readout_row {
    char label[24]; /* "": the value is a line of text across the panel */
    char value[160];
    bool dim; /* shown greyed out (a value the data lacks, a fallback) */
};

struct readout_model {
    char title[80];
    int count;
    struct readout_row rows[READOUT_ROWS];
};

struct readout;

/* NULL (logged) when the font cannot be read (NULL: menu.h's MENU_FONT_PATH). */
struct readout *readout_create(const char *font_path);
void readout_destroy(struct readout *r); /* NULL is fine */

/* The panel for M: READOUT_WIDTH x READOUT_HEIGHT RGBA8, row 0 at the top, drawn again when M
 * changed; GENERATION (may be NULL) counts the drawings.  Valid until the next call. */
const uint8_t *readout_pixels(struct readout *r, const struct readout_model *m,
                              unsigned *generation);

#endif
