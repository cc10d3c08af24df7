/* View math without GL: generalized perspective, seams, stereo disparity, navigation, head
 * paths, poses and field-of-view projections (OpenXR's eyes), display config errors, contact
 * sheets. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include <cglm/cglm.h>

#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"

static void load_display(const char *name, struct display_config *cfg)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s/displays/%s", ANVIL_SOURCE_DIR, name);
    assert_true(display_config_load(path, cfg));
}

/* World point P -> normalised device coordinates of view V.  Returns clip w. */
static float project(const struct view *v, const double p[3], float ndc[3])
{
    mat4 view, proj, vp;
    memcpy(view, v->rv.view, sizeof(view));
    memcpy(proj, v->rv.proj, sizeof(proj));
    glm_mat4_mul(proj, view, vp);
    vec4 in = {(float)p[0], (float)p[1], (float)p[2], 1.0f}, out;
    glm_mat4_mulv(vp, in, out);
    for (int i = 0; i < 3; i++)
        ndc[i] = out[i] / out[3];
    return out[3];
}

/* Tracker point T -> world metres through CFG's navigation. */
static void tracker_to_world(const struct display_config *cfg, const float t[3], double out[3])
{
    mat4 nav, inv;
    display_navigation_matrix(&cfg->navigation, (float *)nav);
    glm_mat4_inv(nav, inv);
    vec4 in = {t[0], t[1], t[2], 1.0f}, w;
    glm_mat4_mulv(inv, in, w);
    for (int i = 0; i < 3; i++)
        out[i] = w[i];
}

static const struct view *find_view(const struct view_set *set, const char *name)
{
    for (int i = 0; i < set->count; i++) {
        if (strcmp(set->views[i].name, name) == 0)
            return &set->views[i];
    }
    fail_msg("no view %s", name);
    return NULL;
}

static void layout(const struct display_config *cfg, const double head_pos[3],
                   struct view_set *set)
{
    struct display_pose head;
    double hpr[3] = {0, 0, 0};
    display_pose_from_euler(head_pos, hpr, &head);
    int sizes[DISPLAY_MAX_WALLS][2];
    for (int w = 0; w < cfg->wall_count; w++)
        view_set_wall_size(cfg, w, 48, sizes[w]);
    memset(set, 0, sizeof(*set));
    view_set_layout(set, cfg, &cfg->navigation, &head, (const int(*)[2])sizes);
}

static void test_cave6_centred_head_symmetric(void **state)
{
    struct display_config cfg;
    load_display("cave6.cfg", &cfg);
    assert_int_equal(cfg.wall_count, 6);
    const float centre[3] = {0.0f, 1.5f, 0.0f};
    float near = (float)cfg.near_m;
    for (int w = 0; w < 6; w++) {
        float view[16], proj[16], e[4];
        assert_true(display_wall_projection(&cfg.walls[w], centre, near, 100.0f, view, proj, e));
        /* 3 m walls 1.5 m away: the frustum is +-near on both axes. */
        assert_float_equal(e[0], -near, 1e-6);
        assert_float_equal(e[1], near, 1e-6);
        assert_float_equal(e[2], -near, 1e-6);
        assert_float_equal(e[3], near, 1e-6);
        /* Symmetric frustum: no off-axis terms in the projection. */
        assert_float_equal(proj[8], 0.0f, 1e-6);
        assert_float_equal(proj[9], 0.0f, 1e-6);
    }
    /* Through the layout: both eyes of the centred head, mirror images of each other. */
    struct view_set set;
    double head[3] = {0.0, 1.5, 0.0};
    layout(&cfg, head, &set);
    assert_int_equal(set.count, 12);
    for (int i = 0; i < 12; i += 2) {
        const struct view *l = &set.views[i], *r = &set.views[i + 1];
        assert_int_equal(l->eye, VIEW_EYE_LEFT);
        assert_int_equal(r->eye, VIEW_EYE_RIGHT);
        assert_true(l->visible && r->visible);
        float w = l->extent[1] - l->extent[0];
        if (strncmp(l->name, "front", 5) == 0 || strncmp(l->name, "back", 4) == 0 ||
            strncmp(l->name, "floor", 5) == 0 || strncmp(l->name, "ceiling", 7) == 0) {
            /* The eyes sit off-centre across these walls: mirrored frusta. */
            assert_float_equal(l->extent[0], -r->extent[1], 1e-6 * w);
            assert_float_equal(l->extent[1], -r->extent[0], 1e-6 * w);
        }
        assert_float_equal(l->extent[2], -l->extent[3], 1e-6 * w);
    }
}

