/*
 * The openxr display through the test runtime (tests/xr/runtime.c), which the OpenXR loader
 * loads from the manifest XR_RUNTIME_JSON names.  Argument "xlib": a GLX window (run under
 * xvfb-run) with the Khronos validation layer between anvil and the runtime; "egl": headless,
 * without the layer (Debian 12's layer, 1.0.20, refuses XrGraphicsBindingEGLMNDX in
 * xrCreateSession's chain).
 *
 * Frames go as app/loop.c runs them, each frame state through its bytes before it is drawn:
 *   - the frame state's head is the runtime's, frame by frame (a moving head, then still);
 *   - each eye's view (anvil's own RGBA32F image) puts a sphere where the runtime's pose and
 *     asymmetric field of view put it, to half a pixel, and is finite;
 *   - the images submitted to the runtime are those views tone-mapped, byte for byte, left and
 *     right apart by the disparity the eyes' poses and fields of view give;
 *   - a LOCAL space (no stage) placed at head.position draws the same pictures;
 *   - a trigger press with the aim on a menu tab turns the menu's page, for each interaction
 *     profile (and a press aimed elsewhere does not);
 *   - the runtime stopping the session or losing it ends the run; the runtime found no fault,
 *     and the validation layer (proven to be listening) reported no error.
 */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openxr/openxr.h>

#include "testutil.h"

#include "runtime.h"
#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "menu/menu.h"
#include "session/frame.h"
#include "session/scene.h"
#include "session/session.h"

#define FRAMES_MAX 80
#define LAYER "XR_APILAYER_LUNARG_core_validation"

static bool xlib;
static anvil_xr_test_reset_fn rt_reset;
static anvil_xr_test_script_fn rt_script;
static anvil_xr_test_get_report_fn rt_report;
static anvil_xr_test_image_fn rt_image;
static char validation_file[1024];

struct run {
    struct config cfg;
    struct display_config dcfg;
    struct display *d;
    struct session *s;
    long frames;
};

/* ---- running ---------------------------------------------------------------------------- */

static void open_run(struct run *r, const char *const *scene_sets, int n_scene,
                     const char *const *display_sets, int n_display, bool menu)
{
    memset(r, 0, sizeof(*r));
    test_config_from(&r->cfg, (const char **)scene_sets, n_scene);
    r->cfg.overlay.when = OVERLAY_NEVER; /* the eyes' pictures here are the volume's alone */
    assert_true(display_config_load(ANVIL_SOURCE_DIR "/displays/openxr.cfg", &r->dcfg));
    for (int i = 0; i < n_display; i++)
        assert_true(display_config_set(&r->dcfg, display_sets[i]));
    r->dcfg.openxr.binding = xlib ? DISPLAY_OPENXR_BINDING_XLIB : DISPLAY_OPENXR_BINDING_EGL;
    assert_true(display_config_validate(&r->dcfg));
    struct display_desc dd = {.height = r->cfg.render.height};
    scene_camera(&r->cfg, &dd.camera);
    r->d = display_create(&r->dcfg, &dd);
    assert_non_null(r->d);
    int rc = 0;
    r->s = session_create(&r->cfg,
                          &(struct session_desc){.command = "run",
                                                 .display = &r->dcfg,
                                                 .views_move = true,
                                                 .interactive = true,
                                                 .menu = true,
                                                 .show_menu = menu},
                          &rc);
    assert_non_null(r->s);
}

static void close_run(struct run *r)
{
    gpu_context_make_current(display_context(r->d));
    session_destroy(r->s);
    display_destroy(r->d);
}

/* One frame in app/loop.c's order; the state drawn is the one read back from its bytes. */
static void frame(struct run *r, struct frame_state *drawn)
{
    struct input_queue *q = calloc(1, sizeof(*q));
    assert_non_null(q);
    display_poll_input(r->d, 0.0, q);
    struct frame_state f;
    bool redraw;
    double t = (double)r->frames / 90.0;
    assert_true(session_update(r->s, q, 1.0 / 90.0, t, &f, &redraw));
    free(q);
    assert_true(session_apply(r->s, &f, NULL) && session_light(r->s));
    assert_true(display_sample_head(r->d, f.time_s, &f.head));
    uint8_t bytes[FRAME_STATE_BYTES];
    frame_state_write(&f, bytes);
    assert_true(frame_state_read(bytes, sizeof(bytes), drawn));
    assert_true(session_draw(r->s, r->d, drawn));
    r->frames++;
}

