/* A WRF parent and its nest in one picture (data/nest.h) on EGL/llvmpipe: a pair written here
 * from one analytic field, looked at from above with the nest's edge in view, renders as the
 * parent alone does to within the parent's own step error (the same picture at a quarter of
 * the step), while the same nest misplaced by one parent column does not: the seam it makes
 * is larger than the step error.  Empty-space skipping keeps the pair's picture as it is. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "common/log.h"
#include "data/wrf_write.h"
#include "gpu/gpu.h"
#include "render/image.h"
#include "render/render.h"
#include "session/effects.h"
#include "session/lightmaps.h"
#include "session/scene.h"

#define PI 3.14159265358979323846
#define DX 2000.0
#define NXP 24
#define NZ 10
#define DZ 500.0
#define RATIO 3
#define IPS 9
#define NNEST 8

static struct gpu_context *ctx;
static struct renderer *renderer;

static double field(double x, double y, double z)
{
    if (z < 1500.0 || z > 3500.0)
        return 0.0;
    return 2e-6 * (1.0 + 0.6 * sin(2.0 * PI * x / 20000.0) * cos(2.0 * PI * y / 24000.0));
}

static void write_domain(const char *name, const struct grid3 *g, double x0, double y0,
                         const struct wrf_write_desc *d)
{
    struct field_volume fv;
    memset(&fv, 0, sizeof(fv));
    fv.grid = *g;
    fv.q[SPECIES_CLOUD] = calloc(grid3_count(g), sizeof(float));
    assert_non_null(fv.q[SPECIES_CLOUD]);
    for (int k = 0; k < g->n[2]; k++)
        for (int j = 0; j < g->n[1]; j++)
            for (int i = 0; i < g->n[0]; i++)
                fv.q[SPECIES_CLOUD][grid3_index(g, i, j, k)] =
                    (float)field(x0 + (i + 0.5) * g->spacing[0], y0 + (j + 0.5) * g->spacing[1],
                                 (k + 0.5) * g->spacing[2]);
    struct wrf_writer *w = wrf_writer_create(test_tmp_path(name), g, d);
    assert_non_null(w);
    assert_true(wrf_writer_add(w, &fv, "2005-08-28_12:00:00"));
    assert_true(wrf_writer_finish(w));
    field_volume_finish(&fv);
}

/* wrfout_d01.nc, wrfout_d02.nc (the nest at parent column IPS, IPS) and shifted_d02.nc (the
 * same nest, its attributes saying it starts one parent column further east). */
static void write_files(void)
{
    struct grid3 pg = {.n = {NXP, NXP, NZ}, .spacing = {DX, DX, DZ}, .origin = {0, 0, 0}};
    struct grid3 ng = {.n = {NNEST * RATIO, NNEST * RATIO, NZ},
                       .spacing = {DX / RATIO, DX / RATIO, DZ},
                       .origin = {0, 0, 0}};
    double ex = NXP * DX;
    struct wrf_write_desc pd = {.cen_lat = 25.0,
                                .cen_lon = -89.0,
                                .grid_id = 1,
                                .parent_id = 1,
                                .i_parent_start = 1,
                                .j_parent_start = 1,
                                .parent_grid_ratio = 1,
                                .map_corner_m = {-0.5 * ex, -0.5 * ex}};
    write_domain("wrfout_d01.nc", &pg, 0.0, 0.0, &pd);
    struct wrf_write_desc nd = pd;
    nd.grid_id = 2;
    nd.i_parent_start = IPS;
    nd.j_parent_start = IPS;
    nd.parent_grid_ratio = RATIO;
    nd.map_corner_m[0] += (IPS - 1) * DX;
    nd.map_corner_m[1] += (IPS - 1) * DX;
    write_domain("wrfout_d02.nc", &ng, (IPS - 1) * DX, (IPS - 1) * DX, &nd);
    nd.i_parent_start = IPS + 1;
    write_domain("shifted_d02.nc", &ng, (IPS - 1) * DX, (IPS - 1) * DX, &nd);
}

