#include "common/glyphs.h"

#include <assert.h>
#include <stdlib.h>

/* The implementation, compiled here and nowhere else; static, so its symbols stay inside this
 * file. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-function"
#define STB_TRUETYPE_IMPLEMENTATION
#define STBTT_STATIC
#include <stb_truetype.h>
#pragma GCC diagnostic pop

#include "common/log.h"

struct glyph_atlas {
    int width, height, count;
    int ascent;
    unsigned char *alpha;
    stbtt_bakedchar chars[]; /* COUNT of them */
};

struct glyph_atlas *glyph_atlas_create(const char *path, float pixels, int first, int count,
                                       int width, int height)
{
    assert(count > 0 && width > 0 && height > 0);
    size_t len = 0;
    unsigned char *ttf = (unsigned char *)file_read_all(path, &len);
    if (!ttf)
        return NULL;
    struct glyph_atlas *a = calloc(1, sizeof(*a) + (size_t)count * sizeof(a->chars[0]));
    unsigned char *alpha = malloc((size_t)width * (size_t)height);
    if (!a || !alpha) {
        log_error("%s: out of memory for a %dx%d glyph atlas", path, width, height);
        goto error;
    }
    a->width = width;
    a->height = height;
    a->count = count;
    a->alpha = alpha;
    /* stb_truetype trusts its input: check the file's tag (GetFontOffsetForIndex answers -1
     * for what is no font) and that the table directory lies inside the file first. */
    stbtt_fontinfo info;
    int offset = len >= 12 ? stbtt_GetFontOffsetForIndex(ttf, 0) : -1;
    if (offset < 0 || (size_t)offset + 12 > len ||
        (size_t)offset + 12 + 16 * (size_t)((ttf[offset + 4] << 8) | ttf[offset + 5]) > len ||
        !stbtt_InitFont(&info, ttf, offset)) {
        log_error("%s: not a TrueType font", path);
        goto error;
    }
    if (stbtt_BakeFontBitmap(ttf, offset, pixels, a->alpha, width, height, first, count,
                             a->chars) <= 0) {
        log_error("%s: the glyphs do not fit a %dx%d atlas at %.0f pixels", path, width, height,
                  pixels);
        goto error;
    }
    int ascent, descent, gap;
    stbtt_GetFontVMetrics(&info, &ascent, &descent, &gap);
    a->ascent = (int)(ascent * stbtt_ScaleForPixelHeight(&info, pixels) + 0.5f);
    free(ttf);
    return a;

error:
    free(ttf);
    if (a)
        glyph_atlas_destroy(a);
    else
        free(alpha);
    return NULL;
}

void glyph_atlas_destroy(struct glyph_atlas *a)
{
    if (!a)
        return;
    free(a->alpha);
    free(a);
}

const unsigned char *glyph_atlas_alpha(const struct glyph_atlas *a)
{
    return a->alpha;
}

int glyph_atlas_ascent(const struct glyph_atlas *a)
{
    return a->ascent;
}

float glyph_atlas_advance(const struct glyph_atlas *a, int index)
{
    assert(index >= 0 && index < a->count);
    return a->chars[index].xadvance;
}

void glyph_atlas_place(const struct glyph_atlas *a, int index, float *x, float *y,
                       struct glyph_quad *q)
{
    assert(index >= 0 && index < a->count);
    stbtt_aligned_quad b;
    stbtt_GetBakedQuad(a->chars, a->width, a->height, index, x, y, &b, 1);
    *q = (struct glyph_quad){b.x0, b.y0, b.x1, b.y1, b.s0, b.t0, b.s1, b.t1};
}
