/* Display files through the settings engine: defaults, the shipped displays, --set of each
 * kind, bad values and names, display.mode reaching the walls, the walls list, @include, the
 * command line's routing of --set, and the reference in the docs. */
#include "testutil.h"

#include <glob.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "app/app.h"
#include "common/log.h"
#include "config/display_config.h"

/* The defaults as display_config_defaults set them before the settings engine did. */
static void old_defaults(struct display_config *cfg)
{
    memset(cfg, 0, sizeof(*cfg));
    cfg->type = DISPLAY_TYPE_DESKTOP;
    cfg->stereo = DISPLAY_STEREO_MONO;
    cfg->eye_separation = 0.065;
    cfg->near_m = 0.01;
    cfg->far_m = 1000.0;
    cfg->window_size[0] = 960;
    cfg->window_size[1] = 600;
    cfg->monitor = -1;
    cfg->head.source = DISPLAY_HEAD_FIXED;
    cfg->head.position[2] = 0.6;
    snprintf(cfg->head.device, sizeof(cfg->head.device), "null");
    cfg->navigation.scale = 1e-5;
    cfg->navigation.origin_km[0] = cfg->navigation.origin_km[1] = 30.0;
    cfg->navigation.position[1] = -0.16;
    cfg->navigation.position[2] = -0.45;
    snprintf(cfg->hmd.device, sizeof(cfg->hmd.device), "null");
    cfg->hmd.aberration[0] = cfg->hmd.aberration[1] = cfg->hmd.aberration[2] = 1.0;
    cfg->hmd.distortion[3] = 1.0;
    cfg->hmd.warp = true;
    cfg->openxr.resolution_scale = 1.0; /* binding and space: auto (0) */
    /* Tracked heads and wands came later: calibrations are the identity, the wand is none. */
    snprintf(cfg->head.tracking.axes, sizeof(cfg->head.tracking.axes), "x y z");
    snprintf(cfg->wand.tracking.axes, sizeof(cfg->wand.tracking.axes), "x y z");
    snprintf(cfg->wand.device, sizeof(cfg->wand.device), "null");
    cfg->wand.flystick = true;
    for (int b = 0; b < 4; b++)
        cfg->wand.buttons[b] = b;
    cfg->wand.joystick[0] = 1;
    cfg->wand.joystick_scale[0] = cfg->wand.joystick_scale[1] = 1.0;
    cfg->wand.dead_zone = 0.1;
    cfg->wall_count = 1;
    struct display_wall *w = &cfg->walls[0];
    w->monitor = -1;
    w->rank = -1; /* (walls.[i].rank came later: dealt round the ranks) */
    snprintf(w->name, sizeof(w->name), "screen");
    w->lower_left[0] = -0.26;
    w->lower_left[1] = -0.16;
    w->lower_right[0] = 0.26;
    w->lower_right[1] = -0.16;
    w->upper_left[0] = -0.26;
    w->upper_left[1] = 0.16;
}

static const char *display_file(const char *name)
{
    static char path[1024];
    snprintf(path, sizeof(path), "%s/displays/%s", ANVIL_SOURCE_DIR, name);
    return path;
}

/* Exactly one error since BEFORE, containing each string of the NULL-terminated list. */
static void check_error(unsigned before, ...)
{
    const char *msg = log_last_error();
    assert_int_equal(log_error_count(), before + 1);
    va_list ap;
    va_start(ap, before);
    for (const char *part = va_arg(ap, const char *); part; part = va_arg(ap, const char *)) {
        if (!strstr(msg, part))
            fail_msg("message \"%s\" lacks \"%s\"", msg, part);
    }
    va_end(ap);
}

/* ASSIGNMENT on CFG fails with one message holding each string, and changes nothing. */
static void expect_set_error(const struct display_config *cfg, const char *assignment, ...)
{
    static struct display_config copy;
    memcpy(&copy, cfg, sizeof(copy));
    unsigned before = log_error_count();
    assert_false(display_config_set(&copy, assignment));
    assert_int_equal(log_error_count(), before + 1);
    va_list ap;
    va_start(ap, assignment);
    for (const char *part = va_arg(ap, const char *); part; part = va_arg(ap, const char *)) {
        if (!strstr(log_last_error(), part))
            fail_msg("--set %s: \"%s\" lacks \"%s\"", assignment, log_last_error(), part);
    }
    va_end(ap);
    assert_memory_equal(&copy, cfg, sizeof(copy)); /* nothing half applied */
}

/* TEXT as a display file fails to load with one message holding each string. */
static void expect_load_error(const char *name, const char *text, ...)
{
    static struct display_config cfg;
    const char *path = test_write_file(name, text);
    unsigned before = log_error_count();
    assert_false(display_config_load(path, &cfg));
    assert_int_equal(log_error_count(), before + 1);
    va_list ap;
    va_start(ap, text);
    for (const char *part = va_arg(ap, const char *); part; part = va_arg(ap, const char *)) {
        if (!strstr(log_last_error(), part))
            fail_msg("%s: \"%s\" lacks \"%s\"", name, log_last_error(), part);
    }
    va_end(ap);
}

