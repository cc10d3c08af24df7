/* menu internal: text baked once into an 8-bit atlas (common/glyphs.h) and blended into the
 * menu's RGBA8 panel image. */
#ifndef ANVIL_MENU_FONT_H
#define ANVIL_MENU_FONT_H

#include <stdbool.h>
#include <stdint.h>

struct menu_font;

/* Bakes printable ASCII of the TrueType file PATH at PIXELS high.  NULL (logged) when the
 * file is missing or not a font.  Free with menu_font_destroy (NULL is fine). */
struct menu_font *menu_font_create(const char *path, float pixels);
void menu_font_destroy(struct menu_font *f);

/* Width in pixels of TEXT. */
int menu_font_width(const struct menu_font *f, const char *text);
/* Ascent in pixels (baseline below the top of a line). */
int menu_font_ascent(const struct menu_font *f);

/* Blends TEXT in RGB (0-255) into IMG (W x H RGBA8, row 0 at the top) with its top-left
 * corner at (X, Y), clipped to the image. */
void menu_font_draw(const struct menu_font *f, uint8_t *img, int w, int h, int x, int y,
                    const char *text, const uint8_t rgb[3]);

#endif
