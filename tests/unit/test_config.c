/* config: defaults, files (with nested @include), --set, validation, the reference table. */
#include "testutil.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/log.h"
#include "config/config.h"

/* Checks that exactly one error was logged since BEFORE and that it contains every string in
 * the NULL-terminated list. */
static void check_error(unsigned before, ...)
{
    const char *msg = log_last_error();
    assert_int_equal(log_error_count(), before + 1);
    va_list ap;
    va_start(ap, before);
    for (const char *part = va_arg(ap, const char *); part; part = va_arg(ap, const char *)) {
        if (!strstr(msg, part)) {
            fprintf(stderr, "message \"%s\" lacks \"%s\"\n", msg, part);
            fail();
        }
    }
    va_end(ap);
}

/* Loads FIXTURE, expects it to fail with one message containing each string given. */
static void expect_load_error(const char *fixture, ...)
{
    static struct config cfg;
    unsigned before = log_error_count();
    assert_false(config_load(test_fixture(fixture), &cfg));
    assert_int_equal(log_error_count(), before + 1);
    va_list ap;
    va_start(ap, fixture);
    for (const char *part = va_arg(ap, const char *); part; part = va_arg(ap, const char *)) {
        if (!strstr(log_last_error(), part)) {
            fprintf(stderr, "message \"%s\" lacks \"%s\"\n", log_last_error(), part);
            fail();
        }
    }
    va_end(ap);
}

/* Applies ASSIGNMENT to the defaults, expects it to fail with one message containing each
 * string given, and to leave the settings untouched. */
static void expect_set_error(const char *assignment, ...)
{
    static struct config cfg, copy;
    config_defaults(&cfg);
    memcpy(&copy, &cfg, sizeof(cfg));
    unsigned before = log_error_count();
    assert_false(config_set(&cfg, assignment));
    assert_int_equal(log_error_count(), before + 1);
    va_list ap;
    va_start(ap, assignment);
    for (const char *part = va_arg(ap, const char *); part; part = va_arg(ap, const char *)) {
        if (!strstr(log_last_error(), part)) {
            fprintf(stderr, "message \"%s\" lacks \"%s\"\n", log_last_error(), part);
            fail();
        }
    }
    va_end(ap);
    assert_memory_equal(&cfg, &copy, sizeof(cfg)); /* nothing half applied */
}

#define EXPECT_LOAD_ERROR(fixture, ...) expect_load_error(fixture, __VA_ARGS__, NULL)
#define EXPECT_SET_ERROR(assignment, ...) expect_set_error(assignment, __VA_ARGS__, NULL)

static void test_defaults(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    assert_string_equal(cfg.path, "");
    assert_int_equal(cfg.scene.kind, SCENE_STORM);
    assert_int_equal(cfg.scene.size[0], 128);
    assert_int_equal(cfg.scene.size[2], 64);
    assert_true(cfg.scene.extent_km[2] == 16.0);
    assert_true(cfg.scene.tau == 4.0);
    assert_int_equal(cfg.scene.phase, PHASE_WATER);
    assert_int_equal(cfg.scene.seed, 1);
    assert_true(cfg.scene.time == 0.5);
    assert_int_equal(cfg.data.format, DATA_WRF);
    assert_int_equal(cfg.data.file_count, 0);
    assert_int_equal(cfg.data.stride[1], 1);
    for (int i = 0; i < 6; i++)
        assert_int_equal(cfg.data.crop[i], -1);
    assert_true(cfg.data.memory_mb == 4096.0);
    assert_int_equal(cfg.data.isabel_size[2], 100);
    assert_true(cfg.data.isabel_extent_km[2] == 19.8);

    struct optics_params p;
    optics_params_defaults(&p);
    assert_memory_equal(&cfg.optics.params, &p, sizeof(p));
    for (int f = 0; f < SPECIES_COUNT; f++) {
        assert_true(cfg.optics.enabled[f]);
        assert_true(cfg.optics.scale[f] == 1.0);
    }

    assert_true(cfg.light.azimuth_deg == 210.0);
    assert_true(cfg.light.elevation_deg == 35.0);
    assert_true(cfg.light.intensity == 6.0);
    assert_true(cfg.light.color[1] == 0.97);
    assert_true(cfg.camera.position_km[1] == -14.0);
    assert_true(cfg.camera.target_km[0] == 30.0);
    assert_true(cfg.camera.up[2] == 1.0 && cfg.camera.up[0] == 0.0);
    assert_true(cfg.camera.fov_deg == 50.0);
    assert_true(cfg.camera.near_m == 10.0);
    assert_true(cfg.camera.far_km == 2000.0);
    assert_int_equal(cfg.render.width, 640);
    assert_int_equal(cfg.render.height, 480);
    assert_true(cfg.render.step_m == 0.0);
    assert_true(cfg.render.sky[2] == 0.75);
    assert_true(cfg.render.ground[0] == 0.05);
    assert_true(cfg.render.ground_on);
    assert_true(cfg.render.termination == 0.001);
    assert_int_equal(cfg.lightmap.mode, LIGHTMAP_DENSE);
    assert_int_equal(cfg.lightmap.resolution[2], 64);
    assert_true(cfg.lightmap.epsilon == 0.01);
    assert_true(cfg.lightmap.forward_angle_deg == 20.0);
    /* Every effect is auto. */
    for (int e = 0; e < EFFECT_COUNT; e++)
        assert_int_equal(cfg.effects.mode[e], EFFECT_AUTO);
    assert_true(config_validate(&cfg));
}

