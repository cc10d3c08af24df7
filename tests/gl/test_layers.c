/* Colour-mapped layers and slices in the eye pass on EGL/llvmpipe (render.h):
 * classified after interpolation (a sharp step of the colour map is one sharp edge in the
 * picture where a field classified per voxel shows a ramp a voxel wide), composited with the
 * clouds by the emission-absorption rule of raycast.comp, tinting the clouds, and not leapt by
 * empty-space skipping; slices in the colours of their maps, with contours, behind clouds. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cglm/cglm.h>

#include "testutil.h"

#include "common/log.h"
#include "gpu/gpu.h"
#include "render/render.h"

static struct gpu_context *ctx;
static struct renderer *renderer;

#define NX 8
#define W 64
#define DEPTH_M 2000.0

/* A NX x 2 x 2 volume of 1 km voxels, extinction BETA everywhere (both phases' sum in the
 * water phase), layer 0's field FIELD(i) at voxel column i. */
static void make_volume(struct ext_volume *v, float beta, const float field[NX])
{
    struct grid3 g = {.n = {NX, 2, 2}, .spacing = {1000.0, 1000.0, 1000.0}};
    assert_true(ext_volume_init(v, &g));
    size_t n = grid3_count(&g);
    v->layer[0] = malloc(n * sizeof(float));
    assert_non_null(v->layer[0]);
    for (size_t idx = 0; idx < n; idx++) {
        v->beta[2 * idx + 1] = beta;
        v->layer[0][idx] = field[idx % NX];
    }
    v->layer_field[0] = TRANSFER_FIELD_QVAPOR;
}

/* Straight down on the whole box, orthographic: pixel p's ray at x = (p + 0.5) 8 km / W. */
static void top_view(struct render_view *view)
{
    mat4 proj, lv;
    vec3 eye = {NX * 500.0f, 1000.0f, 10000.0f}, target = {NX * 500.0f, 1000.0f, 0.0f};
    vec3 up = {0.0f, 1.0f, 0.0f};
    glm_lookat(eye, target, up, lv);
    glm_ortho(-NX * 500.0f, NX * 500.0f, -1000.0f, 1000.0f, 100.0f, 20000.0f, proj);
    memcpy(view->view, lv, sizeof(view->view));
    memcpy(view->proj, proj, sizeof(view->proj));
    view->width = W;
    view->height = 4;
}

static void settings(struct render_settings *s, float sun)
{
    memset(s, 0, sizeof(*s));
    s->sun_dir[2] = 1.0f;
    for (int c = 0; c < 3; c++)
        s->sun_radiance[c] = sun;
    s->termination = 1e-6f;
}

/* Renders the volume with LAYER (NULL: none) into IMG. */
static void draw(const struct ext_volume *v, const struct transfer_layer *layer, bool no_skip,
                 struct image *img)
{
    assert_true(renderer_set_volume(renderer, v));
    struct render_layer rl;
    if (layer)
        render_layer_from_transfer(layer, 1.0f, &rl);
    assert_true(renderer_set_layers(renderer, &rl, layer ? 1 : 0));
    struct render_settings s;
    settings(&s, 0.0f);
    s.no_skip = no_skip;
    struct render_view view;
    top_view(&view);
    struct gpu_texture out = {0};
    assert_true(renderer_draw(renderer, &s, &view, &out));
    assert_true(renderer_read(&out, img));
    gpu_texture_finish(&out);
}