/* Frames until the runtime ends the session (which the script makes it do). */
static void run_to_end(struct run *r)
{
    struct frame_state f;
    while (!display_should_close(r->d) && r->frames < FRAMES_MAX)
        frame(r, &f);
    if (!display_should_close(r->d))
        fail_msg("the run did not end after %d frames though the runtime stopped", FRAMES_MAX);
}

static void expect_clean(const struct anvil_xr_test_report *rep)
{
    for (int i = 0; i < rep->faults && i < ANVIL_XR_TEST_FAULTS_KEPT; i++)
        print_error("runtime fault: %s\n", rep->fault[i]);
    assert_int_equal(rep->faults, 0);
    assert_int_equal(rep->frames_begun, rep->frames_ended);
    assert_string_equal(rep->binding, xlib ? "xlib" : "egl");
}

/* ---- images ----------------------------------------------------------------------------- */

/* The sphere's image in anvil's view of eye E: the centroid of its opacity (1 - alpha). */
static void opacity_centroid(struct display *d, int e, double out[2], size_t *nonfinite)
{
    struct image img;
    assert_true(renderer_read(&display_view(d, e)->target, &img));
    *nonfinite = image_count_nonfinite(&img);
    double sw = 0.0, sx = 0.0, sy = 0.0;
    for (int y = 0; y < img.height; y++) {
        for (int x = 0; x < img.width; x++) {
            double w = 1.0 - img.rgba[4 * ((size_t)y * img.width + x) + 3];
            sw += w;
            sx += w * (x + 0.5);
            sy += w * (y + 0.5);
        }
    }
    assert_true(sw > 5.0); /* the sphere is in view */
    out[0] = sx / sw;
    out[1] = sy / sw;
    image_finish(&img);
}

/* The centroid of what differs from the background (pixel 0) in a submitted RGBA8 image, and
 * the spread of its values. */
static void image_centroid(const uint8_t *px, int w, int h, double out[2], double *spread)
{
    double sw = 0.0, sx = 0.0, sy = 0.0, mean = 0.0, sq = 0.0;
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            const uint8_t *p = px + 4 * ((size_t)y * w + x);
            double dw = abs(p[0] - px[0]) + abs(p[1] - px[1]) + abs(p[2] - px[2]);
            double l = p[0] + p[1] + p[2];
            mean += l;
            sq += l * l;
            sw += dw;
            sx += dw * (x + 0.5);
            sy += dw * (y + 0.5);
        }
    }
    double n = (double)w * h;
    mean /= n;
    *spread = sqrt(fmax(0.0, sq / n - mean * mean));
    assert_true(sw > 0.0);
    out[0] = sx / sw;
    out[1] = sy / sw;
}

/* Where a point straight ahead at DISTANCE m and height 0 relative to the head lands in an
 * eye at EYE_X (m right of the head) with the field of view FOV (degrees: left right up
 * down), image W x H: pixels from the left and from the bottom. */
static void project(double eye_x, double distance, const double fov[4], int w, int h, double out[2])
{
    double tl = tan(fov[0] * M_PI / 180.0), tr = tan(fov[1] * M_PI / 180.0);
    double tu = tan(fov[2] * M_PI / 180.0), td = tan(fov[3] * M_PI / 180.0);
    out[0] = ((0.0 - eye_x) / distance - tl) / (tr - tl) * w;
    out[1] = (0.0 - td) / (tu - td) * h;
}

/* ---- the tests -------------------------------------------------------------------------- */

static const char *const sphere_scene[] = {
    "scene.kind=\"sphere\"",          "scene.extent=[10,10,10]", "scene.size=[32,32,32]",
    "lightmap.resolution=[24,24,24]", "render.ground_on=false",  "render.height=64",
};
/* The sphere (radius 0.05 m) 1 m in front of a head at (0, 1.6, 0). */
static const char *const sphere_display[] = {
    "navigation.scale=1e-5",
    "navigation.origin=[5,5,5]",
    "navigation.position=[0,1.6,-1.0]",
};

#define W 120
#define H 100
static const double fov_left[4] = {-50.0, 40.0, 45.0, -55.0};
static const double fov_right[4] = {-40.0, 50.0, 45.0, -55.0};
static const char eyes_script[] = "size 120 100\n"
                                  "fov left -50 40 45 -55\n"
                                  "fov right -40 50 45 -55\n"
                                  "eye left -0.032 0 0\n"
                                  "eye right 0.032 0 0\n"
                                  "0 head 0.05 1.5 0.1 10 0 0\n"
                                  "6 head 0 1.6 0 0 0 0\n"
                                  "14 exit\n";

static uint8_t *stage_image[2];

