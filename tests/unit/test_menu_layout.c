/* The menu's labels stay inside their widgets: the gap between two neighbouring tabs shows
 * only the panel behind them, on every page (a label too wide for its tab once ran into the
 * next one: "SlicesTransfer"). */
#include "testutil.h"

#include <stdio.h>
#include <string.h>

#include "menu/menu.h"

static const char *const tabs[] = {"tab.time",     "tab.fields", "tab.layers",
                                   "tab.slices",   "tab.transfer", "tab.light",
                                   "tab.quality",  "tab.probe",  "reset"};

/* Whether the columns [X0, X1) of rows [Y0, Y1) of the panel hold one colour. */
static bool uniform_columns(const uint8_t *px, int w, int x0, int x1, int y0, int y1)
{
    const uint8_t *c = &px[4 * ((size_t)y0 * w + x0)];
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++)
            if (memcmp(&px[4 * ((size_t)y * w + x)], c, 4) != 0)
                return false;
    return true;
}

static void test_tab_labels_inside(void **state)
{
    (void)state;
    struct menu_model model = {.speed = 2, .step_count = 4, .light_resolution = 64,
                               .epsilon = 0.01};
    transfer_defaults(&model.transfer, TRANSFER_FIELD_QVAPOR);
    struct menu *m = menu_create(NULL, &model);
    assert_non_null(m);
    const float c[3] = {0, 1.2f, -0.5f}, r[3] = {1, 0, 0}, u[3] = {0, 1, 0};
    menu_set_pose(m, c, r, u, 0.6f);
    menu_set_visible(m, true);
    int n = (int)(sizeof(tabs) / sizeof(tabs[0]));
    for (int page = 0; page < MENU_PAGE_COUNT; page++) {
        menu_set_page(m, (enum menu_page)page);
        int w, h;
        const uint8_t *px = menu_pixels(m, &w, &h, NULL);
        assert_non_null(px);
        for (int i = 0; i + 1 < n; i++) {
            int a[4], b[4];
            assert_true(menu_widget_rect(m, tabs[i], a));
            assert_true(menu_widget_rect(m, tabs[i + 1], b));
            int gap0 = a[0] + a[2], gap1 = b[0];
            assert_true(gap1 > gap0);
            assert_true(gap0 >= 0 && gap1 <= w && a[1] >= 0 && a[1] + a[3] <= h);
            if (!uniform_columns(px, w, gap0, gap1, a[1], a[1] + a[3]))
                fail_msg("page %d: a label runs between %s and %s (columns %d-%d)", page,
                         tabs[i], tabs[i + 1], gap0, gap1);
        }
    }
    menu_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tab_labels_inside),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