/* Red, and alpha that steps from 0 to 1 at X (of [0, 1]). */
static void step_layer(struct transfer_layer *l, double lo, double hi, float x, double density)
{
    memset(l, 0, sizeof(*l));
    l->enabled = true;
    l->opacity = 1.0;
    l->mode = TRANSFER_LAYER_EMIT;
    struct transfer_function *tf = &l->tf;
    transfer_defaults(tf, TRANSFER_FIELD_QVAPOR);
    tf->lo = lo;
    tf->hi = hi;
    tf->density = density;
    tf->count[TRANSFER_RED] = 1;
    tf->points[TRANSFER_RED][0] = (struct transfer_point){0.0f, 1.0f};
    tf->count[TRANSFER_GREEN] = 1;
    tf->points[TRANSFER_GREEN][0] = (struct transfer_point){0.0f, 0.0f};
    tf->count[TRANSFER_BLUE] = 1;
    tf->points[TRANSFER_BLUE][0] = (struct transfer_point){0.0f, 0.0f};
    tf->count[TRANSFER_ALPHA] = 4;
    tf->points[TRANSFER_ALPHA][0] = (struct transfer_point){0.0f, 0.0f};
    tf->points[TRANSFER_ALPHA][1] = (struct transfer_point){x, 0.0f};
    tf->points[TRANSFER_ALPHA][2] = (struct transfer_point){x + 1e-3f, 1.0f};
    tf->points[TRANSFER_ALPHA][3] = (struct transfer_point){1.0f, 1.0f};
    assert_true(transfer_valid(tf, NULL, 0));
}

/* The red of row 1's pixels, and how many lie strictly between 0 and FULL (1e-4 of it apart). */
static int partial_pixels(const struct image *img, double full, float red[W])
{
    int partial = 0;
    for (int p = 0; p < W; p++) {
        red[p] = img->rgba[4 * ((size_t)1 * W + p)];
        if (red[p] > 1e-4 * full && red[p] < full * (1.0 - 1e-4))
            partial++;
    }
    return partial;
}

/* A field rising one unit a voxel (s = i at voxel i) and a colour map stepping at s = 3.2255
 * (between two entries of its 256-entry table, which resolves 7/255 of a unit):
 * post-classification shows one edge where the interpolated field crosses it, at
 * x = 3.73 km (the field at x is x / 1 km - 0.5 between voxel centres): pixels left of it
 * the background, right of it the layer's colour 1 - e^-(density 2 km), nothing between.  The
 * same step classified per voxel first (the field replaced by the map's alpha at each voxel,
 * the pre-classified volume of old) is a ramp a voxel wide: many pixels between. */
static void test_post_classification_step(void **state)
{
    float field[NX];
    for (int i = 0; i < NX; i++)
        field[i] = (float)i;
    const double density = 1.5e-3;
    const double full = (1.0 - exp(-density * DEPTH_M)) * render_display_to_radiance(1.0f, 1.0f);
    struct transfer_layer l;
    const float step = 117.5f / 255.0f; /* s = 3.2255 */
    step_layer(&l, 0.0, 7.0, step, density);
    struct ext_volume v = {0};
    make_volume(&v, 0.0f, field);
    struct image img = {0};
    draw(&v, &l, false, &img);
    float red[W];
    assert_int_equal(partial_pixels(&img, full, red), 0);
    int edge = -1;
    for (int p = 0; p < W; p++) {
        double x = (p + 0.5) * NX * 1000.0 / W;
        bool lit = x / 1000.0 - 0.5 > 7.0 * step;
        if (lit && edge < 0)
            edge = p;
        assert_float_equal(red[p], lit ? full : 0.0, 1e-4 * full);
        assert_float_equal(img.rgba[4 * ((size_t)1 * W + p) + 1], 0.0, 1e-6); /* no green */
    }
    assert_int_equal(edge, 30); /* 3.73 km of 8 km across 64 pixels: 29.8 */
    image_finish(&img);

    /* Classified per voxel: alpha 0 or 1 at the voxels, then interpolated. */
    float classified[NX];
    for (int i = 0; i < NX; i++)
        classified[i] = transfer_eval(&l.tf, TRANSFER_ALPHA, field[i] / 7.0f);
    struct transfer_layer ramp;
    step_layer(&ramp, 0.0, 1.0, 0.0f, density);
    ramp.tf.count[TRANSFER_ALPHA] = 2;
    ramp.tf.points[TRANSFER_ALPHA][0] = (struct transfer_point){0.0f, 0.0f};
    ramp.tf.points[TRANSFER_ALPHA][1] = (struct transfer_point){1.0f, 1.0f};
    memcpy(v.layer[0], classified, sizeof(classified)); /* row 0's voxels */
    for (size_t idx = 0; idx < grid3_count(&v.grid); idx++)
        v.layer[0][idx] = classified[idx % NX];
    draw(&v, &ramp, false, &img);
    assert_true(partial_pixels(&img, full, red) >= 6); /* the staircase's ramp */
    image_finish(&img);
    ext_volume_finish(&v);
}