#define EXPECT_SET_ERROR(cfg, assignment, ...) expect_set_error(cfg, assignment, __VA_ARGS__, NULL)
#define EXPECT_LOAD_ERROR(name, text, ...) expect_load_error(name, text, __VA_ARGS__, NULL)

#define WALL(corners) "{ name = \"w\"; " corners " }"
#define SQUARE                                                                                     \
    "lower_left = [0.0, 0.0, 0.0]; lower_right = [1.0, 0.0, 0.0]; "                                \
    "upper_left = [0.0, 1.0, 0.0];"

static void test_defaults_unchanged(void **state)
{
    static struct display_config got, want;
    display_config_defaults(&got);
    old_defaults(&want);
    assert_memory_equal(&got, &want, sizeof(got));
    /* and they are valid as they stand */
    assert_true(display_config_validate(&got));
    assert_int_equal(got.walls[0].stereo, DISPLAY_STEREO_MONO);
}

static void test_shipped_displays(void **state)
{
    char pattern[1024];
    snprintf(pattern, sizeof(pattern), "%s/displays/*.cfg", ANVIL_SOURCE_DIR);
    glob_t g;
    assert_int_equal(glob(pattern, 0, NULL, &g), 0);
    assert_int_equal(g.gl_pathc, 8);
    static struct display_config cfg;
    for (size_t i = 0; i < g.gl_pathc; i++) {
        if (!display_config_load(g.gl_pathv[i], &cfg))
            fail_msg("%s: %s", g.gl_pathv[i], log_last_error());
        assert_string_equal(cfg.path, g.gl_pathv[i]);
        assert_true(display_config_validate(&cfg)); /* again: nothing changes its mind */
    }
    globfree(&g);

    assert_true(display_config_load(display_file("cave6.cfg"), &cfg));
    assert_int_equal(cfg.type, DISPLAY_TYPE_CAVE);
    assert_int_equal(cfg.wall_count, 6);
    assert_string_equal(cfg.walls[5].name, "ceiling");
    assert_int_equal(cfg.walls[5].stereo, DISPLAY_STEREO_ANAGLYPH); /* from display.mode */
    assert_false(cfg.walls[5].stereo_set);
    assert_true(cfg.walls[2].viewport_set);
    assert_int_equal(cfg.walls[2].viewport[0], 800);
    assert_int_equal(cfg.walls[2].viewport[3], 400);
    assert_int_equal(cfg.walls[0].monitor, -1);
    assert_int_equal(cfg.walls[1].line, 33); /* its "{" in the file */
    assert_false(cfg.navigation.given); /* the domain is fitted to the room */

    assert_true(display_config_load(display_file("cave4.cfg"), &cfg));
    assert_int_equal(cfg.walls[3].monitor, 3);
    assert_false(cfg.walls[3].viewport_set);
    assert_int_equal(cfg.walls[3].viewport[2], 0);
    assert_true(cfg.head.position[1] == 1.6 && cfg.head.position[2] == 0.5);
    assert_int_equal(cfg.window_size[0], 768);

    assert_true(display_config_load(display_file("hmd.cfg"), &cfg));
    assert_int_equal(cfg.head.source, DISPLAY_HEAD_OPENHMD);
    assert_string_equal(cfg.head.device, "null");
    assert_true(cfg.hmd.distortion_set && cfg.hmd.aberration_set);
    assert_true(cfg.hmd.distortion[0] == 0.247 && cfg.hmd.distortion[3] == 0.795);
    assert_true(cfg.hmd.aberration[2] == 1.015);
    assert_int_equal(cfg.wall_count, 1); /* no walls in the file: the default one */
    assert_string_equal(cfg.walls[0].name, "screen");

    assert_true(display_config_load(display_file("desktop.cfg"), &cfg));
    assert_false(cfg.hmd.distortion_set);
    assert_true(cfg.hmd.distortion[3] == 1.0);
    assert_true(cfg.navigation.orientation_deg[1] == 10.0);

    /* The tracked CAVEs: cave4's walls, a tracker's head and wand, their addresses read. */
    assert_true(display_config_load(display_file("cave4-dtrack.cfg"), &cfg));
    assert_int_equal(cfg.wall_count, 4);
    assert_int_equal(cfg.head.source, DISPLAY_HEAD_DTRACK);
    assert_string_equal(cfg.head.tracking.host, "");
    assert_int_equal(cfg.head.tracking.port, 5000);
    assert_int_equal(cfg.head.tracking.units, DISPLAY_UNITS_MM);
    const int z_up[3] = {1, 3, -2};
    assert_memory_equal(cfg.head.tracking.axis_map, z_up, sizeof(z_up));
    assert_int_equal(cfg.wand.source, DISPLAY_WAND_DTRACK);
    assert_true(cfg.wand.flystick);
    assert_memory_equal(cfg.wand.tracking.axis_map, z_up, sizeof(z_up));
    assert_true(display_config_load(display_file("cave4-vrpn.cfg"), &cfg));
    assert_int_equal(cfg.head.source, DISPLAY_HEAD_VRPN);
    assert_string_equal(cfg.head.tracking.device, "Head");
    assert_string_equal(cfg.head.tracking.host, "tracker.local");
    assert_int_equal(cfg.head.tracking.port, 3883);
    assert_int_equal(cfg.wand.source, DISPLAY_WAND_VRPN);
    assert_string_equal(cfg.wand.controls_device, "Wand");
    assert_int_equal(cfg.wand.controls_port, 3883);
}

