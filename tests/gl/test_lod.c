/* The eye pass's level of detail on EGL/llvmpipe (render.lod, render.h "lod_pixels"): where a
 * pixel is narrower than the voxel rule's step nothing changes, bit for bit; where the
 * voxels look smaller than a pixel the rays take steps a few pixels wide, read the volume
 * fewer times and draw nearly the same picture; perspective and orthographic views alike, and
 * empty-space skipping stays exact over the growing steps. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include <cglm/cglm.h>

#include "common/log.h"
#include "gpu/gpu.h"
#include "render/render.h"
#include "session/effects.h"
#include "session/lightmaps.h"
#include "session/scene.h"

static struct gpu_context *ctx;
static struct renderer *renderer;

struct drawn {
    struct image img;
    struct render_counts counts;
};

/* The config SETS's scene (on uneven levels with STRETCHED: test_stretch_levels) drawn with
 * its own light map and effects at render.lod = LOD (skipping off with NO_SKIP), from its
 * camera or, with ORTHO 1, along the y axis through an orthographic view of the whole box (2:
 * the same view tilted 10 degrees down, where the steps' bound at half a voxel's height
 * binds); with
 * DECK > 0 all but the levels [DECK, DECK + 2) emptied first, a thin layer across the box. */
static void draw_deck(const char **sets, int n, float lod, bool no_skip, int ortho, bool stretched,
                      int deck, struct drawn *out)
{
    struct config cfg;
    test_config_from(&cfg, sets, n);
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    if (stretched)
        test_stretch_levels(&vol);
    if (deck > 0) {
        const int *d = vol.grid.n;
        for (int z = 0; z < d[2]; z++)
            if (z < deck || z >= deck + 2)
                memset(vol.beta + 2 * (size_t)d[0] * d[1] * z, 0,
                       2 * (size_t)d[0] * d[1] * sizeof(float));
    }
    assert_true(renderer_set_volume(renderer, &vol));
    assert_true(renderer_set_optics(renderer, &cfg.optics.params));
    struct lightmaps light;
    struct effects e;
    test_scene_light(renderer, &cfg, &vol, &light, &e);
    struct render_view view;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &view);
    if (ortho) {
        const struct grid3 *g = &vol.grid;
        float size[3], mid[3];
        for (int i = 0; i < 3; i++) {
            size[i] = (float)(g->n[i] * g->spacing[i]);
            mid[i] = (float)g->origin[i] + 0.5f * size[i];
        }
        mat4 p, v;
        float down = ortho == 2 ? 0.1745329f : 0.0f;
        vec3 eye = {mid[0], mid[1] - 2.0f * size[1] * cosf(down),
                    mid[2] + 2.0f * size[1] * sinf(down)},
             at = {mid[0], mid[1], mid[2]};
        vec3 up = {0.0f, 0.0f, 1.0f};
        float half_w = 0.55f * size[0], half_h = half_w * (float)view.height / (float)view.width;
        glm_ortho(-half_w, half_w, -half_h, half_h, 1.0f, 4.0f * size[1], p);
        glm_lookat(eye, at, up, v);
        memcpy(view.proj, p, sizeof(view.proj));
        memcpy(view.view, v, sizeof(view.view));
    }
    struct render_settings s;
    scene_render_settings(&cfg, &s);
    effects_apply_render(&e, &s);
    s.lod_pixels = lod;
    s.no_skip = no_skip;
    struct gpu_texture tex = {0};
    assert_true(renderer_set_counting(renderer, true));
    assert_true(renderer_draw(renderer, &s, &view, &tex));
    assert_true(renderer_counts(renderer, &out->counts));
    assert_true(renderer_set_counting(renderer, false));
    memset(&out->img, 0, sizeof(out->img));
    assert_true(renderer_read(&tex, &out->img));
    gpu_texture_finish(&tex);
    lightmaps_finish(&light);
    ext_volume_finish(&vol);
}

static void draw_on(const char **sets, int n, float lod, bool no_skip, int ortho, bool stretched,
                    struct drawn *out)
{
    draw_deck(sets, n, lod, no_skip, ortho, stretched, 0, out);
}

static void draw_scene(const char **sets, int n, float lod, bool no_skip, int ortho,
                       struct drawn *out)
{
    draw_on(sets, n, lod, no_skip, ortho, false, out);
}

static size_t values_of(const struct drawn *d)
{
    return (size_t)d->img.width * d->img.height * 4;
}

/* RMS of A - B over B's RMS (colour channels); *WORST the largest |A - B| over B's largest. */
static double rms_off(const struct drawn *a, const struct drawn *b, double *worst)
{
    double d = 0.0, s = 0.0, big = 0.0, top = 0.0;
    for (size_t i = 0; i < values_of(a); i++) {
        if (i % 4 == 3)
            continue;
        assert_true(isfinite(a->img.rgba[i]));
        double e = (double)a->img.rgba[i] - b->img.rgba[i];
        d += e * e;
        s += (double)b->img.rgba[i] * b->img.rgba[i];
        big = fmax(big, fabs(e));
        top = fmax(top, fabs((double)b->img.rgba[i]));
    }
    *worst = big / top;
    return sqrt(d / s);
}