/* The layer in empty space is drawn with skipping as without it (the macro cells see no
 * extinction there), and the layer's light is really there. */
static void test_layers_not_skipped(void **state)
{
    float field[NX];
    for (int i = 0; i < NX; i++)
        field[i] = 5.0f;
    struct transfer_layer l;
    step_layer(&l, 0.0, 7.0, 0.5f, 1e-3);
    struct ext_volume v = {0};
    make_volume(&v, 0.0f, field);
    struct image a = {0}, b = {0};
    draw(&v, &l, false, &a);
    draw(&v, &l, true, &b);
    for (size_t i = 0; i < (size_t)W * 4 * 4; i++)
        assert_float_equal(a.rgba[i], b.rgba[i], 1e-6);
    double l1 = render_display_to_radiance(1.0f, 1.0f);
    assert_float_equal(a.rgba[4 * W + 4 * 10], (1.0 - exp(-2.0)) * l1, 1e-4 * l1);
    image_finish(&a);
    image_finish(&b);
    ext_volume_finish(&v);
}

/* Clouds and an emitting layer together: the transmittance is e^-(beta + sigma) depth, and in
 * the dark (no sun) the colour is the layer's share sigma / (beta + sigma) of 1 - that, the
 * exact solution for a mixture of constant coefficients. */
static void test_composited_with_clouds(void **state)
{
    float field[NX];
    for (int i = 0; i < NX; i++)
        field[i] = 5.0f;
    const double beta = 5e-4, sigma = 1e-3;
    struct transfer_layer l;
    step_layer(&l, 0.0, 7.0, 0.5f, sigma);
    struct ext_volume v = {0};
    make_volume(&v, (float)beta, field);
    struct image img = {0};
    draw(&v, &l, false, &img);
    const float *px = &img.rgba[4 * W + 4 * 20];
    double t = exp(-(beta + sigma) * DEPTH_M);
    assert_float_equal(px[3], t, 1e-4);
    double l1 = render_display_to_radiance(1.0f, 1.0f);
    assert_float_equal(px[0], sigma / (beta + sigma) * (1.0 - t) * l1, 1e-4 * l1);
    image_finish(&img);
    /* Off: the clouds alone. */
    l.enabled = false;
    draw(&v, &l, false, &img);
    assert_float_equal(img.rgba[4 * W + 4 * 20 + 3], exp(-beta * DEPTH_M), 1e-4);
    assert_float_equal(img.rgba[4 * W + 4 * 20], 0.0, 1e-6);
    image_finish(&img);
    ext_volume_finish(&v);
}

/* Tint mode: the clouds' scattered light takes the map's colour (weight alpha x opacity), and
 * the layer adds no medium. */
static void test_tint_mode(void **state)
{
    float field[NX];
    for (int i = 0; i < NX; i++)
        field[i] = 5.0f;
    struct transfer_layer l;
    step_layer(&l, 0.0, 7.0, 0.5f, 1e-3);
    l.mode = TRANSFER_LAYER_TINT;
    l.opacity = 0.5; /* half way from white to red */
    struct ext_volume v = {0};
    make_volume(&v, 5e-4f, field);
    struct image plain = {0}, tinted = {0};
    assert_true(renderer_set_volume(renderer, &v));
    struct render_settings s;
    settings(&s, 1.0f);
    struct render_view view;
    top_view(&view);
    for (int k = 0; k < 2; k++) {
        struct render_layer rl;
        render_layer_from_transfer(&l, 1.0f, &rl);
        assert_true(renderer_set_layers(renderer, &rl, k));
        struct gpu_texture out = {0};
        assert_true(renderer_draw(renderer, &s, &view, &out));
        assert_true(renderer_read(&out, k ? &tinted : &plain));
        gpu_texture_finish(&out);
    }
    const float *a = &plain.rgba[4 * W + 4 * 20], *b = &tinted.rgba[4 * W + 4 * 20];
    assert_true(a[1] > 1e-3);
    assert_float_equal(b[0], a[0], 1e-6 + 1e-5 * a[0]);
    assert_float_equal(b[1], 0.5 * a[1], 1e-5 * a[1]);
    assert_float_equal(b[2], 0.5 * a[2], 1e-5 * a[2]);
    assert_float_equal(b[3], a[3], 1e-7); /* no medium of its own */
    image_finish(&plain);
    image_finish(&tinted);
    ext_volume_finish(&v);
}