/* Tracked heads and wands: addresses of each protocol's form, axes that form a rotation, a
 * controls device only for VRPN; passive walls name the right eye's output.  Every message
 * names the file, the line and the setting. */
static void test_tracker_settings(void **state)
{
    static struct display_config cfg;
    display_config_defaults(&cfg);
    assert_true(display_config_set(&cfg, "head.source=dtrack"));
    unsigned before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "head.address: expected \"PORT\" or \"ADDRESS:PORT\"", NULL);
    assert_true(display_config_set(&cfg, "head.address=239.255.42.99:5001"));
    assert_true(display_config_validate(&cfg));
    assert_string_equal(cfg.head.tracking.host, "239.255.42.99");
    assert_int_equal(cfg.head.tracking.port, 5001);
    assert_true(display_config_set(&cfg, "head.address=dtrack.local:5000"));
    assert_false(display_config_validate(&cfg));
    assert_true(display_config_set(&cfg, "head.address=70000"));
    assert_false(display_config_validate(&cfg));
    assert_true(display_config_set(&cfg, "head.source=vrpn"));
    before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "head.address: expected \"Device@host\"", "got \"70000\"", NULL);
    assert_true(display_config_set(&cfg, "head.address=DTrack@10.0.0.2:3884"));
    assert_true(display_config_validate(&cfg));
    assert_string_equal(cfg.head.tracking.device, "DTrack");
    assert_int_equal(cfg.head.tracking.port, 3884);
    assert_true(display_config_set(&cfg, "head.axes=x x z"));
    before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "head.axes: expected three tracker axes that form a rotation", NULL);
    assert_true(display_config_set(&cfg, "head.axes=x y -z")); /* a mirror */
    assert_false(display_config_validate(&cfg));
    assert_true(display_config_set(&cfg, "head.axes=-z y x"));
    assert_true(display_config_validate(&cfg));
    EXPECT_SET_ERROR(&cfg, "head.units=inch", "--set head.units: expected one of \"auto\"");
    EXPECT_SET_ERROR(&cfg, "wand.buttons=[0,1,2,64]", "--set wand.buttons: expected [4 numbers]");

    EXPECT_LOAD_ERROR("wandsrc.cfg", "head = { source = \"fixed\"; };\nwand = {\n"
                                     "  source = \"dtrack\";\n  address = \"5000\";\n"
                                     "  controls = \"Buttons@localhost\";\n};\n",
                      "wandsrc.cfg:5: wand.controls: expected no controls device unless "
                      "wand.source = \"vrpn\"");
    EXPECT_LOAD_ERROR("noaddr.cfg", "head = {\n  source = \"vrpn\";\n};\n",
                      "noaddr.cfg:2: head.address: expected \"Device@host\"");
    EXPECT_LOAD_ERROR("passive.cfg",
                      "walls = (\n{ name = \"a\"; " SQUARE " mode = \"passive\";\n"
                      "  output = \"DP-1\"; } );\n",
                      "passive.cfg:2: walls.[0].right_output: expected the right eye's output");
    EXPECT_LOAD_ERROR("passive-vp.cfg",
                      "walls = (\n{ name = \"a\"; " SQUARE " mode = \"passive\";\n"
                      "  right_output = \"DP-2\"; viewport = [0, 0, 10, 10]; } );\n",
                      "passive-vp.cfg:2: walls.[0].viewport: expected no viewport");
    EXPECT_LOAD_ERROR("notpassive.cfg",
                      "walls = (\n{ name = \"a\"; " SQUARE " right_output = \"DP-2\"; } );\n",
                      "notpassive.cfg:2: walls.[0].mode: expected mode = \"passive\"");
    const char *ok = test_write_file(
        "passive-ok.cfg", "display = { type = \"cave\"; };\nwalls = (\n{ name = \"a\"; " SQUARE
                          " mode = \"passive\"; output = \"DP-1\"; right_window = [1920, 0, "
                          "1920, 1080]; } );\n");
    assert_true(display_config_load(ok, &cfg));
    assert_int_equal(cfg.walls[0].stereo, DISPLAY_STEREO_PASSIVE);
    assert_string_equal(cfg.walls[0].output, "DP-1");
    assert_true(cfg.walls[0].right_window_set && cfg.walls[0].right_window[2] == 1920);
}

