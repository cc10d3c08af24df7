#include "menu/font.h"

#include <stdlib.h>

#include "common/glyphs.h"
#include "common/log.h"

#define ATLAS_W 512
#define ATLAS_H 256
#define FIRST_CHAR 32
#define CHAR_COUNT 95

struct menu_font {
    struct glyph_atlas *glyphs;
};

struct menu_font *menu_font_create(const char *path, float pixels)
{
    struct glyph_atlas *g =
        glyph_atlas_create(path, pixels, FIRST_CHAR, CHAR_COUNT, ATLAS_W, ATLAS_H);
    if (!g)
        return NULL;
    struct menu_font *f = malloc(sizeof(*f));
    if (!f) {
        log_error("%s: out of memory", path);
        glyph_atlas_destroy(g);
        return NULL;
    }
    f->glyphs = g;
    return f;
}

void menu_font_destroy(struct menu_font *f)
{
    if (!f)
        return;
    glyph_atlas_destroy(f->glyphs);
    free(f);
}

int menu_font_ascent(const struct menu_font *f)
{
    return glyph_atlas_ascent(f->glyphs);
}

int menu_font_width(const struct menu_font *f, const char *text)
{
    float x = 0.0f;
    for (const unsigned char *p = (const unsigned char *)text; *p; p++) {
        if (*p < FIRST_CHAR || *p >= FIRST_CHAR + CHAR_COUNT)
            continue;
        x += glyph_atlas_advance(f->glyphs, *p - FIRST_CHAR);
    }
    return (int)(x + 0.5f);
}

void menu_font_draw(const struct menu_font *f, uint8_t *img, int w, int h, int x, int y,
                    const char *text, const uint8_t rgb[3])
{
    const unsigned char *atlas = glyph_atlas_alpha(f->glyphs);
    float px = (float)x, py = (float)(y + glyph_atlas_ascent(f->glyphs));
    for (const unsigned char *p = (const unsigned char *)text; *p; p++) {
        if (*p < FIRST_CHAR || *p >= FIRST_CHAR + CHAR_COUNT)
            continue;
        struct glyph_quad q;
        glyph_atlas_place(f->glyphs, *p - FIRST_CHAR, &px, &py, &q);
        int x0 = (int)q.x0, y0 = (int)q.y0;
        int s0 = (int)(q.s0 * ATLAS_W + 0.5f), t0 = (int)(q.t0 * ATLAS_H + 0.5f);
        int gw = (int)(q.x1 - q.x0), gh = (int)(q.y1 - q.y0);
        for (int j = 0; j < gh; j++) {
            int yy = y0 + j;
            if (yy < 0 || yy >= h)
                continue;
            for (int i = 0; i < gw; i++) {
                int xx = x0 + i;
                if (xx < 0 || xx >= w)
                    continue;
                unsigned a = atlas[(t0 + j) * ATLAS_W + s0 + i];
                if (!a)
                    continue;
                uint8_t *d = &img[4 * ((size_t)yy * (size_t)w + (size_t)xx)];
                for (int c = 0; c < 3; c++)
                    d[c] = (uint8_t)((rgb[c] * a + d[c] * (255u - a) + 127u) / 255u);
            }
        }
    }
}