/* A slice across z at 1 km through a field rising one unit a voxel along x, its colour map red
 * = s / 7, green = 1 - s / 7, blue 0.5: each pixel between the outer voxel centres shows the
 * map's colour at s = x / 1 km - 0.5 within 1/255 once tone mapped; with contours every 2
 * units the pixels within a pixel (125 m: 0.125 units) of s = 2, 4, 6 are dark, the others
 * keep their colour; under a dark cloud (no sun) the slice is seen through the kilometre of
 * cloud above it, e^-(beta 1 km). */
static void test_slice_colours(void **state)
{
    float field[NX];
    for (int i = 0; i < NX; i++)
        field[i] = (float)i;
    for (int k = 0; k < 3; k++) {
        const double beta = k == 2 ? 4e-4 : 0.0;
        struct ext_volume v = {0};
        make_volume(&v, (float)beta, field);
        v.slice[0] = v.layer[0]; /* the same field, as a slice's */
        v.layer[0] = NULL;
        v.slice_field[0] = TRANSFER_FIELD_TEMPERATURE;
        struct transfer_slice sl = {.enabled = true,
                                    .point = {0, 0, 1000.0},
                                    .normal = {0, 0, 1},
                                    .opacity = 1.0,
                                    .contour_every = k == 1 ? 2.0 : 0.0};
        transfer_defaults(&sl.tf, TRANSFER_FIELD_TEMPERATURE);
        sl.tf.lo = 0.0;
        sl.tf.hi = 7.0;
        struct transfer_function *tf = &sl.tf;
        tf->count[TRANSFER_RED] = 2;
        tf->points[TRANSFER_RED][0] = (struct transfer_point){0.0f, 0.0f};
        tf->points[TRANSFER_RED][1] = (struct transfer_point){1.0f, 1.0f};
        tf->count[TRANSFER_GREEN] = 2;
        tf->points[TRANSFER_GREEN][0] = (struct transfer_point){0.0f, 1.0f};
        tf->points[TRANSFER_GREEN][1] = (struct transfer_point){1.0f, 0.0f};
        tf->count[TRANSFER_BLUE] = 1;
        tf->points[TRANSFER_BLUE][0] = (struct transfer_point){0.0f, 0.5f};
        struct render_slice rs;
        render_slice_from_transfer(&sl, 1.0f, &rs);
        assert_true(renderer_set_slices(renderer, &rs, 1));
        struct image img = {0};
        draw(&v, NULL, false, &img);
        assert_true(renderer_set_slices(renderer, NULL, 0));
        double seen = exp(-beta * 1000.0);
        int dark = 0;
        for (int p = 8; p < W - 8; p++) { /* a voxel from the faces: a whole gradient */
            double sv = (p + 0.5) * NX * 1000.0 / W / 1000.0 - 0.5;
            const float *px = &img.rgba[4 * ((size_t)1 * W + p)];
            double off = fabs(sv / 2.0 - round(sv / 2.0)) * 2.0;
            if (k == 1 && off < 0.125) {
                assert_float_equal(px[0], 0.02, 1e-4);
                dark++;
                continue;
            }
            if (k == 1 && off < 0.2)
                continue; /* the line's edge: the gradient's differences round */
            const double want[3] = {sv / 7.0, 1.0 - sv / 7.0, 0.5};
            for (int c = 0; c < 3; c++) {
                if (k < 2) { /* on screen, the map's colour to the byte */
                    int got = image_tonemap(px[c], 1.0f);
                    assert_true(abs(got - (int)lround(want[c] * 255.0)) <= 1);
                } else { /* behind the cloud: that colour's radiance, dimmed */
                    double l = render_display_to_radiance((float)want[c], 1.0f);
                    assert_float_equal(px[c], seen * l, 1e-3 * l + 1e-6);
                }
            }
            assert_float_equal(px[3], 0.0, 1e-6); /* opaque */
        }
        if (k == 1)
            assert_int_equal(dark, 3 * 2); /* at s = 2, 4 and 6, two pixels each */
        image_finish(&img);
        ext_volume_finish(&v);
    }
}