static void test_set_each_kind(void **state)
{
    static struct display_config cfg;
    assert_true(display_config_load(display_file("cave4.cfg"), &cfg));
    /* a number, in any of the ways a number is written */
    assert_true(display_config_set(&cfg, "display.eye_separation=0.07"));
    assert_true(cfg.eye_separation == 0.07);
    assert_true(display_config_set(&cfg, "navigation.scale=2e-4"));
    assert_true(cfg.navigation.scale == 2e-4);
    assert_true(display_config_set(&cfg, " display.far = 50 "));
    assert_true(cfg.far_m == 50.0);
    assert_true(display_config_set(&cfg, "display.monitor=-1"));
    assert_int_equal(cfg.monitor, -1);
    /* vectors */
    assert_true(display_config_set(&cfg, "head.position=[0,1.7,0.4]"));
    assert_true(cfg.head.position[0] == 0.0 && cfg.head.position[1] == 1.7 &&
                cfg.head.position[2] == 0.4);
    assert_true(display_config_set(&cfg, "display.window_size=640,480"));
    assert_int_equal(cfg.window_size[0], 640);
    assert_int_equal(cfg.window_size[1], 480);
    assert_false(cfg.hmd.distortion_set);
    assert_true(display_config_set(&cfg, "hmd.distortion=(0.1, 0.2, 0.3, 0.4)"));
    assert_true(cfg.hmd.distortion_set); /* given now: it replaces the device's */
    assert_true(cfg.hmd.distortion[2] == 0.3);
    /* enums, quoted or not */
    assert_true(display_config_set(&cfg, "display.type=headless"));
    assert_int_equal(cfg.type, DISPLAY_TYPE_HEADLESS);
    assert_true(display_config_set(&cfg, "head.source=\"openhmd\""));
    assert_int_equal(cfg.head.source, DISPLAY_HEAD_OPENHMD);
    /* bools */
    assert_true(display_config_set(&cfg, "hmd.warp=false"));
    assert_false(cfg.hmd.warp);
    assert_true(display_config_set(&cfg, "hmd.warp=yes"));
    assert_true(cfg.hmd.warp);
    /* short strings */
    assert_true(display_config_set(&cfg, "hmd.device=Rift"));
    assert_string_equal(cfg.hmd.device, "Rift");
    assert_true(display_config_set(&cfg, "head.device=\"HTC Vive\""));
    assert_string_equal(cfg.head.device, "HTC Vive");
    /* a path from the command line is relative to the working folder: kept as given */
    assert_true(display_config_set(&cfg, "head.path=paths/walk.txt"));
    assert_string_equal(cfg.head.path, "paths/walk.txt");
    assert_true(display_config_set(&cfg, "head.path=/abs/walk.txt"));
    assert_string_equal(cfg.head.path, "/abs/walk.txt");
    /* one wall's settings */
    assert_false(cfg.walls[2].stereo_set);
    assert_true(display_config_set(&cfg, "walls.[2].mode=anaglyph"));
    assert_int_equal(cfg.walls[2].stereo, DISPLAY_STEREO_ANAGLYPH);
    assert_true(cfg.walls[2].stereo_set);
    assert_int_equal(cfg.walls[1].stereo, DISPLAY_STEREO_QUAD_BUFFER); /* not a neighbour */
    assert_true(display_config_set(&cfg, "walls.[3].name=ground"));
    assert_string_equal(cfg.walls[3].name, "ground");
    assert_true(display_config_set(&cfg, "walls.[0].size=[100,50]"));
    assert_int_equal(cfg.walls[0].size[0], 100);
    assert_int_equal(cfg.walls[0].size[1], 50);
    assert_true(display_config_set(&cfg, "walls.[0].viewport=[0,0,10,20]"));
    assert_true(cfg.walls[0].viewport_set);
    assert_int_equal(cfg.walls[0].viewport[3], 20);
    assert_true(display_config_set(&cfg, "walls.[1].upper_left=[-1.5,2.0,1.5]"));
    assert_true(cfg.walls[1].upper_left[1] == 2.0);
    assert_int_equal(cfg.wall_count, 4);
    assert_true(display_config_validate(&cfg));
}

