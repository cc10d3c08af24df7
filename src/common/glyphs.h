/*
 * common/glyphs: the glyphs of a TrueType font baked into an 8-bit coverage atlas, and where
 * each one goes along a line of text.  The one place that compiles stb_truetype (Debian's
 * libstb): the menu blends glyphs into its panel image, the map's labels texture quads with
 * the atlas.  Knows nothing of GL, menus or maps.
 */
#ifndef ANVIL_COMMON_GLYPHS_H
#define ANVIL_COMMON_GLYPHS_H

struct glyph_atlas;

/* One glyph placed on a line: its rectangle in pixels (y down, relative to the line's origin
 * at the baseline) and its rectangle in the atlas (texture coordinates in [0, 1]). */
struct glyph_quad {
    float x0, y0, x1, y1;
    float s0, t0, s1, t1;
};

/* Bakes the code points FIRST .. FIRST + COUNT - 1 of the TrueType file PATH at PIXELS high
 * into a WIDTH x HEIGHT atlas.  NULL (logged with PATH) when the file cannot be read, is not
 * a TrueType font, or its glyphs do not fit.  Free with glyph_atlas_destroy (NULL is fine). */
struct glyph_atlas *glyph_atlas_create(const char *path, float pixels, int first, int count,
                                       int width, int height);
void glyph_atlas_destroy(struct glyph_atlas *a);

/* The WIDTH x HEIGHT coverage (0-255), row 0 at the top.  Valid until destroy. */
const unsigned char *glyph_atlas_alpha(const struct glyph_atlas *a);
/* The font's ascent at the baked size, in whole pixels (the baseline's depth below a line's
 * top). */
int glyph_atlas_ascent(const struct glyph_atlas *a);
/* How far glyph INDEX (its code point minus FIRST) moves the pen, in pixels. */
float glyph_atlas_advance(const struct glyph_atlas *a, int index);
/* Places glyph INDEX with the pen at (*X, *Y) on the baseline, pixel-aligned, into *Q, and
 * moves the pen on by its advance. */
void glyph_atlas_place(const struct glyph_atlas *a, int index, float *x, float *y,
                       struct glyph_quad *q);

#endif