static void test_seam_point_on_shared_edge(void **state)
{
    struct display_config cfg;
    load_display("cave6.cfg", &cfg);
    struct view_set set;
    double head[3] = {0.3, 1.7, 0.4}; /* off-centre on purpose */
    layout(&cfg, head, &set);
    /* On the front/left seam and the front/floor seam. */
    const float seam_fl[3] = {-1.5f, 1.2f, -1.5f};
    const float seam_ff[3] = {0.6f, 0.0f, -1.5f};
    double p[3], q[3];
    tracker_to_world(&cfg, seam_fl, p);
    tracker_to_world(&cfg, seam_ff, q);
    const char *eyes[] = {"left", "right"};
    for (int e = 0; e < 2; e++) {
        char a[48], b[48], c[48];
        snprintf(a, sizeof(a), "front-%s", eyes[e]);
        snprintf(b, sizeof(b), "left-%s", eyes[e]);
        snprintf(c, sizeof(c), "floor-%s", eyes[e]);
        const struct view *front = find_view(&set, a), *left = find_view(&set, b),
                          *floor = find_view(&set, c);
        float nf[3], nl[3], nfl[3];
        assert_true(project(front, p, nf) > 0.0f);
        assert_true(project(left, p, nl) > 0.0f);
        /* The front wall's left edge is the left wall's right edge; same height on both. */
        float px = 2.0f / (float)front->rv.width; /* one pixel in NDC */
        assert_float_equal(nf[0], -1.0f, 1e-3 * px);
        assert_float_equal(nl[0], 1.0f, 1e-3 * px);
        assert_float_equal(nf[1], 1.2f / 3.0f * 2.0f - 1.0f, 1e-3 * px);
        assert_float_equal(nl[1], nf[1], 1e-3 * px);
        /* The front wall's bottom edge is the floor's top edge. */
        assert_true(project(front, q, nf) > 0.0f);
        assert_true(project(floor, q, nfl) > 0.0f);
        assert_float_equal(nf[1], -1.0f, 1e-3 * px);
        assert_float_equal(nfl[1], 1.0f, 1e-3 * px);
        assert_float_equal(nf[0], 2.1f / 3.0f * 2.0f - 1.0f, 1e-3 * px);
        assert_float_equal(nfl[0], nf[0], 1e-3 * px);
    }
}

static void test_stereo_disparity_sign(void **state)
{
    struct display_config cfg;
    load_display("cave4.cfg", &cfg);
    struct view_set set;
    double head[3] = {0.0, 1.6, 0.5};
    layout(&cfg, head, &set);
    const struct view *l = find_view(&set, "front-left"), *r = find_view(&set, "front-right");
    /* Behind the front wall (z < -1.5): uncrossed disparity, the left eye sees it further
     * left. */
    const float behind[3] = {0.2f, 1.4f, -4.0f};
    double p[3];
    tracker_to_world(&cfg, behind, p);
    float nl[3], nr[3];
    assert_true(project(l, p, nl) > 0.0f && project(r, p, nr) > 0.0f);
    assert_true(nl[0] < nr[0] - 1e-3f);
    assert_float_equal(nl[1], nr[1], 1e-5);
    /* In front of the wall (between it and the viewer): crossed, the other way round. */
    const float before[3] = {0.2f, 1.4f, -0.5f};
    tracker_to_world(&cfg, before, p);
    assert_true(project(l, p, nl) > 0.0f && project(r, p, nr) > 0.0f);
    assert_true(nl[0] > nr[0] + 1e-3f);
    /* On the wall plane: no disparity. */
    const float on[3] = {0.2f, 1.4f, -1.5f};
    tracker_to_world(&cfg, on, p);
    assert_true(project(l, p, nl) > 0.0f && project(r, p, nr) > 0.0f);
    assert_float_equal(nl[0], nr[0], 1e-5);
}

