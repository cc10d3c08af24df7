/* config: what libconfig 1.5 gets wrong and the engine now catches (integers past 32 bits,
 * NaN and infinity, @include names too long to keep), and settings that contradict each
 * other (a display's near plane beyond its far one). */
#include "testutil.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "common/log.h"
#include "config/config.h"
#include "config/display_config.h"

static struct config cfg;

/* TEXT as a scene file loads. */
static void load_ok(const char *name, const char *text)
{
    if (!config_load(test_write_file(name, text), &cfg))
        fail_msg("%s: %s", name, log_last_error());
}

/* TEXT as a scene file fails with one message holding each string. */
static void load_error(const char *name, const char *text, ...)
{
    unsigned before = log_error_count();
    assert_false(config_load(test_write_file(name, text), &cfg));
    assert_int_equal(log_error_count(), before + 1);
    va_list ap;
    va_start(ap, text);
    for (const char *part = va_arg(ap, const char *); part; part = va_arg(ap, const char *)) {
        if (!strstr(log_last_error(), part))
            fail_msg("%s: \"%s\" lacks \"%s\"", name, log_last_error(), part);
    }
    va_end(ap);
}
#define LOAD_ERROR(name, text, ...) load_error(name, text, __VA_ARGS__, NULL)

static void test_wide_integers(void **state)
{
    /* 4294967297 was read as 1 (and a 1-pixel-wide picture rendered). */
    LOAD_ERROR("w.cfg", "render = { width = 4294967297; };\n",
               "w.cfg:1: render.width: expected an integer in [1, 16384], got 4294967297");
    LOAD_ERROR("h.cfg", "render = {\n  height = 0x100000010;\n};\n",
               "h.cfg:2: render.height: expected an integer in [1, 16384], got 4294967312");
    LOAD_ERROR("n.cfg", "render = { width = -2147483649; };\n", "got -2147483649");
    /* In an array every integer becomes 64-bit (libconfig wants one type per array). */
    LOAD_ERROR("a.cfg", "scene = { size = [4294967328, 8, 8]; };\n",
               "scene.size[0]: expected an integer in [1, 500], got 4294967328");
    /* Past 64 bits: refused as such (libconfig saturated it). */
    LOAD_ERROR("b.cfg", "render = { width = 99999999999999999999; };\n",
               "b.cfg:1: 99999999999999999999: expected an integer of at most 64 bits");
    /* What fits is read as before, L or not; strings, names and comments are left alone. */
    load_ok("ok.cfg", "# 99999999999999999999\nscene = { size = [64, 0x10, 8]; };\n"
                      "render = { width = 320L; height = 240; };\n"
                      "data = { files = [\"run-99999999999999999999.nc\"]; };\n"
                      "/* 4294967297\n */ light = { azimuth = 1.5e2; elevation = -5.5e-1; };\n");
    assert_int_equal(cfg.scene.size[1], 16);
    assert_int_equal(cfg.render.width, 320);
    assert_true(cfg.light.azimuth_deg == 150.0 && cfg.light.elevation_deg == -0.55);
    assert_int_equal(cfg.render.height, 240);
    assert_non_null(strstr(cfg.data.files[0], "run-99999999999999999999.nc"));
}

static void test_nan_and_infinity(void **state)
{
    /* libconfig has no NaN: it said only "syntax error". */
    LOAD_ERROR("nan.cfg", "light = {\n  azimuth = nan;\n};\n",
               "nan.cfg:2: nan: expected a finite number");
    LOAD_ERROR("inf.cfg", "scene = { extent = [60.0, -Inf, 16.0]; };\n",
               "inf.cfg:1: -Inf: expected a finite number");
    LOAD_ERROR("infinity.cfg", "light : { azimuth : INFINITY; };\n", "INFINITY: expected a finite");
    /* After an integer in an array (its bookkeeping leaked then). */
    LOAD_ERROR("arr.cfg", "scene = { size = [64, 64, nan]; };\n",
               "arr.cfg:1: nan: expected a finite");
    /* A string left open: refused where it begins (libconfig said "syntax error" and leaked). */
    LOAD_ERROR("open.cfg", "scene = {\n  kind = \"empty;\n};\n",
               "open.cfg:2: syntax error: a string without its closing quote");
    /* A string may hold line breaks, and nan or 99999999999 inside it is text. */
    load_ok("text.cfg", "data = { files = [\"a\nnan 99999999999.nc\"]; };\n");
    /* A setting may be called nan. */
    LOAD_ERROR("name.cfg", "nan = 1;\n", "nan");
    assert_null(strstr(log_last_error(), "finite"));
}

static void test_long_include_names(void **state)
{
    /* An absolute name of 1023 characters naming inc.cfg, then "_other.cfg": it was cut to the
     * first 1023 and included inc.cfg. */
    test_write_file("inc.cfg", "light = { azimuth = 17.0; };\n");
    char name[1100];
    snprintf(name, sizeof(name), "%s/", test_tmpdir());
    while (strlen(name) + strlen("inc.cfg") + 2 <= 1023)
        strcat(name, "./");
    if (strlen(name) + strlen("inc.cfg") < 1023)
        strcat(name, "/");
    strcat(name, "inc.cfg");
    assert_int_equal(strlen(name), 1023);
    char text[1300];
    snprintf(text, sizeof(text), "scene = { kind = \"empty\"; };\n@include \"%s\"\n", name);
    load_ok("fits.cfg", text);
    assert_true(cfg.light.azimuth_deg == 17.0);
    snprintf(text, sizeof(text), "scene = { kind = \"empty\"; };\n@include \"%s_other.cfg\"\n",
             name);
    LOAD_ERROR("long.cfg", text, "long.cfg:2: @include: a name of 1033 characters (at most 1023)");
}

static void test_display_near_beyond_far(void **state)
{
    static struct display_config d;
    const char *path = test_write_file("d.cfg", "display = {\n  type = \"headless\";\n"
                                                "  near = 10.0;\n  far = 5.0;\n};\n");
    unsigned before = log_error_count();
    assert_false(display_config_load(path, &d));
    assert_int_equal(log_error_count(), before + 1);
    assert_non_null(strstr(log_last_error(), "d.cfg:4: display.far: expected a far plane beyond "
                                             "display.near (10 m), got 5 m"));
    path = test_write_file("e.cfg", "display = { type = \"headless\"; near = 5.0; far = 5.0; };\n");
    assert_false(display_config_load(path, &d));
    path = test_write_file("f.cfg", "display = { type = \"headless\"; near = 0.5; far = 5.0; };\n");
    assert_true(display_config_load(path, &d));
    /* --set as well. */
    assert_true(display_config_set(&d, "display.near=50"));
    assert_false(display_config_validate(&d));
    assert_non_null(strstr(log_last_error(), "display.far: expected a far plane beyond"));
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wide_integers),
        cmocka_unit_test(test_nan_and_infinity),
        cmocka_unit_test(test_long_include_names),
        cmocka_unit_test(test_display_near_beyond_far),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