static void test_set_errors(void **state)
{
    static struct display_config cfg;
    assert_true(display_config_load(display_file("cave4.cfg"), &cfg));
    EXPECT_SET_ERROR(&cfg, "display.eye_separation=2",
                     "--set display.eye_separation: expected a number in [0, 1], got 2");
    EXPECT_SET_ERROR(&cfg, "display.eye_separation=wide", "expected a number", "\"wide\"");
    EXPECT_SET_ERROR(&cfg, "display.near=0", "--set display.near: expected a number in (0, 1000]");
    EXPECT_SET_ERROR(&cfg, "display.monitor=1.5", "expected an integer in [-1, 64], got 1.5");
    EXPECT_SET_ERROR(&cfg, "display.eye_separation", "--set display.eye_separation:",
                     "expected SETTING=VALUE, e.g. display.eye_separation=0.07");
    EXPECT_SET_ERROR(&cfg, "head.position=[0,1.7]",
                     "--set head.position: expected [3 numbers] "
                     "each a number in [-10000, 10000], got [0, 1.7]");
    EXPECT_SET_ERROR(&cfg, "head.position=[0,1e5,0]", "--set head.position: expected [3 numbers]",
                     "got [0, 100000.0, 0]");
    EXPECT_SET_ERROR(&cfg, "display.window_size=[800.0,600]",
                     "--set display.window_size: "
                     "expected [2 numbers] each an integer in [1, 16384]");
    EXPECT_SET_ERROR(&cfg, "display.mode=polarised",
                     "--set display.mode: expected one of "
                     "\"mono\", \"side-by-side\", \"anaglyph\", \"quad-buffer\", "
                     "\"passive\", got \"polarised\"");
    EXPECT_SET_ERROR(&cfg, "hmd.warp=maybe", "--set hmd.warp: expected true or false", "\"maybe\"");
    EXPECT_SET_ERROR(&cfg, "hmd.device=",
                     "--set hmd.device: expected a string of 1 to 127 "
                     "characters");
    char longname[64];
    snprintf(longname, sizeof(longname), "walls.[0].name=%040d", 7);
    EXPECT_SET_ERROR(&cfg, longname, "--set walls.[0].name: expected a string of 1 to 31");
    /* unknown names: the closest known one, or what is known */
    EXPECT_SET_ERROR(&cfg, "head.postion=[0,1,0]",
                     "--set head.postion: expected a known setting (did you mean "
                     "head.position?)");
    EXPECT_SET_ERROR(&cfg, "head.zz=1",
                     "--set head.zz: expected a known setting (one of "
                     "source, position, orientation, path, device, address, sensor, units, axes, offset, "
                     "rotation)");
    EXPECT_SET_ERROR(&cfg, "screens.x=1",
                     "--set screens.x: expected a known group (display, "
                     "head, navigation, hmd, openxr, wand, walls)");
    EXPECT_SET_ERROR(&cfg, "walls.[0].nmae=x",
                     "--set walls.[0].nmae: expected a known "
                     "setting (did you mean walls.[0].name?)");
    EXPECT_SET_ERROR(&cfg, "head=1",
                     "--set head: expected a setting, not a group "
                     "(e.g. head.source)");
    /* the walls: one element's settings, of an element that exists */
    EXPECT_SET_ERROR(&cfg, "walls.[4].mode=mono",
                     "--set walls.[4].mode: expected a wall "
                     "index in [0, 3] (there are 4 walls), got 4");
    EXPECT_SET_ERROR(&cfg, "walls.[x].mode=mono",
                     "--set walls.[x].mode: expected "
                     "walls.[INDEX].SETTING");
    EXPECT_SET_ERROR(&cfg, "walls.0.mode=mono", "expected walls.[INDEX].SETTING");
    EXPECT_SET_ERROR(&cfg, "walls.[1]=x", "--set walls.[1]: expected a setting, not a group");
    EXPECT_SET_ERROR(&cfg, "walls=()", "--set walls: expected a setting, not a list of walls");
    EXPECT_SET_ERROR(&cfg, "walls.[0].mode=stereo", "expected one of \"mono\"");
}

static void test_mode_reaches_walls(void **state)
{
    static struct display_config cfg;
    /* The wall naming its own mode is written before display.mode. */
    const char *path =
        test_write_file("modes.cfg", "walls = ( { name = \"a\"; " SQUARE " },\n"
                                     "  { name = \"b\"; mode = \"mono\"; " SQUARE " } );\n"
                                     "display = { mode = \"side-by-side\"; };\n");
    assert_true(display_config_load(path, &cfg));
    assert_int_equal(cfg.walls[0].stereo, DISPLAY_STEREO_SIDE_BY_SIDE);
    assert_int_equal(cfg.walls[1].stereo, DISPLAY_STEREO_MONO);
    assert_true(display_config_set(&cfg, "display.mode=anaglyph"));
    assert_int_equal(cfg.walls[0].stereo, DISPLAY_STEREO_SIDE_BY_SIDE); /* until validated */
    assert_true(display_config_validate(&cfg));
    assert_int_equal(cfg.walls[0].stereo, DISPLAY_STEREO_ANAGLYPH);
    assert_int_equal(cfg.walls[1].stereo, DISPLAY_STEREO_MONO); /* its own */

    /* cave4: every wall follows; one set to its own mode stays there whatever comes later. */
    assert_true(display_config_load(display_file("cave4.cfg"), &cfg));
    assert_true(display_config_set(&cfg, "walls.[1].mode=mono"));
    assert_true(display_config_set(&cfg, "display.mode=anaglyph"));
    assert_true(display_config_validate(&cfg));
    const enum display_stereo want[] = {DISPLAY_STEREO_ANAGLYPH, DISPLAY_STEREO_MONO,
                                        DISPLAY_STEREO_ANAGLYPH, DISPLAY_STEREO_ANAGLYPH};
    for (int w = 0; w < 4; w++)
        assert_int_equal(cfg.walls[w].stereo, want[w]);
    assert_int_equal(cfg.stereo, DISPLAY_STEREO_ANAGLYPH);

    /* the default wall follows too */
    display_config_defaults(&cfg);
    assert_true(display_config_set(&cfg, "display.mode=quad-buffer"));
    assert_true(display_config_validate(&cfg));
    assert_int_equal(cfg.walls[0].stereo, DISPLAY_STEREO_QUAD_BUFFER);
}