static void test_eye_behind_wall_is_invisible(void **state)
{
    struct display_config cfg;
    load_display("cave4.cfg", &cfg);
    float view[16], proj[16];
    const float outside[3] = {0.0f, 1.5f, -2.0f}; /* beyond the front wall */
    assert_false(display_wall_projection(&cfg.walls[0], outside, 0.01f, 10.0f, view, proj,
                                         NULL));
    const float on[3] = {0.0f, 1.5f, -1.5f};
    assert_false(display_wall_projection(&cfg.walls[0], on, 0.01f, 10.0f, view, proj, NULL));
}

static void test_navigation_places_the_storm(void **state)
{
    struct display_navigation nav = {.scale = 5e-5, .origin_km = {30, 30, 0},
                                     .position = {0.0, 0.5, -1.0}};
    mat4 m;
    display_navigation_matrix(&nav, (float *)m);
    vec4 origin = {30000, 30000, 0, 1}, east = {90000, 30000, 0, 1}, north = {30000, 90000, 0, 1},
         up = {30000, 30000, 16000, 1}, out;
    glm_mat4_mulv(m, origin, out);
    assert_float_equal(out[0], 0.0f, 1e-5);
    assert_float_equal(out[1], 0.5f, 1e-5);
    assert_float_equal(out[2], -1.0f, 1e-5);
    glm_mat4_mulv(m, east, out); /* 60 km east: 3 m to the right */
    assert_float_equal(out[0], 3.0f, 1e-5);
    glm_mat4_mulv(m, north, out); /* north: away from the viewer, -z */
    assert_float_equal(out[2], -4.0f, 1e-5);
    glm_mat4_mulv(m, up, out); /* up: +y, 16 km -> 0.8 m */
    assert_float_equal(out[1], 1.3f, 1e-5);
    /* Heading 90 degrees (counter-clockwise from above): east turns to -z. */
    nav.orientation_deg[0] = 90.0;
    display_navigation_matrix(&nav, (float *)m);
    glm_mat4_mulv(m, east, out);
    assert_float_equal(out[0], 0.0f, 1e-5);
    assert_float_equal(out[2], -4.0f, 1e-5);
}

static void test_eyes_along_head_right_axis(void **state)
{
    struct display_pose head;
    double pos[3] = {1.0, 1.6, 0.0}, hpr[3] = {90.0, 0.0, 0.0}; /* turned to face -x */
    display_pose_from_euler(pos, hpr, &head);
    float l[3], r[3];
    display_pose_eyes(&head, 0.064, l, r);
    /* Facing -x, the right hand points to -z... */
    assert_float_equal(l[0], 1.0f, 1e-6);
    assert_float_equal(r[0], 1.0f, 1e-6);
    assert_float_equal(l[2], 0.032f, 1e-6);
    assert_float_equal(r[2], -0.032f, 1e-6);
    assert_float_equal(l[1], 1.6f, 1e-6);
}

static void test_head_path(void **state)
{
    const char *file = test_write_file("walk.txt", "# t x y z heading pitch roll\n"
                                                   "0   0 1.5 0   0 0 0\n"
                                                   "2.0 1 1.5 -2  90 0 0   # turn left\n"
                                                   "\n"
                                                   "4.0 1 1.7 -2  90 0 0\n");
    struct display_path path;
    assert_true(display_path_load(file, &path));
    assert_int_equal(path.count, 3);
    struct display_pose p;
    display_path_eval(&path, 1.0, &p);
    assert_float_equal(p.position[0], 0.5f, 1e-6);
    assert_float_equal(p.position[2], -1.0f, 1e-6);
    /* Half way through a 90 degree turn: 45 degrees about y. */
    assert_float_equal(p.rotation[1], sinf(22.5f * (float)M_PI / 180.0f), 1e-5);
    assert_float_equal(p.rotation[3], cosf(22.5f * (float)M_PI / 180.0f), 1e-5);
    display_path_eval(&path, 3.0, &p);
    assert_float_equal(p.position[1], 1.6f, 1e-6);
    display_path_eval(&path, -5.0, &p); /* clamped */
    assert_float_equal(p.position[0], 0.0f, 0.0);
    display_path_eval(&path, 99.0, &p);
    assert_float_equal(p.position[1], 1.7f, 1e-6);
    display_path_finish(&path);

    const char *bad = test_write_file("bad.txt", "0 0 0 0 0 0 0\n1 0 0 0 0 0\n");
    assert_false(display_path_load(bad, &path));
    assert_non_null(strstr(log_last_error(), "bad.txt:2: expected 7 numbers"));
    const char *back = test_write_file("back.txt", "1 0 0 0 0 0 0\n0.5 0 0 0 0 0 0\n");
    assert_false(display_path_load(back, &path));
    assert_non_null(strstr(log_last_error(), "back.txt:2: expected a time after 1"));
}