static double mean_of(const struct drawn *d)
{
    double m = 0.0;
    for (size_t i = 0; i < values_of(d); i++)
        m += i % 4 == 3 ? 0.0 : d->img.rgba[i];
    return m;
}

/* A pixel narrower than the step everywhere: render.lod changes no bit of the picture and
 * no sample (the storm at 640 x 480, where a pixel at the storm is 40 - 160 m and the voxel
 * rule's step 235 m and more, at render.lod = 1; and any scene at a tiny level). */
static void test_no_change_where_pixels_are_fine(void **state)
{
    static const char *storm[] = {"scene.size=[64,64,32]", "render.width=320", "render.height=240"};
    static const char *inside[] = {"scene.size=[48,48,24]", "camera.position=[8,10,12]",
                                   "camera.target=[30,30,6]", "render.width=80",
                                   "render.height=60"};
    const char **cases[] = {storm, inside};
    int counts[] = {3, 5};
    for (int c = 0; c < 2; c++) {
        struct drawn off, on;
        draw_scene(cases[c], counts[c], 0.0f, false, false, &off);
        draw_scene(cases[c], counts[c], 0.01f, false, false, &on);
        assert_memory_equal(off.img.rgba, on.img.rgba, values_of(&off) * sizeof(float));
        assert_int_equal(off.counts.beta_samples, on.counts.beta_samples);
        assert_int_equal(off.counts.light_reads, on.counts.light_reads);
        image_finish(&off.img);
        image_finish(&on.img);
    }
}

/* A storm whose voxels (375 m) look several times smaller than a pixel (96 x 72 at 20 - 80 km:
 * 260 m - 1 km) in perspective, and the same storm from an orthographic view (a pixel 0.46 km
 * everywhere): each further level samples less, the pictures stay close to the full march's,
 * and skipping leaves them as they are without it. */
static void test_fewer_samples_nearly_the_same_picture(void **state)
{
    static const char *fine[] = {"scene.size=[160,160,64]", "render.width=96", "render.height=72"};
    for (int ortho = 0; ortho < 2; ortho++) {
        struct drawn off;
        draw_scene(fine, 3, 0.0f, false, ortho, &off);
        uint64_t before = off.counts.beta_samples;
        const float levels[] = {1.0f, 2.0f};
        for (int k = 0; k < 2; k++) {
            struct drawn on, plain;
            draw_scene(fine, 3, levels[k], false, ortho, &on);
            draw_scene(fine, 3, levels[k], true, ortho, &plain);
            double worst;
            double rms = rms_off(&on, &off, &worst);
            double mean = mean_of(&on) / mean_of(&off);
            print_message("%s, render.lod = %.0f: beta samples %llu -> %llu (%.2f), light reads "
                          "%llu -> %llu, RMS %.4f, at most %.4f, mean %.4f\n",
                          ortho ? "orthographic" : "perspective", levels[k],
                          (unsigned long long)off.counts.beta_samples,
                          (unsigned long long)on.counts.beta_samples,
                          (double)on.counts.beta_samples / (double)off.counts.beta_samples,
                          (unsigned long long)off.counts.light_reads,
                          (unsigned long long)on.counts.light_reads, rms, worst, mean);
            assert_true(on.counts.beta_samples < before);
            before = on.counts.beta_samples;
            /* Skipping leaps only steps whose samples would read nothing. */
            assert_memory_equal(on.img.rgba, plain.img.rgba, values_of(&on) * sizeof(float));
            assert_true(on.counts.steps_leapt > 0);
            assert_true(rms < 0.06 * levels[k]);
            assert_true(fabs(mean - 1.0) < 0.01);
            image_finish(&on.img);
            image_finish(&plain.img);
        }
        image_finish(&off.img);
    }
}

/* Other scenes of the march with a level of detail: a wide flat storm under a low sun (its
 * sheared light map), the model's uneven levels (steps that follow the level they start in),
 * a camera inside the storm, and an orthographic view tilted down (steps of one width, held
 * at half a voxel's height).  Skipping leaves each picture as it is without it, and the steps
 * grown to two pixels read the volume less than the plain march.  The same flat storm on
 * coarser voxels takes its thick steps in light map node parts: there the grown steps are
 * leapt one by one as that path's plain ones, and a grown step that is thick is the plain step
 * first (both reached on some rays of this view: counted once in a shader made for it). */