static void test_validate_after_set(void **state)
{
    static struct display_config cfg;
    const char *cave = display_file("cave4.cfg");
    assert_true(display_config_load(cave, &cfg));
    assert_true(display_config_set(&cfg, "head.source=path"));
    unsigned before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "cave4.cfg: head.path: expected a pose file when head.source = \"path\"",
                NULL);
    assert_true(display_config_set(&cfg, "head.path=walk.txt"));
    assert_true(display_config_validate(&cfg));

    assert_true(display_config_load(cave, &cfg));
    assert_true(display_config_set(&cfg, "walls.[2].upper_left=[1.5,3.0,-1.0]"));
    before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "cave4.cfg: walls.[2].upper_left: expected corners of a rectangle", NULL);

    assert_true(display_config_load(cave, &cfg));
    assert_true(display_config_set(&cfg, "walls.[3].name=left"));
    before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "walls.[3].name: expected a name no other wall has", NULL);

    assert_true(display_config_load(cave, &cfg));
    assert_true(display_config_set(&cfg, "walls.[0].name=front/wall"));
    before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "walls.[0].name: expected letters, digits", NULL);

    assert_true(display_config_load(cave, &cfg));
    assert_true(display_config_set(&cfg, "walls.[1].viewport=[0,0,0,100]"));
    before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "walls.[1].viewport: expected [x, y, w, h] with w, h >= 1", NULL);
    assert_true(display_config_set(&cfg, "walls.[1].viewport=[0,0,1,100]"));
    assert_true(display_config_validate(&cfg));

    /* No file: the message names the setting alone. */
    display_config_defaults(&cfg);
    assert_true(display_config_set(&cfg, "head.source=path"));
    before = log_error_count();
    assert_false(display_config_validate(&cfg));
    check_error(before, "head.path: expected a pose file", NULL);
    assert_null(strstr(log_last_error(), ".cfg"));
}

static void test_walls_errors(void **state)
{
    EXPECT_LOAD_ERROR("array.cfg", "\nwalls = [1, 2];\n",
                      "array.cfg:2: walls: expected a list ( { ... }, { ... } ) of walls, got "
                      "an array");
    EXPECT_LOAD_ERROR("group.cfg", "walls = { a = 1; };\n", "group.cfg:1: walls: expected a list");
    EXPECT_LOAD_ERROR("none.cfg", "walls = ();\n",
                      "none.cfg:1: walls: expected 1 to 8 walls, "
                      "got 0");
    char nine[4096] = "walls = (\n";
    for (int i = 0; i < 9; i++) {
        char wall[256];
        snprintf(wall, sizeof(wall), "%s{ name = \"w%d\"; " SQUARE " }\n", i ? "," : "", i);
        strcat(nine, wall);
    }
    strcat(nine, ");\n");
    EXPECT_LOAD_ERROR("nine.cfg", nine, "nine.cfg:1: walls: expected 1 to 8 walls, got 9");
    EXPECT_LOAD_ERROR("elem.cfg", "walls = ( " WALL(SQUARE) ",\n 3 );\n",
                      "elem.cfg:2: walls.[1]: expected a group { ... }, got 3");
    EXPECT_LOAD_ERROR("member.cfg",
                      "walls = ( { name = \"a\"; " SQUARE "\n  moed = \"mono\"; } );\n",
                      "member.cfg:2: walls.[0].moed: expected a known setting (did you mean "
                      "walls.[0].mode?)");
    EXPECT_LOAD_ERROR("noname.cfg", "walls = (\n {\n " SQUARE " } );\n",
                      "noname.cfg:2: walls.[0].name: expected a setting \"name\" in every wall");
    EXPECT_LOAD_ERROR("badname.cfg", "walls = (\n { name = \"a b\"; " SQUARE " } );\n",
                      "badname.cfg:2: walls.[0].name: expected letters, digits, '-' and '_'");
    EXPECT_LOAD_ERROR("empty.cfg", "walls = ( { name = \"\"; " SQUARE " } );\n",
                      "empty.cfg:1: walls.[0].name: expected a string of 1 to 31 characters");
    EXPECT_LOAD_ERROR("view.cfg",
                      "walls = (\n{ name = \"a\"; " SQUARE "\n viewport = [0, 0, 100, 0]; } );\n",
                      "view.cfg:2: walls.[0].viewport: expected [x, y, w, h] with w, h >= 1");
    EXPECT_LOAD_ERROR("mode.cfg", "walls = ( { name = \"a\"; " SQUARE "\n mode = 3; } );\n",
                      "mode.cfg:2: walls.[0].mode: expected one of \"mono\"");
    EXPECT_LOAD_ERROR("zero.cfg",
                      "walls = (\n { name = \"a\"; lower_left = [0.0, 0.0, 0.0];\n"
                      " lower_right = [0.0, 0.0, 0.0]; upper_left = [0.0, 1.0, 0.0]; } );\n",
                      "zero.cfg:2: walls.[0].upper_left: expected corners of a rectangle");
}