/* Fills a stack frame and a freed heap block with BYTE: what an unset byte would pick up. */
static void __attribute__((noinline)) dirty(unsigned char byte)
{
    volatile unsigned char stack[256 * 1024];
    for (size_t i = 0; i < sizeof(stack); i++)
        stack[i] = byte;
    void *heap = malloc(sizeof(struct config) * 2);
    if (heap) {
        memset(heap, byte, sizeof(struct config) * 2);
        free(heap);
    }
}

/* A cluster's ranks compare their configs byte for byte (--check-sync): loading one file
 * must set every byte, padding and the rest of each string included, whatever memory held. */
static void test_loaded_bytes_are_all_set(void **state)
{
    (void)state;
    const char *path = test_write_file("bytes.cfg",
                                       "scene = { kind = \"data\"; };\n"
                                       "data = { files = [\"a.nc\", \"b*.nc\"]; };\n"
                                       "render = { width = 64; };\n"
                                       "transfer = { function = \"tf.cfg\"; };\n");
    test_write_file("b1.nc", "");
    char *sets[] = {"camera.fov=40", "data.files=[\"c.nc\"]"};
    struct config *a = malloc(sizeof(*a)), *b = malloc(sizeof(*b));
    assert_non_null(a);
    assert_non_null(b);
    memset(a, 0xa5, sizeof(*a));
    memset(b, 0x5a, sizeof(*b));
    dirty(0x33);
    bool ok_a = config_load_overrides(path, sets, 2, a);
    dirty(0xcc);
    bool ok_b = config_load_overrides(path, sets, 2, b);
    assert_int_equal(ok_a, ok_b);
    const unsigned char *x = (const unsigned char *)a, *y = (const unsigned char *)b;
    size_t first = sizeof(*a);
    for (size_t i = 0; i < sizeof(*a) && first == sizeof(*a); i++)
        if (x[i] != y[i])
            first = i;
    if (first != sizeof(*a))
        fail_msg("byte %zu of struct config depends on what memory held before", first);
    free(a);
    free(b);
}

static void test_good_file(void **state)
{
    struct config cfg;
    const char *path = test_fixture("config/good.cfg");
    assert_true(config_load(path, &cfg));
    assert_string_equal(cfg.path, path);
    assert_int_equal(cfg.scene.kind, SCENE_SLAB);
    assert_int_equal(cfg.scene.size[0], 32);
    assert_int_equal(cfg.scene.size[1], 16);
    assert_int_equal(cfg.scene.size[2], 8);
    assert_true(cfg.scene.extent_km[0] == 10.0 && cfg.scene.extent_km[1] == 12.0);
    assert_true(cfg.scene.tau == 2.5);
    assert_int_equal(cfg.scene.phase, PHASE_ICE);
    assert_int_equal(cfg.scene.seed, 42);
    assert_true(cfg.scene.time == 0.5); /* untouched */

    assert_int_equal(cfg.data.format, DATA_ISABEL);
    assert_int_equal(cfg.data.file_count, 3);
    /* Relative to the file's folder, in the order given; absolute paths unchanged. */
    assert_string_equal(cfg.data.files[0], test_fixture("config/frames/b.nc"));
    assert_string_equal(cfg.data.files[1], test_fixture("config/frames/a.nc"));
    assert_string_equal(cfg.data.files[2], "/abs/c.nc");
    assert_int_equal(cfg.data.stride[0], 2);
    assert_int_equal(cfg.data.stride[2], 1);
    assert_int_equal(cfg.data.crop[1], 99);
    assert_int_equal(cfg.data.crop[4], -1);

    /* 0.5 mm stored in metres; only the rain radius changes. */
    struct optics_params p;
    optics_params_defaults(&p);
    assert_true(fabs(cfg.optics.params.radius_m[SPECIES_RAIN] - 0.5e-3) < 1e-15);
    assert_true(cfg.optics.params.radius_m[SPECIES_SNOW] == p.radius_m[SPECIES_SNOW]);
    assert_true(cfg.optics.params.density[SPECIES_SNOW] == 150.0);
    assert_true(cfg.optics.params.density[SPECIES_GRAUPEL] == p.density[SPECIES_GRAUPEL]);
    assert_true(cfg.optics.params.g_ice == 0.7);
    assert_true(cfg.optics.params.g_water == p.g_water);
    assert_false(cfg.optics.enabled[SPECIES_GRAUPEL]);
    assert_true(cfg.optics.scale[SPECIES_GRAUPEL] == 0.5);
    assert_true(cfg.optics.enabled[SPECIES_SNOW]);
    assert_true(cfg.optics.scale[SPECIES_SNOW] == 1.0);

    assert_true(cfg.light.elevation_deg == 10.0);
    assert_true(cfg.light.azimuth_deg == 200.0);
    assert_true(cfg.light.color[1] == 1.0);
    assert_false(cfg.render.ground_on);
    assert_int_equal(cfg.render.width, 320);
    assert_int_equal(cfg.render.height, 480);
    assert_int_equal(cfg.lightmap.mode, LIGHTMAP_COMPRESSED);
    assert_int_equal(cfg.lightmap.resolution[2], 96);
    assert_true(config_validate(&cfg));
}