static void test_skipping_exact_on_every_path(void **state)
{
    static const char *flat[] = {"scene.size=[128,128,16]",   "scene.extent=[200,200,16]",
                                 "light.elevation=20",        "camera.position=[-20,-30,12]",
                                 "camera.target=[100,100,4]", "render.width=96",
                                 "render.height=72"};
    static const char *parts[] = {"scene.size=[64,64,16]",     "scene.extent=[200,200,16]",
                                  "light.elevation=20",        "camera.position=[-20,-30,12]",
                                  "camera.target=[100,100,4]", "render.width=96",
                                  "render.height=72"};
    static const char *storm[] = {"scene.size=[96,96,48]", "render.width=96", "render.height=72"};
    static const char *inside[] = {"scene.size=[96,96,48]", "camera.position=[8,10,12]",
                                   "camera.target=[30,30,6]", "render.width=80",
                                   "render.height=60"};
    struct {
        const char *name;
        const char **sets;
        int n;
        bool stretched;
        int ortho;
    } cases[] = {{"flat storm, low sun", flat, 7, false, 0},
                 {"flat storm, in parts", parts, 7, false, 0},
                 {"storm, stretched", storm, 3, true, 0},
                 {"inside", inside, 5, false, 0},
                 {"orthographic, tilted", storm, 3, false, 2}};
    for (size_t c = 0; c < sizeof(cases) / sizeof(cases[0]); c++) {
        struct drawn off, on, plain;
        draw_on(cases[c].sets, cases[c].n, 0.0f, false, cases[c].ortho, cases[c].stretched, &off);
        draw_on(cases[c].sets, cases[c].n, 2.0f, false, cases[c].ortho, cases[c].stretched, &on);
        draw_on(cases[c].sets, cases[c].n, 2.0f, true, cases[c].ortho, cases[c].stretched, &plain);
        double worst, rms = rms_off(&on, &off, &worst);
        print_message("%-20s beta samples %llu -> %llu, %llu steps leapt, RMS %.4f off the "
                      "plain march's\n",
                      cases[c].name, (unsigned long long)off.counts.beta_samples,
                      (unsigned long long)on.counts.beta_samples,
                      (unsigned long long)on.counts.steps_leapt, rms);
        assert_memory_equal(on.img.rgba, plain.img.rgba, values_of(&on) * sizeof(float));
        assert_true(on.counts.steps_leapt > 0);
        assert_true(on.counts.beta_samples < off.counts.beta_samples);
        assert_true(rms < 0.12);
        image_finish(&off.img);
        image_finish(&on.img);
        image_finish(&plain.img);
    }
}

/* A deck two levels thick (a slab cut down to 500 m of a 16 km box), seen from 100 km at 25
 * degrees down, where four pixels are 5 km and a ray crosses the deck in 1.2 km: the grown
 * steps stop at half a level's crossing, so every ray samples the deck on its way through,
 * on uniform levels and on the model's (with the automatic step, and with render.step, a
 * deck of the thin low levels), and the picture is the plain march's within 2 % (steps of
 * four pixels' width step over it on some rays and not on others). */
static void test_thin_deck_kept(void **state)
{
    /* The last setting only in the third case: render.step set, on uneven levels, where the
     * steps follow no level: they stop at half the crossing of the thinnest. */
    static const char *deck[] = {"scene.kind=slab",
                                 "scene.size=[32,32,64]",
                                 "scene.tau=40",
                                 "camera.position=[-40,-40,45]",
                                 "camera.target=[30,30,8]",
                                 "render.width=96",
                                 "render.height=72",
                                 "render.ground_on=false",
                                 "render.step=150"};
    for (int c = 0; c < 3; c++) {
        bool stretched = c > 0;
        int n = c == 2 ? 9 : 8, level = c == 2 ? 3 : 32; /* low down: thin levels there */
        struct drawn off, on;
        draw_deck(deck, n, 0.0f, false, false, stretched, level, &off);
        draw_deck(deck, n, 4.0f, false, false, stretched, level, &on);
        double worst, rms = rms_off(&on, &off, &worst);
        double mean = mean_of(&on) / mean_of(&off);
        print_message("deck%s, render.lod = 4: beta samples %llu -> %llu, RMS %.4f, at most "
                      "%.4f, mean %.4f\n",
                      c == 2      ? " on uneven levels, render.step = 150"
                      : stretched ? " on uneven levels"
                                  : "",
                      (unsigned long long)off.counts.beta_samples,
                      (unsigned long long)on.counts.beta_samples, rms, worst, mean);
        assert_true(rms < 0.02);
        assert_true(fabs(mean - 1.0) < 0.01);
        image_finish(&off.img);
        image_finish(&on.img);
    }
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
        cmocka_unit_test(test_no_change_where_pixels_are_fine),
        cmocka_unit_test(test_fewer_samples_nearly_the_same_picture),
        cmocka_unit_test(test_skipping_exact_on_every_path),
        cmocka_unit_test(test_thin_deck_kept),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