/* Contours at given values (transfer_slice.contour_values) on test_slice_colours' slice:
 * lines at s = 1.5 and 5.25 only (no contour_every): dark within a pixel's width (0.125 units)
 * of them, the map's colour elsewhere. */
static void test_slice_contour_values(void **state)
{
    (void)state;
    float field[NX];
    for (int i = 0; i < NX; i++)
        field[i] = (float)i;
    struct ext_volume v = {0};
    make_volume(&v, 0.0f, field);
    v.slice[0] = v.layer[0];
    v.layer[0] = NULL;
    v.slice_field[0] = TRANSFER_FIELD_TEMPERATURE;
    struct transfer_slice sl = {.enabled = true,
                                .point = {0, 0, 1000.0},
                                .normal = {0, 0, 1},
                                .opacity = 1.0,
                                .contour_values = {1.5, 5.25},
                                .contour_count = 2};
    transfer_defaults(&sl.tf, TRANSFER_FIELD_TEMPERATURE);
    sl.tf.lo = 0.0;
    sl.tf.hi = 7.0;
    struct transfer_function *tf = &sl.tf;
    tf->count[TRANSFER_RED] = 2;
    tf->points[TRANSFER_RED][0] = (struct transfer_point){0.0f, 0.0f};
    tf->points[TRANSFER_RED][1] = (struct transfer_point){1.0f, 1.0f};
    tf->count[TRANSFER_GREEN] = 1;
    tf->points[TRANSFER_GREEN][0] = (struct transfer_point){0.0f, 1.0f};
    tf->count[TRANSFER_BLUE] = 1;
    tf->points[TRANSFER_BLUE][0] = (struct transfer_point){0.0f, 0.5f};
    struct render_slice rs;
    render_slice_from_transfer(&sl, 1.0f, &rs);
    assert_true(renderer_set_slices(renderer, &rs, 1));
    struct image img = {0};
    draw(&v, NULL, false, &img);
    assert_true(renderer_set_slices(renderer, NULL, 0));
    int dark[2] = {0, 0};
    for (int p = 8; p < W - 8; p++) {
        double sv = (p + 0.5) * NX * 1000.0 / W / 1000.0 - 0.5;
        const float *px = &img.rgba[4 * ((size_t)1 * W + p)];
        double off[2] = {fabs(sv - 1.5), fabs(sv - 5.25)};
        if (off[0] < 0.125 || off[1] < 0.125) {
            assert_float_equal(px[0], 0.02, 1e-4);
            dark[off[1] < 0.125]++;
            continue;
        }
        if (off[0] < 0.2 || off[1] < 0.2)
            continue; /* the line's edge */
        assert_true(abs(image_tonemap(px[0], 1.0f) - (int)lround(sv / 7.0 * 255.0)) <= 1);
        assert_true(abs(image_tonemap(px[1], 1.0f) - 255) <= 1);
    }
    assert_int_equal(dark[0], 2);
    assert_int_equal(dark[1], 2);
    image_finish(&img);
    ext_volume_finish(&v);
}

/* A slice following a model level whose height rises linearly with x, h(x) = 600 m + 0.1 x,
 * through a field that rises one unit a voxel along x and three along z, s = (x - 500 m) /
 * 1 km + 3 (z - 500 m) / 1 km (linear, so trilinear interpolation keeps it): straight down,
 * each pixel between the outer voxel centres shows the map's colour at s(x, h(x)) within
 * 1/255, the colour of the field on that level; a plane at the level's mean height would be up
 * to 0.9 units (23/255) off. */