/* Eyes, frame states and images with the STAGE space (LOCAL with NO_STAGE). */
static void eyes_run(bool no_stage)
{
    char script[1024];
    snprintf(script, sizeof(script), "%s%s", no_stage ? "stage off\n" : "", eyes_script);
    assert_true(rt_reset(script));
    struct run r;
    open_run(&r, sphere_scene, 6, sphere_display, 3, false);
    struct frame_state f;
    while (!display_should_close(r.d) && r.frames < FRAMES_MAX) {
        frame(&r, &f);
        struct anvil_xr_test_report rep;
        rt_report(&rep);
        long k = rep.frames_waited - 1; /* the runtime's frame this state was sampled in */
        if (k < 0)
            continue;
        /* The frame state carries the headset's pose: the scripted one of that frame. */
        double yaw = k < 6 ? 10.0 : 0.0;
        const float want_p[3] = {k < 6 ? 0.05f : 0.0f, k < 6 ? 1.5f : 1.6f, k < 6 ? 0.1f : 0.0f};
        for (int i = 0; i < 3; i++)
            assert_float_equal(f.head.position[i], want_p[i], 1e-5);
        assert_float_equal(f.head.rotation[1], sin(0.5 * yaw * M_PI / 180.0), 1e-5);
        assert_float_equal(f.head.rotation[3], cos(0.5 * yaw * M_PI / 180.0), 1e-5);
    }
    assert_true(display_should_close(r.d));
    struct anvil_xr_test_report rep;
    rt_report(&rep);
    expect_clean(&rep);
    assert_true(rep.layers >= 10);
    assert_string_equal(rep.layer_space, no_stage ? "local" : "stage");
    assert_non_null(strstr(rep.states, "STOPPING IDLE EXITING"));
    /* The layer's eyes are where the runtime put them. */
    assert_true(rep.pose_error < 1e-4f);
    for (int e = 0; e < 2; e++) {
        const double *fov = e == 0 ? fov_left : fov_right;
        for (int i = 0; i < 4; i++)
            assert_float_equal(rep.layer_fov[e][i], fov[i] * M_PI / 180.0, 1e-6);
    }

    /* Anvil's own views: the sphere where the eyes' poses and fields of view put it. */
    double c[2][2], want[2][2];
    for (int e = 0; e < 2; e++) {
        size_t nonfinite;
        opacity_centroid(r.d, e, c[e], &nonfinite);
        assert_int_equal(nonfinite, 0);
        project(e == 0 ? -0.032 : 0.032, 1.0, e == 0 ? fov_left : fov_right, W, H, want[e]);
        print_message("eye %d: sphere at (%.2f, %.2f) px, projected (%.2f, %.2f)\n", e, c[e][0],
                      c[e][1], want[e][0], want[e][1]);
        assert_float_equal(c[e][0], want[e][0], 0.5);
        assert_float_equal(c[e][1], want[e][1], 0.5);
    }

    /* What the runtime got: each view tone-mapped, byte for byte. */
    const uint8_t *img[2];
    for (int e = 0; e < 2; e++) {
        int w = 0, h = 0;
        img[e] = rt_image(e, &w, &h);
        assert_non_null(img[e]);
        assert_int_equal(w, W);
        assert_int_equal(h, H);
        struct gpu_texture tm = {0};
        gpu_context_make_current(display_context(r.d));
        float exposure = (float)session_config(r.s)->render.exposure;
        assert_true(
            renderer_tonemap(session_renderer(r.s), &display_view(r.d, e)->target, exposure, &tm));
        uint8_t *mine = malloc((size_t)W * H * 4);
        assert_non_null(mine);
        gpu_texture_read(&tm, mine, (size_t)W * H * 4);
        gpu_texture_finish(&tm);
        assert_memory_equal(mine, img[e], (size_t)W * H * 4);
        free(mine);
    }
    /* Not blank, the two eyes differ, by the disparity expected. */
    double ic[2][2], spread[2];
    for (int e = 0; e < 2; e++) {
        image_centroid(img[e], W, H, ic[e], &spread[e]);
        assert_true(spread[e] > 3.0);
    }
    assert_memory_not_equal(img[0], img[1], (size_t)W * H * 4);
    double disparity = ic[0][0] - ic[1][0], expected = want[0][0] - want[1][0];
    print_message("disparity %.2f px, expected %.2f px (%.2f px of it from the eyes' 64 mm)\n",
                  disparity, expected, 0.064 / (tan(40 * M_PI / 180) + tan(50 * M_PI / 180)) * W);
    assert_float_equal(disparity, expected, 1.0);
    assert_float_equal(ic[0][1], ic[1][1], 0.5);

    if (!no_stage) {
        for (int e = 0; e < 2; e++) {
            stage_image[e] = malloc((size_t)W * H * 4);
            assert_non_null(stage_image[e]);
            memcpy(stage_image[e], img[e], (size_t)W * H * 4);
        }
    } else {
        /* LOCAL at head.position shows what STAGE showed. */
        for (int e = 0; e < 2; e++) {
            assert_non_null(stage_image[e]);
            int worst = 0;
            for (size_t i = 0; i < (size_t)W * H * 4; i++) {
                int dv = abs((int)img[e][i] - (int)stage_image[e][i]);
                worst = dv > worst ? dv : worst;
            }
            assert_true(worst <= 2);
        }
    }
    close_run(&r);
}