static void test_int_for_double(void **state)
{
    struct config cfg;
    assert_true(config_load(test_fixture("config/int_for_double.cfg"), &cfg));
    assert_true(cfg.light.elevation_deg == 10.0);
    assert_int_equal(cfg.scene.seed, 7);
    assert_int_equal(cfg.scene.size[1], 20);
    /* Not the other way round. */
    EXPECT_LOAD_ERROR("config/double_for_int.cfg", "double_for_int.cfg:2:", "render.width",
                      "expected an integer in [1, 16384]", "got 640.5");
}

static void test_nested_include(void **state)
{
    struct config cfg;
    /* include_ok.cfg -> sub/light.cfg -> sub/camera.cfg (a sibling, named relative to sub/). */
    assert_true(config_load(test_fixture("config/include_ok.cfg"), &cfg));
    assert_int_equal(cfg.scene.kind, SCENE_SPHERE);
    assert_true(cfg.light.elevation_deg == 20.0);
    assert_true(cfg.camera.fov_deg == 30.0);
    assert_true(cfg.camera.position_km[2] == 3.0);
    assert_int_equal(cfg.render.width, 200);

    /* Line 10 of the including file, after 8 included lines. */
    EXPECT_LOAD_ERROR("config/include_main.cfg", "include_main.cfg:10:", "render.height",
                      "expected an integer", "got \"tall\"");
    /* An error inside an included file names that file and its own line. */
    EXPECT_LOAD_ERROR("config/include_bad.cfg", "sub/bad.cfg:3:", "camera.fov",
                      "expected a number in (1, 179)", "got 180.0");
    EXPECT_LOAD_ERROR("config/include_missing.cfg",
                      "include_missing.cfg:3:", "sub/no_such_file.cfg");
    EXPECT_LOAD_ERROR("config/cycle/a.cfg", "cycle/b.cfg:2:", "cycle");
}

static void test_include_overrides(void **state)
{
    /* A top-level @include is a base: the same groups written later add and override. */
    struct config cfg;
    assert_true(config_load(test_fixture("config/override.cfg"), &cfg));
    assert_true(cfg.light.azimuth_deg == 100.0);
    assert_true(cfg.light.elevation_deg == 12.0);
    assert_true(cfg.camera.fov_deg == 50.0);
    assert_true(cfg.camera.position_km[1] == -30.0);

    /* Inside a group, @include inserts that group's settings; lines still map back. */
    EXPECT_LOAD_ERROR("config/include_in_group.cfg", "sub/render_size.cfg:2:", "render.exposure",
                      "expected a number in (0, 1000000]", "got -1.0");
    assert_false(config_load(test_fixture("config/include_in_group.cfg"), &cfg));
    assert_int_equal(cfg.render.width, 100);
    assert_int_equal(cfg.render.height, 50);
}

