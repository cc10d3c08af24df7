#include "menu/font.h"

#include <stdlib.h>
#include <string.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-function"
#define STB_TRUETYPE_IMPLEMENTATION
#define STBTT_STATIC
#include <stb_truetype.h>
#pragma GCC diagnostic pop

#include "common/log.h"

#define ATLAS_W 512
#define ATLAS_H 256
#define FIRST_CHAR 32
#define CHAR_COUNT 95

struct menu_font {
    uint8_t atlas[ATLAS_W * ATLAS_H];
    stbtt_bakedchar chars[CHAR_COUNT];
    int ascent;
};

struct menu_font *menu_font_create(const char *path, float pixels)
{
    size_t len = 0;
    unsigned char *ttf = (unsigned char *)file_read_all(path, &len);
    if (!ttf)
        return NULL;
    struct menu_font *f = calloc(1, sizeof(*f));
    if (!f) {
        free(ttf);
        log_error("%s: out of memory", path);
        return NULL;
    }
    stbtt_fontinfo info;
    if (len < 12 || !stbtt_InitFont(&info, ttf, stbtt_GetFontOffsetForIndex(ttf, 0))) {
        log_error("%s: not a TrueType font", path);
        goto error;
    }
    if (stbtt_BakeFontBitmap(ttf, 0, pixels, f->atlas, ATLAS_W, ATLAS_H, FIRST_CHAR, CHAR_COUNT,
                             f->chars) <= 0) {
        log_error("%s: the glyphs do not fit the atlas at %.0f pixels", path, pixels);
        goto error;
    }
    int ascent, descent, gap;
    stbtt_GetFontVMetrics(&info, &ascent, &descent, &gap);
    f->ascent = (int)(ascent * stbtt_ScaleForPixelHeight(&info, pixels) + 0.5f);
    free(ttf);
    return f;

error:
    free(ttf);
    free(f);
    return NULL;
}

void menu_font_destroy(struct menu_font *f)
{
    free(f);
}

int menu_font_ascent(const struct menu_font *f)
{
    return f->ascent;
}

int menu_font_width(const struct menu_font *f, const char *text)
{
    float x = 0.0f;
    for (const unsigned char *p = (const unsigned char *)text; *p; p++) {
        if (*p < FIRST_CHAR || *p >= FIRST_CHAR + CHAR_COUNT)
            continue;
        x += f->chars[*p - FIRST_CHAR].xadvance;
    }
    return (int)(x + 0.5f);
}

void menu_font_draw(const struct menu_font *f, uint8_t *img, int w, int h, int x, int y,
                    const char *text, const uint8_t rgb[3])
{
    float px = (float)x, py = (float)(y + f->ascent);
    for (const unsigned char *p = (const unsigned char *)text; *p; p++) {
        if (*p < FIRST_CHAR || *p >= FIRST_CHAR + CHAR_COUNT)
            continue;
        stbtt_aligned_quad q;
        stbtt_GetBakedQuad(f->chars, ATLAS_W, ATLAS_H, *p - FIRST_CHAR, &px, &py, &q, 1);
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
                unsigned a = f->atlas[(t0 + j) * ATLAS_W + s0 + i];
                if (!a)
                    continue;
                uint8_t *d = &img[4 * ((size_t)yy * (size_t)w + (size_t)xx)];
                for (int c = 0; c < 3; c++)
                    d[c] = (uint8_t)((rgb[c] * a + d[c] * (255u - a) + 127u) / 255u);
            }
        }
    }
}