/* The scene of FILES (NULL-terminated names in the temporary folder) at STEP metres, from
 * above, into IMG. */
static void render(const char *const *files, double step, bool no_skip, struct image *img)
{
    char list[2048] = "data.files=[", stepset[64];
    for (int i = 0; files[i]; i++) {
        char one[600];
        snprintf(one, sizeof(one), "%s\"%s\"", i ? "," : "", test_tmp_path(files[i]));
        strcat(list, one);
    }
    strcat(list, "]");
    snprintf(stepset, sizeof(stepset), "render.step=%g", step);
    const char *sets[] = {"scene.kind=data",
                          list,
                          stepset,
                          "camera.position=[24,20,90]",
                          "camera.target=[24,24,0]",
                          "camera.up=[0,1,0]",
                          "camera.fov=32",
                          "render.width=96",
                          "render.height=96",
                          "light.elevation=60",
                          "light.azimuth=30",
                          "effects.multiple=off",
                          "effects.lateral=off",
                          "effects.shadows=on",
                          "effects.forward=off",
                          "effects.peripheral=off",
                          "effects.phase=off"};
    struct config cfg;
    test_config_from(&cfg, sets, (int)(sizeof(sets) / sizeof(sets[0])));
    struct ext_volume vol = {0};
    test_upload_scene(renderer, &cfg, &vol);
    struct lightmaps light;
    struct effects e;
    test_scene_light(renderer, &cfg, &vol, &light, &e);
    struct render_view view;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &view);
    struct render_settings s;
    scene_render_settings(&cfg, &s);
    effects_apply_render(&e, &s);
    s.no_skip = no_skip;
    struct gpu_texture out = {0};
    assert_true(renderer_draw(renderer, &s, &view, &out));
    assert_true(renderer_read(&out, img));
    gpu_texture_finish(&out);
    lightmaps_finish(&light);
    ext_volume_finish(&vol);
}

/* Largest difference of the RGB radiance, relative to the brightest pixel of A. */
static double worst(const struct image *a, const struct image *b)
{
    double top = 0.0, diff = 0.0;
    size_t n = (size_t)a->width * a->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            double x = a->rgba[4 * i + c], y = b->rgba[4 * i + c];
            assert_true(isfinite(x) && isfinite(y));
            top = fmax(top, x);
            diff = fmax(diff, fabs(x - y));
        }
    return diff / top;
}

static void test_nest_seamless(void **state)
{
    (void)state;
    write_files();
    const char *parent[] = {"wrfout_d01.nc", NULL};
    const char *pair[] = {"wrfout_d01.nc", "wrfout_d02.nc", NULL};
    const char *shifted[] = {"wrfout_d01.nc", "shifted_d02.nc", NULL};
    /* Half the parent's column: what render.step = 0 takes on the parent alone. */
    const double step = 0.5 * DX;
    struct image p = {0}, fine = {0}, c = {0}, m = {0}, plain = {0};
    render(parent, step, false, &p);
    render(parent, 0.25 * step, false, &fine);
    render(pair, step, false, &c);
    render(shifted, step, false, &m);
    render(pair, step, true, &plain);
    double step_error = worst(&p, &fine);
    double seam = worst(&p, &c);
    double misplaced = worst(&p, &m);
    printf("# step error %.3g, parent + nest against the parent %.3g, misplaced nest %.3g\n",
           step_error, seam, misplaced);
    assert_true(step_error > 0.0);
    assert_true(seam > 0.0); /* the nest is drawn */
    assert_true(seam < step_error);
    assert_true(misplaced > step_error);
    /* Empty-space skipping over the composite leaves the picture as the plain march draws it
     * (its cells are the composite's). */
    assert_true(worst(&c, &plain) < 1e-6);
    image_finish(&p);
    image_finish(&fine);
    image_finish(&c);
    image_finish(&m);
    image_finish(&plain);
}

static int setup(void **state)
{
    (void)state;
    ctx = test_gl_context_or_skip();
    log_set_level(LOG_WARN);
    renderer = renderer_create();
    return renderer ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nest_seamless),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