static void test_include_in_tmpdir(void **state)
{
    /* Includes two levels down, commented-out includes, trailing comments. */
    char sub[512];
    snprintf(sub, sizeof(sub), "%s", test_tmp_path("inc"));
    mkdir(sub, 0755);
    test_write_file("inc/deep.cfg", "light = { azimuth = 90.0; };\n");
    test_write_file("inc/mid.cfg", "# comment\n  @include \"deep.cfg\"  # trailing\n");
    const char *top = test_write_file("top.cfg", "/* @include \"nothing.cfg\"\n"
                                                 "@include \"nothing.cfg\"\n"
                                                 "*/\n"
                                                 "@include \"inc/mid.cfg\"\n"
                                                 "light = { elevation = 99.0; };\n");
    struct config cfg;
    unsigned before = log_error_count();
    assert_false(config_load(top, &cfg));
    /* The commented-out includes are skipped; the error is on line 5 of top.cfg. */
    check_error(before, "top.cfg:5:", "light.elevation", "got 99.0", NULL);
    assert_true(cfg.light.azimuth_deg == 90.0);

    const char *junk = test_write_file("junk.cfg", "@include \"inc/mid.cfg\" x = 1;\n");
    before = log_error_count();
    assert_false(config_load(junk, &cfg));
    check_error(before, "junk.cfg:1:", "syntax error", NULL);
}

/* A slice's contour values and model level from a file: up to six values, any count, then
 * set again element by element; seven, or a word among them, refused with the file's line. */
static void test_slice_contours_and_level(void **state)
{
    (void)state;
    const char *good = test_write_file(
        "contours.cfg", "look = { slices = ( { field = \"temperature\"; level = 3;\n"
                        "    contours = [273.15, 253.0, 233.15]; },\n"
                        "  { field = \"w\"; contours = []; } ); };\n");
    static struct config cfg;
    assert_true(config_load(good, &cfg));
    assert_int_equal(cfg.look.slice_count, 2);
    assert_int_equal(cfg.look.slices[0].level, 3);
    assert_int_equal(cfg.look.slices[0].contour_count, 3);
    assert_true(cfg.look.slices[0].contours[0] == 273.15);
    assert_true(cfg.look.slices[0].contours[1] == 253.0);
    assert_true(cfg.look.slices[0].contours[2] == 233.15);
    assert_int_equal(cfg.look.slices[1].contour_count, 0);
    assert_int_equal(cfg.look.slices[1].level, 0);
    assert_true(config_set(&cfg, "look.slices.[1].contours=[1.5, -2.0]"));
    assert_int_equal(cfg.look.slices[1].contour_count, 2);
    assert_true(cfg.look.slices[1].contours[1] == -2.0);

    const char *many = test_write_file(
        "contours7.cfg",
        "look = { slices = (\n  { contours = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]; } ); };\n");
    unsigned before = log_error_count();
    assert_false(config_load(many, &cfg));
    check_error(before, "contours7.cfg:2:", "contours", "0 to 6", NULL);
    const char *word = test_write_file(
        "contoursw.cfg", "look = { slices = (\n  { contours = [\"two\"]; } ); };\n");
    before = log_error_count();
    assert_false(config_load(word, &cfg));
    check_error(before, "contoursw.cfg:2:", "contours", "\"two\"", NULL);
}

static void test_file_errors(void **state)
{
    EXPECT_LOAD_ERROR("config/syntax.cfg", "syntax.cfg:4:", "syntax error");
    EXPECT_LOAD_ERROR("config/wrong_type.cfg", "wrong_type.cfg:6:", "light.elevation",
                      "expected a number in [-90, 90]", "got \"high\"");
    EXPECT_LOAD_ERROR("config/unknown.cfg", "unknown.cfg:7:", "light.elevaton", "unknown setting",
                      "did you mean light.elevation?");
    EXPECT_LOAD_ERROR("config/range.cfg", "range.cfg:12: light.elevation: "
                                          "expected a number in [-90, 90], got 120.0");
    EXPECT_LOAD_ERROR("config/bad_enum.cfg", "bad_enum.cfg:2:", "lightmap.mode",
                      "expected one of \"dense\", \"compressed\"", "\"sparse\"");
    EXPECT_LOAD_ERROR("config/bad_vector.cfg", "bad_vector.cfg:2:", "scene.size",
                      "expected an array of 3 integers in [1, 500]", "got 2 elements");
    /* The line of the bad element, not of the array. */
    EXPECT_LOAD_ERROR("config/bad_element.cfg", "bad_element.cfg:3:", "scene.size[1]",
                      "expected an integer in [1, 500]", "got 0");
    EXPECT_LOAD_ERROR("config/mixed_array.cfg", "mixed_array.cfg:2:", "syntax error", "mismatched");
    EXPECT_LOAD_ERROR("config/not_group.cfg", "not_group.cfg:1:", "light", "expected a group");
}

static void test_missing_file(void **state)
{
    struct config cfg;
    unsigned before = log_error_count();
    assert_false(config_load("/nonexistent/folder/scene.cfg", &cfg));
    check_error(before, "/nonexistent/folder/scene.cfg", "No such file", NULL);
    /* Defaults remain. */
    assert_true(cfg.light.elevation_deg == 35.0);
    assert_true(cfg.light.intensity == 6.0);
}

