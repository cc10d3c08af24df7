/* common/glyphs: a TrueType font baked into an atlas, and the pen moving along a line; files
 * that are no font, and atlases too small, are refused with the file's name. */
#include "testutil.h"

#include <math.h>
#include <string.h>
#include <unistd.h>

#include "common/glyphs.h"
#include "common/log.h"

#define FONT "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"

static struct glyph_atlas *ascii(float pixels, int w, int h)
{
    return glyph_atlas_create(FONT, pixels, 32, 95, w, h);
}

static void test_bake_and_place(void **state)
{
    if (access(FONT, R_OK) != 0)
        skip();
    struct glyph_atlas *a = ascii(20.0f, 512, 256);
    assert_non_null(a);
    /* Pixel height is ascent + descent: DejaVu Sans' ascent is 1901 of its 2384 units, 16 of
     * 20 pixels. */
    assert_true(glyph_atlas_ascent(a) >= 15 && glyph_atlas_ascent(a) <= 17);
    float narrow = glyph_atlas_advance(a, 'i' - 32), wide = glyph_atlas_advance(a, 'W' - 32);
    assert_true(narrow > 2.0f && wide > 2.0f * narrow && wide < 25.0f);
    assert_true(glyph_atlas_advance(a, ' ' - 32) > 0.0f);

    /* The pen moves by the advance; the quad sits on the baseline, its atlas rectangle inside
     * the atlas and as large as the quad. */
    float x = 10.0f, y = 30.0f;
    struct glyph_quad q;
    glyph_atlas_place(a, 'W' - 32, &x, &y, &q);
    assert_true(fabsf(x - (10.0f + wide)) < 1e-4f && y == 30.0f);
    assert_true(q.x0 >= 9.0f && q.x1 > q.x0 && q.y0 < 30.0f && q.y1 <= 31.0f);
    assert_true(q.s0 >= 0.0f && q.s1 <= 1.0f && q.t0 >= 0.0f && q.t1 <= 1.0f);
    assert_true(fabsf((q.s1 - q.s0) * 512.0f - (q.x1 - q.x0)) < 1e-3f);
    assert_true(fabsf((q.t1 - q.t0) * 256.0f - (q.y1 - q.y0)) < 1e-3f);
    /* The atlas holds the glyph there: some coverage inside its rectangle. */
    const unsigned char *alpha = glyph_atlas_alpha(a);
    unsigned sum = 0;
    for (int t = (int)(q.t0 * 256.0f + 0.5f); t < (int)(q.t1 * 256.0f + 0.5f); t++) {
        for (int s = (int)(q.s0 * 512.0f + 0.5f); s < (int)(q.s1 * 512.0f + 0.5f); s++)
            sum += alpha[t * 512 + s];
    }
    assert_true(sum > 255u * 10u);
    glyph_atlas_destroy(a);
    glyph_atlas_destroy(NULL);
}

static void test_refused(void **state)
{
    if (access(FONT, R_OK) != 0)
        skip();
    log_set_level(LOG_NONE);
    unsigned errors = log_error_count();
    const char *text = test_write_file("not-a-font.ttf", "this is not a font at all\n");
    assert_null(glyph_atlas_create(text, 20.0f, 32, 95, 512, 256));
    assert_null(glyph_atlas_create(test_tmp_path("missing.ttf"), 20.0f, 32, 95, 512, 256));
    assert_null(ascii(48.0f, 32, 32)); /* 95 glyphs at 48 pixels in 32 x 32 */
    assert_int_equal(log_error_count(), errors + 3);
    log_set_level(LOG_INFO);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bake_and_place),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