static void test_include_and_paths(void **state)
{
    char sub[1024];
    snprintf(sub, sizeof(sub), "%s", test_tmp_path("room"));
    mkdir(sub, 0755);
    test_write_file("room/walls.cfg", "walls = (\n  { name = \"front\"; " SQUARE " },\n"
                                      "  { name = \"front\"; " SQUARE " } );\n");
    test_write_file("room/head.cfg", "head = { source = \"path\"; path = \"walk.txt\"; };\n");
    test_write_file("room/good_walls.cfg", "walls = ( { name = \"one\"; " SQUARE " } );\n");
    /* An error in an included file names that file and its own line. */
    const char *dup = test_write_file("dup.cfg", "display = { type = \"cave\"; };\n"
                                                 "@include \"room/walls.cfg\"\n");
    static struct display_config cfg;
    unsigned before = log_error_count();
    assert_false(display_config_load(dup, &cfg));
    check_error(before, "room/walls.cfg:3: walls.[1].name: expected a name no other wall has",
                NULL);
    /* A path is relative to the file that names it, an included one too. */
    const char *top = test_write_file("top.cfg", "@include \"room/head.cfg\"\n"
                                                 "@include \"room/good_walls.cfg\"\n"
                                                 "display = { mode = \"anaglyph\"; };\n");
    assert_true(display_config_load(top, &cfg));
    char want[1024];
    snprintf(want, sizeof(want), "%s/room/walk.txt", test_tmpdir());
    assert_string_equal(cfg.head.path, want);
    assert_string_equal(cfg.walls[0].name, "one");
    assert_int_equal(cfg.walls[0].stereo, DISPLAY_STEREO_ANAGLYPH);
    assert_int_equal(cfg.walls[0].line, 1);
    /* A list after an @include replaces the included one, and the other way round. */
    const char *later = test_write_file("later.cfg", "@include \"room/good_walls.cfg\"\n"
                                                     "walls = ( { name = \"a\"; " SQUARE " },\n"
                                                     "  { name = \"b\"; " SQUARE " } );\n");
    assert_true(display_config_load(later, &cfg));
    assert_int_equal(cfg.wall_count, 2);
    assert_string_equal(cfg.walls[1].name, "b");
    assert_int_equal(cfg.walls[1].line, 3);
    const char *earlier = test_write_file(
        "earlier.cfg", "walls = ( { name = \"a\"; " SQUARE " },\n  { name = \"b\"; " SQUARE
                       " } );\n@include \"room/good_walls.cfg\"\n");
    assert_true(display_config_load(earlier, &cfg));
    assert_int_equal(cfg.wall_count, 1);
    assert_string_equal(cfg.walls[0].name, "one");
    /* A misspelt group: what the file may hold. */
    EXPECT_LOAD_ERROR("typo.cfg", "\n\nnavigaton = { scale = 1.0; };\n",
                      "typo.cfg:3: navigaton: expected a known group (did you mean "
                      "navigation?)");
    EXPECT_LOAD_ERROR("notgroup.cfg", "head = 3;\n",
                      "notgroup.cfg:1: head: expected a group { ... }, got 3");
}

static void test_has_setting(void **state)
{
    const char *mine[] = {"display.eye_separation",
                          "display.eye_separation=0.07",
                          "head.position=[0,1.7,0.4]",
                          "navigation.scale=2e-4",
                          "hmd.warp",
                          "walls.[0].mode=anaglyph",
                          "head.postion=1",
                          " head.source = path",
                          "walls=()",
                          "display"};
    const char *theirs[] = {"light.elevation=10",
                            "scene.size=[32,32,16]",
                            "effects.distortion=on",
                            "displays.mode=x",
                            "heads.x=1",
                            "wall.[0].mode=x",
                            "",
                            "=3",
                            "render.height=32"};
    for (size_t i = 0; i < sizeof(mine) / sizeof(mine[0]); i++) {
        if (!display_config_has_setting(mine[i]))
            fail_msg("%s is a display setting", mine[i]);
    }
    for (size_t i = 0; i < sizeof(theirs) / sizeof(theirs[0]); i++) {
        if (display_config_has_setting(theirs[i]))
            fail_msg("%s is not a display setting", theirs[i]);
    }
}