static void test_stage_eyes(void **state)
{
    eyes_run(false);
}

static void test_local_space(void **state)
{
    eyes_run(true);
}

/* A press of TRIGGER (an input path) with HAND's aim at tab.light, or next to the menu. */
static void press_run(const char *profile, const char *hand, const char *trigger, bool on_tab)
{
    char script[512];
    snprintf(script, sizeof(script), "size 48 40\nprofile %s\n", profile);
    assert_true(rt_reset(script));
    struct run r;
    const char *const scene[] = {"scene.size=[16,16,8]", "lightmap.resolution=[16,16,16]",
                                 "render.height=40"};
    open_run(&r, scene, 3, NULL, 0, true);
    struct frame_state f;
    for (int i = 0; i < 3; i++)
        frame(&r, &f);
    struct menu *m = session_menu(r.s);
    assert_non_null(m);
    assert_int_equal(menu_page(m), MENU_PAGE_TIME);
    float p[3];
    assert_true(menu_widget_point(m, "tab.light", 0.5f, 0.5f, p));
    if (!on_tab)
        p[0] += 1.0f; /* a metre to the right of the panel */
    struct anvil_xr_test_report rep;
    rt_report(&rep);
    long k = rep.frames_waited + 1;
    snprintf(script, sizeof(script),
             "%ld aim %s 0.1 1.1 -0.2 %g %g %g\n%ld input %s 1\n%ld input %s 0\n%ld exit\n", k,
             hand, p[0], p[1], p[2], k + 2, trigger, k + 4, trigger, k + 8);
    assert_true(rt_script(script));
    run_to_end(&r);
    rt_report(&rep);
    expect_clean(&rep);
    assert_string_equal(rep.profile, profile);
    assert_true(rep.syncs > 0);
    print_message("%s, %s hand %s: page %s\n", profile, hand, on_tab ? "on the tab" : "aside",
                  menu_page_name(menu_page(m)));
    assert_int_equal(menu_page(m), on_tab ? MENU_PAGE_LIGHT : MENU_PAGE_TIME);
    close_run(&r);
}

static void test_trigger_reaches_menu(void **state)
{
    press_run("/interaction_profiles/khr/simple_controller", "right",
              "/user/hand/right/input/select/click", true);
    press_run("/interaction_profiles/oculus/touch_controller", "left",
              "/user/hand/left/input/trigger/value", true);
    press_run("/interaction_profiles/valve/index_controller", "right",
              "/user/hand/right/input/trigger/value", true);
    press_run("/interaction_profiles/htc/vive_controller", "right",
              "/user/hand/right/input/trigger/value", true);
}

static void test_press_aside_does_nothing(void **state)
{
    press_run("/interaction_profiles/valve/index_controller", "right",
              "/user/hand/right/input/trigger/value", false);
}

static void test_session_lost(void **state)
{
    assert_true(rt_reset("size 32 24\n4 lose\n"));
    struct run r;
    const char *const scene[] = {"scene.size=[16,16,8]", "lightmap.resolution=[16,16,16]"};
    open_run(&r, scene, 2, NULL, 0, false);
    run_to_end(&r);
    struct anvil_xr_test_report rep;
    rt_report(&rep);
    expect_clean(&rep);
    assert_non_null(strstr(rep.states, "LOSS_PENDING"));
    close_run(&r);
}

/* The layer reports into VALIDATION_FILE: none of its messages is an error. */
static void test_no_validation_errors(void **state)
{
    if (!xlib)
        skip();
    FILE *f = fopen(validation_file, "r");
    if (!f)
        return; /* the layer reported nothing at all */
    fclose(f);
    char *text = file_read_all(validation_file, NULL);
    assert_non_null(text);
    int errors = 0;
    for (char *p = text; (p = strstr(p, "[VALID_ERROR")); p++)
        errors++;
    if (errors)
        print_error("%s", text);
    free(text);
    assert_int_equal(errors, 0);
}

/* ---- set-up ----------------------------------------------------------------------------- */