static void expect_error(const char *name, const char *text, const char *message)
{
    const char *path = test_write_file(name, text);
    struct display_config cfg;
    assert_false(display_config_load(path, &cfg));
    const char *got = log_last_error();
    if (!strstr(got, message))
        fail_msg("%s: expected \"%s\" in \"%s\"", name, message, got);
}

/* An asymmetric field of view: each edge's direction lands on its side of NDC, exactly. */
static void test_fov_projection(void **state)
{
    const float l = -0.87f, r = 0.70f, u = 0.79f, d = -0.96f, near = 0.05f, far = 200.0f;
    mat4 p;
    display_fov_projection(l, r, u, d, near, far, (float *)p);
    struct {
        float x, y, z, ndc_x, ndc_y;
    } cases[] = {
        {tanf(l), 0.0f, -1.0f, -1.0f, NAN}, {tanf(r), 0.0f, -1.0f, 1.0f, NAN},
        {0.0f, tanf(u), -1.0f, NAN, 1.0f},  {0.0f, tanf(d), -1.0f, NAN, -1.0f},
        {tanf(l) * 7.0f, tanf(d) * 7.0f, -7.0f, -1.0f, -1.0f},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        vec4 in = {cases[i].x, cases[i].y, cases[i].z, 1.0f}, out;
        glm_mat4_mulv(p, in, out);
        if (!isnan(cases[i].ndc_x))
            assert_float_equal(out[0] / out[3], cases[i].ndc_x, 1e-5);
        if (!isnan(cases[i].ndc_y))
            assert_float_equal(out[1] / out[3], cases[i].ndc_y, 1e-5);
    }
    /* The axis is off the centre of an asymmetric frustum: straight ahead is not x = 0. */
    vec4 ahead = {0.0f, 0.0f, -1.0f, 1.0f}, out;
    glm_mat4_mulv(p, ahead, out);
    float want = (0.0f - tanf(l)) / (tanf(r) - tanf(l)) * 2.0f - 1.0f;
    assert_float_equal(out[0] / out[3], want, 1e-5);
    assert_true(fabsf(want) > 0.05f);
    /* Depth: near at -1, far at +1. */
    vec4 pn = {0.0f, 0.0f, -near, 1.0f}, pf = {0.0f, 0.0f, -far, 1.0f};
    glm_mat4_mulv(p, pn, out);
    assert_float_equal(out[2] / out[3], -1.0f, 1e-4);
    glm_mat4_mulv(p, pf, out);
    assert_float_equal(out[2] / out[3], 1.0f, 1e-4);
}

/* Composing, inverting and viewing poses: a heading of 90 degrees turns -z into -x. */
static void test_pose_math(void **state)
{
    struct display_pose a, b = {.position = {0.0f, 0.0f, -1.0f}, .rotation = {0, 0, 0, 1}}, c;
    display_pose_from_euler((const double[3]){1.0, 2.0, 0.0}, (const double[3]){90.0, 0.0, 0.0},
                            &a);
    display_pose_compose(&a, &b, &c);
    assert_float_equal(c.position[0], 0.0f, 1e-6);
    assert_float_equal(c.position[1], 2.0f, 1e-6);
    assert_float_equal(c.position[2], 0.0f, 1e-6);
    struct display_pose inv, id;
    display_pose_invert(&c, &inv);
    display_pose_compose(&c, &inv, &id);
    for (int i = 0; i < 3; i++)
        assert_float_equal(id.position[i], 0.0f, 1e-6);
    assert_float_equal(fabsf(id.rotation[3]), 1.0f, 1e-6);
    /* A's eye sees a point 2 m along its own -z straight ahead, 2 m away. */
    mat4 nav = GLM_MAT4_IDENTITY_INIT, view;
    display_pose_view(&a, (float *)nav, (float *)view);
    vec4 p = {1.0f - 2.0f, 2.0f, 0.0f, 1.0f}, out;
    glm_mat4_mulv(view, p, out);
    assert_float_equal(out[0], 0.0f, 1e-6);
    assert_float_equal(out[1], 0.0f, 1e-6);
    assert_float_equal(out[2], -2.0f, 1e-6);
}