static void test_load_keeps_values_read_before_error(void **state)
{
    struct config cfg;
    assert_false(config_load(test_fixture("config/range.cfg"), &cfg));
    assert_int_equal(cfg.scene.size[2], 32);
    assert_true(cfg.camera.fov_deg == 60.0);
    assert_true(cfg.light.elevation_deg == 35.0);
    assert_true(cfg.light.intensity == 6.0);
}

static void test_data_files_glob(void **state)
{
    char dir[512];
    snprintf(dir, sizeof(dir), "%s", test_tmp_path("frames"));
    mkdir(dir, 0755);
    test_write_file("frames/f2.nc", "");
    test_write_file("frames/f10.nc", "");
    test_write_file("frames/f1.nc", "");
    test_write_file("frames/other.txt", "");
    const char *path =
        test_write_file("glob.cfg", "data = { files = [\"frames/f*.nc\", "
                                    "\"late.nc\"]; };\nscene = { kind = \"data\"; };\n");
    struct config cfg;
    assert_true(config_load(path, &cfg));
    /* A pattern stays one entry, resolved against the config's folder: the data reader
     * expands it, so a glob may match more files than data.files has entries. */
    assert_int_equal(cfg.data.file_count, 2);
    char want[1024];
    snprintf(want, sizeof(want), "%s/frames/f*.nc", test_tmpdir());
    assert_string_equal(cfg.data.files[0], want);
    snprintf(want, sizeof(want), "%s/late.nc", test_tmpdir());
    assert_string_equal(cfg.data.files[1], want);
    assert_true(config_validate(&cfg));

    /* A single string is a list of one. */
    path = test_write_file("one.cfg", "data = { files = \"x.nc\"; };\n");
    assert_true(config_load(path, &cfg));
    assert_int_equal(cfg.data.file_count, 1);

    path = test_write_file("nomatch.cfg", "\ndata = { files = [\"frames/*.grib\"]; };\n");
    unsigned before = log_error_count();
    assert_false(config_load(path, &cfg));
    check_error(before, "nomatch.cfg:2:", "data.files[0]", "no file matches", NULL);

    path = test_write_file("notstring.cfg", "data = { files = (\"a.nc\", 3); };\n");
    before = log_error_count();
    assert_false(config_load(path, &cfg));
    check_error(before, "notstring.cfg:1:", "data.files[1]", "expected a file name", "got 3", NULL);

    char text[4096] = "data = { files = [";
    for (int i = 0; i <= CONFIG_MAX_FILES; i++)
        strcat(text, i ? ", \"a.nc\"" : "\"a.nc\"");
    strcat(text, "]; };\n");
    path = test_write_file("many.cfg", text);
    before = log_error_count();
    assert_false(config_load(path, &cfg));
    check_error(before, "many.cfg:1:", "data.files", "at most 64", NULL);
}