static bool layer_present(void)
{
    uint32_t n = 0;
    if (xrEnumerateApiLayerProperties(0, &n, NULL) != XR_SUCCESS || n == 0)
        return false;
    XrApiLayerProperties *props = calloc(n, sizeof(*props));
    if (!props)
        return false;
    for (uint32_t i = 0; i < n; i++)
        props[i].type = XR_TYPE_API_LAYER_PROPERTIES;
    bool found = false;
    if (xrEnumerateApiLayerProperties(n, &n, props) == XR_SUCCESS) {
        for (uint32_t i = 0; i < n; i++)
            found = found || strcmp(props[i].layerName, LAYER) == 0;
    }
    free(props);
    return found;
}

/* The layer listens: a call it must refuse (a wrong structure type) lands in FILE. */
static bool layer_listens(const char *file)
{
    setenv("XR_CORE_VALIDATION_FILE_NAME", file, 1);
    rt_reset(NULL);
    const char *ext[] = {"XR_KHR_opengl_enable"};
    XrInstanceCreateInfo ci = {.type = XR_TYPE_INSTANCE_CREATE_INFO,
                               .enabledExtensionCount = 1,
                               .enabledExtensionNames = ext};
    snprintf(ci.applicationInfo.applicationName, sizeof(ci.applicationInfo.applicationName),
             "layer probe");
    ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
    XrInstance inst;
    if (xrCreateInstance(&ci, &inst) != XR_SUCCESS)
        return false;
    XrSystemGetInfo bad = {.type = XR_TYPE_SESSION_CREATE_INFO,
                           .formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY};
    XrSystemId sys;
    XrResult r = xrGetSystem(inst, &bad, &sys);
    xrDestroyInstance(inst);
    char *text = file_read_all(file, NULL);
    bool heard =
        r != XR_SUCCESS && text && strstr(text, "VALID_ERROR") && strstr(text, "xrGetSystem");
    free(text);
    return heard;
}

int main(int argc, char **argv)
{
    log_set_level(LOG_WARN);
    if (argc != 2 || (strcmp(argv[1], "xlib") != 0 && strcmp(argv[1], "egl") != 0)) {
        fprintf(stderr, "usage: test_openxr xlib|egl\n");
        return 2;
    }
    xlib = strcmp(argv[1], "xlib") == 0;
    setenv("XR_RUNTIME_JSON", ANVIL_XR_RUNTIME_JSON, 1);
    void *lib = dlopen(ANVIL_XR_RUNTIME_LIB, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        return 1;
    }
    rt_reset = (anvil_xr_test_reset_fn)dlsym(lib, "anvil_xr_test_reset");
    rt_script = (anvil_xr_test_script_fn)dlsym(lib, "anvil_xr_test_script");
    rt_report = (anvil_xr_test_get_report_fn)dlsym(lib, "anvil_xr_test_get_report");
    rt_image = (anvil_xr_test_image_fn)dlsym(lib, "anvil_xr_test_image");
    if (!rt_reset || !rt_script || !rt_report || !rt_image) {
        fprintf(stderr, "the test runtime lacks its side door\n");
        return 1;
    }
    if (!xlib)
        gpu_context_destroy(test_gl_context_or_skip()); /* exits 77 without a context */
    if (xlib) {
        const char *x = getenv("DISPLAY");
        if (!x || !*x) {
            fprintf(stderr, "no X display (run under xvfb-run): skipping\n");
            return TEST_SKIP;
        }
        if (!layer_present()) {
            fprintf(stderr,
                    "the Khronos validation layer (%s, Debian: "
                    "openxr-layer-corevalidation) is not installed: skipping\n",
                    LAYER);
            return TEST_SKIP;
        }
        setenv("XR_ENABLE_API_LAYERS", LAYER, 1);
        setenv("XR_CORE_VALIDATION_EXPORT_TYPE", "text", 1);
        if (!layer_listens(test_tmp_path("probe.txt"))) {
            fprintf(stderr, "the validation layer did not report a wrong call\n");
            return 1;
        }
        snprintf(validation_file, sizeof(validation_file), "%s", test_tmp_path("layer.txt"));
        setenv("XR_CORE_VALIDATION_FILE_NAME", validation_file, 1);
    } else {
        unsetenv("XR_ENABLE_API_LAYERS");
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stage_eyes),
        cmocka_unit_test(test_local_space),
        cmocka_unit_test(test_trigger_reaches_menu),
        cmocka_unit_test(test_press_aside_does_nothing),
        cmocka_unit_test(test_session_lost),
        cmocka_unit_test(test_no_validation_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