static void test_slice_follows_level(void **state)
{
    (void)state;
    struct ext_volume v = {0};
    float zero[NX] = {0};
    make_volume(&v, 0.0f, zero);
    free(v.layer[0]);
    v.layer[0] = NULL;
    size_t n = grid3_count(&v.grid), plane = (size_t)v.grid.n[0] * v.grid.n[1];
    v.slice[0] = malloc(n * sizeof(float));
    v.slice_surface[0] = malloc(plane * sizeof(float));
    assert_non_null(v.slice[0]);
    assert_non_null(v.slice_surface[0]);
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < NX; i++)
                v.slice[0][grid3_index(&v.grid, i, j, k)] = (float)(i + 3 * k);
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < NX; i++)
            v.slice_surface[0][(size_t)j * NX + i] = (float)(600.0 + 0.1 * (i + 0.5) * 1000.0);
    v.slice_field[0] = TRANSFER_FIELD_W;
    struct transfer_slice sl = {.enabled = true,
                                .point = {0, 0, 1000.0},
                                .normal = {0, 0, 1},
                                .opacity = 1.0,
                                .level = 3};
    transfer_defaults(&sl.tf, TRANSFER_FIELD_W);
    sl.tf.lo = 0.0;
    sl.tf.hi = 10.0;
    struct transfer_function *tf = &sl.tf;
    tf->count[TRANSFER_RED] = 2;
    tf->points[TRANSFER_RED][0] = (struct transfer_point){0.0f, 0.0f};
    tf->points[TRANSFER_RED][1] = (struct transfer_point){1.0f, 1.0f};
    tf->count[TRANSFER_GREEN] = 2;
    tf->points[TRANSFER_GREEN][0] = (struct transfer_point){0.0f, 1.0f};
    tf->points[TRANSFER_GREEN][1] = (struct transfer_point){1.0f, 0.0f};
    tf->count[TRANSFER_BLUE] = 1;
    tf->points[TRANSFER_BLUE][0] = (struct transfer_point){0.0f, 0.5f};
    struct render_slice rs;
    render_slice_from_transfer(&sl, 1.0f, &rs);
    assert_true(renderer_set_slices(renderer, &rs, 1));
    struct image img = {0};
    draw(&v, NULL, false, &img);
    assert_true(renderer_set_slices(renderer, NULL, 0));
    for (int p = 8; p < W - 8; p++) {
        double x = (p + 0.5) * NX * 1000.0 / W, h = 600.0 + 0.1 * x;
        double sv = (x - 500.0) / 1000.0 + 3.0 * (h - 500.0) / 1000.0;
        const float *px = &img.rgba[4 * ((size_t)1 * W + p)];
        const double want[3] = {sv / 10.0, 1.0 - sv / 10.0, 0.5};
        for (int c = 0; c < 3; c++) {
            int got = image_tonemap(px[c], 1.0f);
            assert_true(abs(got - (int)lround(want[c] * 255.0)) <= 1);
        }
        assert_float_equal(px[3], 0.0, 1e-6);
    }
    image_finish(&img);
    /* Without its surface the slice is not drawn (not a plane in its place). */
    free(v.slice_surface[0]);
    v.slice_surface[0] = NULL;
    assert_true(renderer_set_slices(renderer, &rs, 1));
    draw(&v, NULL, false, &img);
    assert_true(renderer_set_slices(renderer, NULL, 0));
    assert_float_equal(img.rgba[4 * ((size_t)1 * W + W / 2) + 3], 1.0, 1e-6);
    image_finish(&img);
    ext_volume_finish(&v);
}

static int setup(void **state)
{
    ctx = test_gl_context_or_skip();
    log_set_level(LOG_WARN);
    renderer = renderer_create();
    return renderer ? 0 : -1;
}

static int teardown(void **state)
{
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_post_classification_step),
        cmocka_unit_test(test_layers_not_skipped),
        cmocka_unit_test(test_composited_with_clouds),
        cmocka_unit_test(test_tint_mode),
        cmocka_unit_test(test_slice_colours),
        cmocka_unit_test(test_slice_follows_level),
        cmocka_unit_test(test_slice_contour_values),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