static void test_set_each_type(void **state)
{
    struct config cfg;
    config_defaults(&cfg);
    assert_true(config_set(&cfg, "light.elevation=10.0"));
    assert_true(cfg.light.elevation_deg == 10.0);
    assert_true(config_set(&cfg, " light.azimuth = 90 "));
    assert_true(cfg.light.azimuth_deg == 90.0);
    assert_true(config_set(&cfg, "scene.size=[64,64,32]"));
    assert_int_equal(cfg.scene.size[0], 64);
    assert_int_equal(cfg.scene.size[2], 32);
    assert_true(config_set(&cfg, "scene.size=16, 8,4"));
    assert_int_equal(cfg.scene.size[0], 16);
    assert_int_equal(cfg.scene.size[1], 8);
    assert_int_equal(cfg.scene.size[2], 4);
    assert_true(config_set(&cfg, "data.crop=[0,9,1,8,-1,-1]"));
    assert_int_equal(cfg.data.crop[3], 8);
    assert_true(config_set(&cfg, "camera.position=(1, 2.5, 3)"));
    assert_true(cfg.camera.position_km[1] == 2.5);
    assert_true(config_set(&cfg, "lightmap.mode=dense"));
    assert_int_equal(cfg.lightmap.mode, LIGHTMAP_DENSE);
    assert_true(config_set(&cfg, "lightmap.mode=\"compressed\""));
    assert_int_equal(cfg.lightmap.mode, LIGHTMAP_COMPRESSED);
    assert_false(config_set(&cfg, "lightmap.mode=off")); /* effects.shadows=off now */
    assert_true(config_set(&cfg, "effects.shadows=off"));
    assert_int_equal(cfg.effects.mode[EFFECT_SHADOWS], EFFECT_OFF);
    assert_true(config_set(&cfg, "effects.ground_shadow=\"on\""));
    assert_int_equal(cfg.effects.mode[EFFECT_GROUND_SHADOW], EFFECT_ON);
    /* The row sets its own slot, not a neighbour's (off is the default: set the others). */
    assert_true(config_set(&cfg, "effects.multiple=on"));
    assert_int_equal(cfg.effects.mode[EFFECT_MULTIPLE], EFFECT_ON);
    assert_true(config_set(&cfg, "effects.multiple=auto"));
    assert_int_equal(cfg.effects.mode[EFFECT_MULTIPLE], EFFECT_AUTO);
    assert_int_equal(cfg.effects.mode[EFFECT_PERIPHERAL], EFFECT_AUTO);
    assert_int_equal(cfg.effects.mode[EFFECT_PHASE], EFFECT_AUTO);
    assert_true(config_set(&cfg, "render.ground_on=false"));
    assert_false(cfg.render.ground_on);
    assert_true(config_set(&cfg, "render.ground_on=yes"));
    assert_true(cfg.render.ground_on);
    assert_true(config_set(&cfg, "species.rain.enabled=false"));
    assert_false(cfg.optics.enabled[SPECIES_RAIN]);
    assert_true(cfg.optics.enabled[SPECIES_CLOUD]);
    assert_true(config_set(&cfg, "species.snow.scale=2"));
    assert_true(cfg.optics.scale[SPECIES_SNOW] == 2.0);
    assert_true(config_set(&cfg, "optics.radius_mm.graupel=3"));
    assert_true(fabs(cfg.optics.params.radius_m[SPECIES_GRAUPEL] - 3e-3) < 1e-15);
    assert_true(config_set(&cfg, "scene.seed=4294967295"));
    assert_true(cfg.scene.seed == 4294967295u);
    assert_true(config_set(&cfg, "scene.kind=voxel"));
    assert_int_equal(cfg.scene.kind, SCENE_VOXEL);
    assert_true(config_set(&cfg, "render.step=1e2"));
    assert_true(cfg.render.step_m == 100.0);

    /* Files from the command line are relative to the working folder. */
    assert_true(config_set(&cfg, "data.files=a.nc,b.nc"));
    assert_int_equal(cfg.data.file_count, 2);
    assert_string_equal(cfg.data.files[0], "a.nc");
    assert_string_equal(cfg.data.files[1], "b.nc");
    assert_true(config_set(&cfg, "data.files=[\"c.nc\"]"));
    assert_int_equal(cfg.data.file_count, 1);
    assert_string_equal(cfg.data.files[0], "c.nc");
    assert_true(config_set(&cfg, "data.files=[]"));
    assert_int_equal(cfg.data.file_count, 0);
}

static void test_set_errors(void **state)
{
    EXPECT_SET_ERROR("light.elevaton=10", "--set light.elevaton: unknown setting",
                     "did you mean light.elevation?");
    EXPECT_SET_ERROR("elevation=10", "did you mean light.elevation?");
    EXPECT_SET_ERROR("light.elevation=120", "--set light.elevation: "
                                            "expected a number in [-90, 90], got 120");
    EXPECT_SET_ERROR("light.elevation=10.0x", "expected a number", "got \"10.0x\"");
    EXPECT_SET_ERROR("light.elevation=", "expected a number", "got nothing");
    EXPECT_SET_ERROR("light.elevation=nan", "expected a number");
    EXPECT_SET_ERROR("light.elevation 10", "--set light.elevation 10", "SETTING=VALUE");
    EXPECT_SET_ERROR("light=3", "--set light:", "not a group");
    EXPECT_SET_ERROR("render.width=1.5", "render.width", "expected an integer", "got 1.5");
    EXPECT_SET_ERROR("render.width=0", "expected an integer in [1, 16384], got 0");
    EXPECT_SET_ERROR("camera.fov=179", "expected a number in (1, 179)");
    EXPECT_SET_ERROR("render.ground_on=maybe", "expected true or false", "\"maybe\"");
    EXPECT_SET_ERROR("lightmap.mode=sparse", "expected one of \"dense\", "
                                             "\"compressed\", got \"sparse\"");
    EXPECT_SET_ERROR("effects.forward=maybe", "expected one of \"auto\", \"on\", \"off\", "
                                              "got \"maybe\"");
    EXPECT_SET_ERROR("scene.size=[64,64]", "scene.size", "expected an array of 3 integers",
                     "got 2 elements");
    EXPECT_SET_ERROR("scene.size=[64,64,32,1]", "got 4 elements");
    EXPECT_SET_ERROR("scene.size=[64,64,32", "scene.size[0]");
    EXPECT_SET_ERROR("scene.size=64,0,32", "scene.size[1]", "got 0");
    EXPECT_SET_ERROR("scene.seed=-1", "scene.seed", "got -1");
    EXPECT_SET_ERROR("data.files=/nonexistent/*.nc", "no file matches");
}

