/* The information panel: the legend's colours are the transfer function's at the values along
 * its bar, the date is drawn, the north arrow points where it is told, and the km ticks of the
 * box are round numbers. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "menu/overlay.h"
#include "session/overlay_view.h"

static const uint8_t *pixel(const uint8_t *img, int x, int y)
{
    return &img[4 * (y * OVERLAY_WIDTH + x)];
}

static void test_legend_colours(void **state)
{
    struct overlay *o = overlay_create(NULL);
    assert_non_null(o);
    struct overlay_model m;
    memset(&m, 0, sizeof(m));
    m.legend = true;
    transfer_defaults(&m.transfer, TRANSFER_FIELD_TEMPERATURE);
    const uint8_t *img = overlay_pixels(o, &m, NULL);
    for (int i = 0; i <= 8; i++) {
        float x = i / 8.0f;
        int px, py;
        assert_true(overlay_legend_pixel(o, x, &px, &py));
        const uint8_t *p = pixel(img, px, py);
        for (int c = 0; c < 3; c++) {
            float v = transfer_eval(&m.transfer, (enum transfer_channel)c, x);
            int want = (int)(v * 255.0f + 0.5f);
            if (abs(p[c] - want) > 2) /* the bar's pixel centre is within half a pixel of X */
                fail_msg("legend at %.3f, channel %d: %d, the function says %d", x, c, p[c], want);
        }
    }
    /* Its labels in the field's units. */
    char buf[32];
    overlay_value_text(TRANSFER_FIELD_TEMPERATURE, 253.15, buf, sizeof(buf));
    assert_string_equal(buf, "-20 C");
    overlay_value_text(TRANSFER_FIELD_QVAPOR, 0.0125, buf, sizeof(buf));
    assert_string_equal(buf, "12.5 g/kg");
    overlay_value_text(TRANSFER_FIELD_WIND, 35.0, buf, sizeof(buf));
    assert_string_equal(buf, "35 m/s");
    /* Without the legend there is no bar. */
    m.legend = false;
    img = overlay_pixels(o, &m, NULL);
    int px, py;
    assert_false(overlay_legend_pixel(o, 0.5f, &px, &py));
    overlay_destroy(o);
}

/* Ink: pixels much brighter than the panel's background. */
static int ink_in(const uint8_t *img, int x0, int y0, int x1, int y1)
{
    int n = 0;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++)
            n += pixel(img, x, y)[0] > 120;
    return n;
}

static void test_date_and_north(void **state)
{
    struct overlay *o = overlay_create(NULL);
    struct overlay_model m;
    memset(&m, 0, sizeof(m));
    unsigned g0, g1;
    const uint8_t *img = overlay_pixels(o, &m, &g0);
    assert_int_equal(ink_in(img, 0, 0, OVERLAY_WIDTH, OVERLAY_HEIGHT), 0);
    m.date = true;
    snprintf(m.date_text, sizeof(m.date_text), "2005-08-28 12:00 UTC");
    img = overlay_pixels(o, &m, &g1);
    assert_true(g1 != g0); /* drawn again */
    assert_true(ink_in(img, 0, 10, 240, 40) > 100);
    unsigned g2;
    overlay_pixels(o, &m, &g2);
    assert_true(g2 == g1); /* the same model: not drawn again */
    m.date = false;
    m.north = true;
    /* The arrow's centre is at (282, 92), its tip 26 pixels out. */
    m.north_deg = 0.0f;
    img = overlay_pixels(o, &m, NULL);
    int up = ink_in(img, 276, 67, 288, 80), down = ink_in(img, 276, 105, 288, 118);
    assert_true(up > down);
    m.north_deg = 90.0f;
    img = overlay_pixels(o, &m, NULL);
    int right = ink_in(img, 295, 86, 308, 98), left = ink_in(img, 256, 86, 269, 98);
    assert_true(right > left);
    overlay_destroy(o);
}

static void test_ticks(void **state)
{
    assert_true(overlay_tick_km(60.0) == 10.0);
    assert_true(overlay_tick_km(480.0) == 100.0);
    assert_true(overlay_tick_km(16.0) == 2.0);
    assert_true(overlay_tick_km(2000.0) == 200.0);
    for (double e = 1.0; e < 1e5; e *= 1.37) {
        double t = overlay_tick_km(e), n = e / t;
        assert_true(n >= 3.0 && n <= 12.0);
        double m = t / pow(10.0, floor(log10(t) + 1e-9));
        assert_true(fabs(m - 1.0) < 1e-9 || fabs(m - 2.0) < 1e-9 || fabs(m - 5.0) < 1e-9);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_legend_colours),
        cmocka_unit_test(test_date_and_north),
        cmocka_unit_test(test_ticks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