static void test_config_errors(void **state)
{
    expect_error("type.cfg", "display = {\n  type = \"dome\";\n};\n",
                 "type.cfg:2: display.type: expected one of \"headless\"");
    expect_error("sep.cfg", "display = { eye_separation = \"wide\"; };\n",
                 "sep.cfg:1: display.eye_separation: expected a number in [0, 1]");
    expect_error("unknown.cfg", "head = {\n  postion = [0.0, 1.0, 0.0];\n};\n",
                 "unknown.cfg:2: head.postion: expected a known setting");
    expect_error("group.cfg", "screens = ();\n", "group.cfg:1: screens: expected a known group");
    expect_error("xr.cfg", "openxr = {\n  space = \"floor\";\n};\n",
                 "xr.cfg:2: openxr.space: expected one of \"auto\", \"stage\", \"local\"");
    expect_error("scale.cfg", "openxr = { resolution_scale = 0.0; };\n",
                 "scale.cfg:1: openxr.resolution_scale: expected a number in [0.05, 2]");
    expect_error("vec.cfg",
                 "walls = ({ name = \"a\";\n lower_left = [0.0, 0.0];\n"
                 " lower_right = [1.0, 0.0, 0.0]; upper_left = [0.0, 1.0, 0.0]; });\n",
                 "vec.cfg:2: walls.[0].lower_left: expected [3 numbers]");
    expect_error("skew.cfg",
                 "walls = (\n { name = \"a\"; lower_left = [0.0, 0.0, 0.0];\n"
                 "   lower_right = [1.0, 0.0, 0.0]; upper_left = [0.5, 1.0, 0.0]; });\n",
                 "skew.cfg:2: walls.[0].upper_left: expected corners of a rectangle");
    expect_error("missing.cfg", "walls = ({ name = \"a\"; lower_left = [0.0, 0.0, 0.0]; });\n",
                 "missing.cfg:1: walls.[0].lower_right: expected a setting");
    expect_error("dup.cfg",
                 "walls = ({ name = \"a\"; lower_left = [0.0, 0.0, 0.0];\n"
                 " lower_right = [1.0, 0.0, 0.0]; upper_left = [0.0, 1.0, 0.0]; },\n"
                 "{ name = \"a\"; lower_left = [0.0, 0.0, 0.0];\n"
                 " lower_right = [1.0, 0.0, 0.0]; upper_left = [0.0, 1.0, 0.0]; });\n",
                 "dup.cfg:3: walls.[1].name: expected a name no other wall has");
    expect_error("path.cfg", "head = { source = \"path\"; };\n",
                 "path.cfg:1: head.path: expected a pose file");
    expect_error("syntax.cfg", "display = {\n  type = ;\n};\n", "syntax.cfg:2:");
    expect_error("int.cfg", "display = { window_size = [800.0, 600.0]; };\n",
                 "int.cfg:1: display.window_size: expected [2 numbers] each an integer");
    struct display_config cfg;
    assert_false(display_config_load("/nonexistent/x.cfg", &cfg));
    assert_non_null(strstr(log_last_error(), "/nonexistent/x.cfg"));
}