static void test_route_sets(void **state)
{
    char a[] = "light.elevation=10", b[] = "display.eye_separation=0.07", c[] = "scene.seed=3",
         d[] = "walls.[0].mode=mono";
    char *sets[] = {a, b, c, d}, *display[4];
    int n = 4, n_display = -1;
    assert_true(app_route_sets(sets, &n, true, display, &n_display));
    assert_int_equal(n, 2);
    assert_ptr_equal(sets[0], a);
    assert_ptr_equal(sets[1], c);
    assert_int_equal(n_display, 2);
    assert_ptr_equal(display[0], b);
    assert_ptr_equal(display[1], d);

    char *again[] = {a, b};
    n = 2;
    unsigned before = log_error_count();
    assert_false(app_route_sets(again, &n, false, display, &n_display));
    check_error(before, "display.eye_separation is a display setting: it needs --display FILE",
                NULL);
    assert_null(strstr(log_last_error(), "0.07"));

    /* the display's --set after the file, then validated */
    static struct display_config cfg;
    char e[] = "display.mode=anaglyph", f[] = "head.source=path";
    char *good[] = {e, b};
    assert_true(app_load_display_config(display_file("cave4.cfg"), good, 2, &cfg));
    assert_true(cfg.eye_separation == 0.07);
    assert_int_equal(cfg.walls[3].stereo, DISPLAY_STEREO_ANAGLYPH);
    char *bad[] = {f};
    assert_false(app_load_display_config(display_file("cave4.cfg"), bad, 1, &cfg));
    assert_non_null(strstr(log_last_error(), "head.path: expected a pose file"));
}

static char *read_all(const char *path)
{
    char *text = file_read_all(path, NULL);
    assert_non_null(text);
    return text;
}

/* The reference: current in both docs, and every default it shows is a valid --set that
 * changes nothing. */
static void test_reference(void **state)
{
    char *table = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&table, &len);
    assert_non_null(f);
    display_config_write_reference(f);
    fclose(f);
    assert_non_null(strstr(table, "| setting | type | default | range | description |\n"));
    assert_non_null(strstr(table, "| `display.eye_separation` | float | `0.065` | [0, 1] |"));
    assert_non_null(strstr(table, "| `head.device` | string | `\"null\"` | 1 to 127 characters |"));
    assert_non_null(strstr(table, "| `head.path` | path | `\"\"` |"));
    assert_non_null(strstr(table, "| `walls` | list of groups | `( { name = \"screen\"; "
                                  "lower_left = [-0.26, -0.16, 0.0];"));
    assert_non_null(strstr(table, "| 1 to 8 walls |"));
    assert_non_null(strstr(table, "| `walls.[i].name` | string | required |"));
    assert_non_null(strstr(table, "| `walls.[i].mode` | string | display.mode |"));

    int rows = 0, set_back = 0;
    for (const char *line = table; *line; line = strchr(line, '\n') + 1) {
        if (++rows <= 2)
            continue;
        assert_int_equal(strncmp(line, "| `", 3), 0);
        char path[128];
        size_t n = strcspn(line + 3, "`");
        snprintf(path, sizeof(path), "%.*s", (int)n, line + 3);
        assert_true(display_config_has_setting(path));
        const char *type = strstr(line + 3, "| ") + 2, *cell = strstr(type, "| ") + 2;
        if (strcmp(path, "walls") == 0 || cell[0] != '`')
            continue; /* the list itself; defaults written as words */
        char *wall = strstr(path, ".[i].");
        if (wall)
            memmove(wall + 2, "0", 1); /* walls.[0].monitor */
        const char *end = strchr(cell + 1, '`');
        char assignment[256];
        snprintf(assignment, sizeof(assignment), "%s=%.*s", path, (int)(end - cell - 1), cell + 1);
        static struct display_config cfg, before;
        display_config_defaults(&cfg);
        memcpy(&before, &cfg, sizeof(cfg));
        if (!display_config_set(&cfg, assignment))
            fail_msg("%s: %s", assignment, log_last_error());
        if (strncmp(path, "navigation.", 11) == 0) {
            /* Given, even at its default: the display places the world itself. */
            assert_true(cfg.navigation.given);
            cfg.navigation.given = false;
        }
        assert_memory_equal(&cfg, &before, sizeof(cfg));
        set_back++;
    }
    assert_int_equal(rows, 2 + 57);
    assert_int_equal(set_back, 19 + 4 + 17);

    const char *docs[] = {"/docs/config-reference.md", "/docs/displays.md"};
    for (int i = 0; i < 2; i++) {
        char path[1024];
        snprintf(path, sizeof(path), "%s%s", ANVIL_SOURCE_DIR, docs[i]);
        char *doc = read_all(path);
        if (!strstr(doc, table))
            fail_msg("%s is out of date: regenerate its display table (anvil "
                     "--config-reference)",
                     docs[i] + 1);
        free(doc);
    }
    free(table);
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_unchanged), cmocka_unit_test(test_shipped_displays),
        cmocka_unit_test(test_set_each_kind),      cmocka_unit_test(test_set_errors),
        cmocka_unit_test(test_mode_reaches_walls), cmocka_unit_test(test_validate_after_set),
        cmocka_unit_test(test_walls_errors),       cmocka_unit_test(test_include_and_paths),
        cmocka_unit_test(test_has_setting),        cmocka_unit_test(test_route_sets),
        cmocka_unit_test(test_reference),          cmocka_unit_test(test_tracker_settings),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