static void test_validate(void **state)
{
    static struct config cfg;
    unsigned before;

    config_defaults(&cfg);
    memcpy(cfg.camera.target_km, cfg.camera.position_km, sizeof(cfg.camera.target_km));
    before = log_error_count();
    assert_false(config_validate(&cfg));
    check_error(before, "camera.target", "camera.position", NULL);

    config_defaults(&cfg);
    assert_true(config_set(&cfg, "camera.position=[5.0,5.0,20.0]"));
    assert_true(config_set(&cfg, "camera.target=[5.0,5.0,0.0]"));
    before = log_error_count();
    assert_false(config_validate(&cfg)); /* up [0, 0, 1] along the view */
    check_error(before, "camera.up", "parallel", NULL);
    assert_true(config_set(&cfg, "camera.up=[0,1,0]"));
    assert_true(config_validate(&cfg));

    config_defaults(&cfg);
    assert_true(config_set(&cfg, "camera.up=0,0,0"));
    assert_false(config_validate(&cfg));

    config_defaults(&cfg);
    assert_true(config_set(&cfg, "scene.kind=data"));
    before = log_error_count();
    assert_false(config_validate(&cfg));
    check_error(before, "data.files", "scene.kind", NULL);
    assert_true(config_set(&cfg, "data.files=x.nc"));
    assert_true(config_validate(&cfg));

    config_defaults(&cfg);
    assert_true(config_set(&cfg, "data.crop=[0,10,20,5,-1,-1]"));
    before = log_error_count();
    assert_false(config_validate(&cfg));
    check_error(before, "data.crop", "y range", NULL);
    assert_true(config_set(&cfg, "data.crop=[0,10,5,5,-1,3]"));
    assert_true(config_validate(&cfg));

    config_defaults(&cfg);
    assert_true(config_set(&cfg, "camera.near=5000"));
    assert_true(config_set(&cfg, "camera.far=4"));
    assert_false(config_validate(&cfg));

    static struct config loaded;
    assert_true(config_load(test_fixture("config/bad_validate.cfg"), &loaded));
    before = log_error_count();
    assert_false(config_validate(&loaded));
    check_error(before, "bad_validate.cfg", "camera.target", NULL);
}

static void test_shipped_configs(void **state)
{
    static const char *const names[] = {"default", "slab", "sphere", "empty", "voxel"};
    static const enum scene_kind kinds[] = {SCENE_STORM, SCENE_SLAB, SCENE_SPHERE, SCENE_EMPTY,
                                            SCENE_VOXEL};
    for (int i = 0; i < 5; i++) {
        char path[1024];
        snprintf(path, sizeof(path), "%s/configs/%s.cfg", ANVIL_SOURCE_DIR, names[i]);
        struct config cfg;
        assert_true(config_load(path, &cfg));
        assert_true(config_validate(&cfg));
        assert_int_equal(cfg.scene.kind, kinds[i]);
    }

    /* default.cfg spells out exactly the built-in defaults. */
    char path[1024];
    snprintf(path, sizeof(path), "%s/configs/default.cfg", ANVIL_SOURCE_DIR);
    static struct config file, def;
    assert_true(config_load(path, &file));
    config_defaults(&def);
    for (int f = 0; f < SPECIES_COUNT; f++) {
        /* mm to m may differ in the last bit */
        assert_true(fabs(file.optics.params.radius_m[f] - def.optics.params.radius_m[f]) <=
                    1e-12 * def.optics.params.radius_m[f]);
        file.optics.params.radius_m[f] = def.optics.params.radius_m[f];
    }
    memset(file.path, 0, sizeof(file.path));
    /* It names the camera: the scene has one (no framing of the data). */
    assert_true(file.camera.given);
    assert_false(def.camera.given);
    file.camera.given = false;
    assert_memory_equal(&file, &def, sizeof(file));

    /* The slab: 10 x 10 x 1 km, tau 2, looked at straight down from above its centre. */
    snprintf(path, sizeof(path), "%s/configs/slab.cfg", ANVIL_SOURCE_DIR);
    assert_true(config_load(path, &file));
    assert_true(file.scene.extent_km[0] == 10.0 && file.scene.extent_km[2] == 1.0);
    assert_true(file.scene.tau == 2.0);
    assert_true(file.camera.position_km[0] == 5.0 && file.camera.target_km[0] == 5.0);
    assert_true(file.camera.position_km[1] == 5.0 && file.camera.target_km[1] == 5.0);
    assert_true(file.camera.position_km[2] > file.scene.extent_km[2]);
}