static void test_shipped_configs_load(void **state)
{
    const char *names[] = {"desktop.cfg", "desktop-stereo.cfg", "cave4.cfg", "cave6.cfg",
                           "hmd.cfg", "openxr.cfg"};
    struct display_config cfg;
    for (int i = 0; i < 6; i++)
        load_display(names[i], &cfg);
    load_display("cave4.cfg", &cfg);
    assert_int_equal(cfg.type, DISPLAY_TYPE_CAVE);
    assert_int_equal(cfg.wall_count, 4);
    const char *walls[] = {"front", "left", "right", "floor"};
    for (int w = 0; w < 4; w++) {
        assert_string_equal(cfg.walls[w].name, walls[w]);
        assert_int_equal(cfg.walls[w].stereo, DISPLAY_STEREO_QUAD_BUFFER);
    }
    load_display("desktop-stereo.cfg", &cfg);
    assert_int_equal(cfg.type, DISPLAY_TYPE_STEREO);
    assert_int_equal(cfg.walls[0].stereo, DISPLAY_STEREO_ANAGLYPH);
    load_display("hmd.cfg", &cfg);
    assert_int_equal(cfg.type, DISPLAY_TYPE_HMD);
    assert_string_equal(cfg.hmd.device, "null");
    assert_true(cfg.hmd.distortion_set);
    load_display("openxr.cfg", &cfg);
    assert_int_equal(cfg.type, DISPLAY_TYPE_OPENXR);
    assert_int_equal(cfg.openxr.binding, DISPLAY_OPENXR_BINDING_AUTO);
    assert_int_equal(cfg.openxr.space, DISPLAY_OPENXR_SPACE_AUTO);
    assert_true(display_config_set(&cfg, "openxr.space=\"local\""));
    assert_int_equal(cfg.openxr.space, DISPLAY_OPENXR_SPACE_LOCAL);
    assert_true(display_config_has_setting("openxr.binding"));
    /* Built with the loader or not, the type is known; the backend only with it. */
#if HAVE_OPENXR
    assert_true(display_type_available(DISPLAY_TYPE_OPENXR));
#else
    assert_false(display_type_available(DISPLAY_TYPE_OPENXR));
#endif
}

static void test_contact_sheet_layout(void **state)
{
    struct image imgs[3];
    for (int i = 0; i < 3; i++) {
        assert_true(image_init(&imgs[i], 4, 3));
        for (int p = 0; p < 12; p++)
            imgs[i].rgba[4 * p] = (float)(i + 1);
    }
    struct image sheet;
    const float bg[4] = {0, 0, 0, 1};
    assert_true(display_contact_sheet(imgs, 3, 2, 1, bg, &sheet));
    assert_int_equal(sheet.width, 2 * 4 + 3);
    assert_int_equal(sheet.height, 2 * 3 + 3);
    /* Image 0 top-left, image 1 top-right, image 2 bottom-left; rows stored bottom up. */
    assert_float_equal(sheet.rgba[4 * ((sheet.height - 2) * sheet.width + 1)], 1.0f, 0.0);
    assert_float_equal(sheet.rgba[4 * ((sheet.height - 2) * sheet.width + 6)], 2.0f, 0.0);
    assert_float_equal(sheet.rgba[4 * (1 * sheet.width + 1)], 3.0f, 0.0);
    assert_float_equal(sheet.rgba[4 * (1 * sheet.width + 6)], 0.0f, 0.0); /* empty cell */
    image_finish(&sheet);
    for (int i = 0; i < 3; i++)
        image_finish(&imgs[i]);
}

/* docs/displays.md carries the reference table as the code writes it. */
static void test_reference_in_docs(void **state)
{
    char *ref = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&ref, &len);
    assert_non_null(f);
    display_config_write_reference(f);
    fclose(f);
    char *doc = file_read_all(ANVIL_SOURCE_DIR "/docs/displays.md", NULL);
    assert_non_null(doc);
    int lines = 0;
    for (char *line = strtok(ref, "\n"); line; line = strtok(NULL, "\n"), lines++) {
        if (!strstr(doc, line))
            fail_msg("docs/displays.md lacks the reference line: %s", line);
    }
    assert_true(lines > 20);
    free(doc);
    free(ref);
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cave6_centred_head_symmetric),
        cmocka_unit_test(test_seam_point_on_shared_edge),
        cmocka_unit_test(test_stereo_disparity_sign),
        cmocka_unit_test(test_eye_behind_wall_is_invisible),
        cmocka_unit_test(test_navigation_places_the_storm),
        cmocka_unit_test(test_eyes_along_head_right_axis),
        cmocka_unit_test(test_head_path),
        cmocka_unit_test(test_fov_projection),
        cmocka_unit_test(test_pose_math),
        cmocka_unit_test(test_config_errors),
        cmocka_unit_test(test_shipped_configs_load),
        cmocka_unit_test(test_contact_sheet_layout),
        cmocka_unit_test(test_reference_in_docs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