static char *read_stream(FILE *f)
{
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    rewind(f);
    char *buf = malloc((size_t)len + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)len, f), (size_t)len);
    buf[len] = '\0';
    return buf;
}

static void test_reference(void **state)
{
    FILE *f = tmpfile();
    assert_non_null(f);
    config_write_reference(f);
    char *table = read_stream(f);
    fclose(f);

    assert_non_null(strstr(table, "| setting | type | default | range | description |\n"));
    assert_non_null(strstr(table, "| `light.elevation` | float | `35.0` | [-90, 90] |"));
    assert_non_null(strstr(table, "| `scene.size` | int[3] | `[128, 128, 64]` | [1, 500] |"));
    assert_non_null(strstr(table, "| `lightmap.mode` | string | `\"dense\"` | "
                                  "\"dense\", \"compressed\" |"));
    assert_non_null(strstr(table, "| `effects.phase` | string | `\"auto\"` | "
                                  "\"auto\", \"on\", \"off\" |"));
    assert_non_null(strstr(table, "| `optics.radius_mm.rain` | float | `1.0` |"));
    assert_non_null(strstr(table, "| `optics.radius_mm.cloud` | float | `0.01` |"));
    assert_non_null(strstr(table, "| `species.graupel.enabled` | bool | `true` |"));
    assert_non_null(strstr(table, "| `data.files` | list of strings | `[]` |"));

    /* Every row's setting can be set from the command line; header + rule + 140 rows. */
    int rows = 0;
    for (const char *line = table; *line; line = strchr(line, '\n') + 1) {
        rows++;
        if (rows <= 2)
            continue;
        assert_true(strncmp(line, "| `", 3) == 0);
        char path[128];
        size_t n = strcspn(line + 3, "`");
        snprintf(path, sizeof(path), "%.*s", (int)n, line + 3);
        assert_true(strchr(path, '*') == NULL);
        /* A list of groups, and its elements' settings, are set in files (or element by
         * element once a file made the element): look.layers, look.slices. */
        if (strcmp(path, "look.layers") == 0 || strncmp(path, "look.layers.[i].", 16) == 0 ||
            strcmp(path, "look.slices") == 0 || strncmp(path, "look.slices.[i].", 16) == 0)
            continue;
        /* Setting the default back must succeed (it lies in the range) and change nothing. */
        const char *start = strstr(line + 3, "| `") + 3;
        const char *end = strchr(start, '`');
        char assignment[256];
        snprintf(assignment, sizeof(assignment), "%s=%.*s", path, (int)(end - start), start);
        static struct config cfg, before;
        config_defaults(&cfg);
        memcpy(&before, &cfg, sizeof(cfg));
        assert_true(config_set(&cfg, assignment));
        if (strncmp(path, "camera.", 7) == 0) {
            /* Given, even at its default: the scene has a camera (no framing). */
            assert_true(cfg.camera.given);
            cfg.camera.given = false;
        }
        if (strncmp(path, "optics.radius_mm.", 17) != 0) /* mm to m may round differently */
            assert_memory_equal(&cfg, &before, sizeof(cfg));
    }
    assert_int_equal(rows, 2 + 144);

    /* docs/config-reference.md holds the current table. */
    char doc_path[1024];
    snprintf(doc_path, sizeof(doc_path), "%s/docs/config-reference.md", ANVIL_SOURCE_DIR);
    FILE *doc = fopen(doc_path, "r");
    assert_non_null(doc);
    char *text = read_stream(doc);
    fclose(doc);
    if (!strstr(text, table)) {
        fprintf(stderr, "docs/config-reference.md is out of date: regenerate its table\n");
        fail();
    }
    free(text);
    free(table);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_loaded_bytes_are_all_set),
        cmocka_unit_test(test_good_file),
        cmocka_unit_test(test_int_for_double),
        cmocka_unit_test(test_nested_include),
        cmocka_unit_test(test_include_overrides),
        cmocka_unit_test(test_include_in_tmpdir),
        cmocka_unit_test(test_slice_contours_and_level),
        cmocka_unit_test(test_file_errors),
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_load_keeps_values_read_before_error),
        cmocka_unit_test(test_data_files_glob),
        cmocka_unit_test(test_set_each_type),
        cmocka_unit_test(test_set_errors),
        cmocka_unit_test(test_validate),
        cmocka_unit_test(test_shipped_configs),
        cmocka_unit_test(test_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
