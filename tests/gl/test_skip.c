/* Empty-space skipping on EGL/llvmpipe (render.h, "empty-space skipping"): the macro cells
 * hold what a CPU computes from the same voxels, and leaping the empty ones leaves every
 * picture as it was without them (render.skip = false, the eye pass of before), while the rays
 * do measurably less: fewer extinction samples, steps leapt, rays never marched. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "session/effects.h"
#include "session/lightmaps.h"
#include "session/scene.h"
#include "common/log.h"
#include "gpu/gpu.h"
#include "render/render.h"

static struct gpu_context *ctx;
static struct renderer *renderer;

/* What the GPU's cells must hold: the CPU's cells of the same voxels (render_cells_cpu: per
 * level-0 cell the largest ice + water extinction, NaN and negative as 0, infinity as 1e30,
 * over the cell's voxels and HALO voxels around it, clamped to the volume; each further level
 * the largest of its 2 x 2 x 2 children).  NEXT (may be NULL) is a second volume of the same
 * grid whose values count too. */
static float *cpu_cells_halo(const struct ext_volume *vol, const struct ext_volume *next, int halo,
                             struct render_cells *layout)
{
    float *out = render_cells_cpu(vol, next, halo, layout);
    assert_non_null(out);
    return out;
}

static float *cpu_cells(const struct ext_volume *vol, const struct ext_volume *next,
                        struct render_cells *layout)
{
    return cpu_cells_halo(vol, next, 1, layout);
}

/* Compares the GPU's cells CELLS with the CPU's for VOL (and NEXT); returns the share of
 * level-0 cells that are empty. */
static double check_cells(const struct render_cells *cells, const struct ext_volume *vol,
                          const struct ext_volume *next)
{
    struct render_cells layout;
    float *want = cpu_cells(vol, next, &layout);
    assert_int_equal(cells->cell_voxels, layout.cell_voxels);
    assert_int_equal(cells->levels, layout.levels);
    assert_int_equal(cells->count, layout.count);
    assert_memory_equal(cells->dims, layout.dims, sizeof(layout.dims));
    const int *top = layout.dims[layout.levels - 1];
    assert_int_equal(top[0] * top[1] * top[2], 1); /* the pyramid ends in one cell */
    float *got = render_cells_read(cells);
    assert_non_null(got);
    for (size_t i = 0; i < layout.count; i++) {
        if (got[i] != want[i])
            fail_msg("cell %zu: GPU %g, CPU %g", i, got[i], want[i]);
    }
    size_t n0 = (size_t)layout.dims[0][0] * layout.dims[0][1] * layout.dims[0][2], clear = 0;
    for (size_t i = 0; i < n0; i++)
        clear += want[i] <= 0.0f;
    free(got);
    free(want);
    return (double)clear / (double)n0;
}

/* COUNT voxels of VOL (at places SEED picks) given water or ice of 1e-3 to 5e-3 per metre. */
static void scatter_voxels(struct ext_volume *vol, int count, unsigned seed)
{
    const int *n = vol->grid.n;
    for (int k = 0; k < count; k++) {
        seed = seed * 1664525u + 1013904223u;
        int x = (int)((seed >> 8) % (unsigned)n[0]);
        seed = seed * 1664525u + 1013904223u;
        int y = (int)((seed >> 8) % (unsigned)n[1]);
        seed = seed * 1664525u + 1013904223u;
        int z = (int)((seed >> 8) % (unsigned)n[2]);
        vol->beta[2 * grid3_index(&vol->grid, x, y, z) + (seed & 1)] = 1e-3f * (float)(1 + k % 5);
    }
}

/* The macro cells of a storm with bad values in it (NaN, infinity, negative), and of a single
 * voxel on a cell's face, whose footprint reaches into the neighbouring cell. */
static void test_cells_match_cpu(void **state)
{
    struct config cfg;
    const char *sets[] = {"scene.size=[44,37,21]"};
    test_config_from(&cfg, sets, 1);
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    size_t count = (size_t)vol.grid.n[0] * vol.grid.n[1] * vol.grid.n[2];
    vol.beta[2 * (count / 3)] = NAN;
    vol.beta[2 * (count / 2) + 1] = INFINITY;
    vol.beta[2 * (count / 5)] = -1.0f;
    assert_true(renderer_set_volume(renderer, &vol));
    double clear = check_cells(renderer_cells(renderer), &vol, NULL);
    print_message("storm 44x37x21: %.0f %% of the cells empty\n", 100.0 * clear);
    assert_true(clear > 0.3 && clear < 0.95); /* a test of both kinds of cell */
    assert_int_equal(renderer_cells(renderer)->cell_voxels, RENDER_CELL_VOXELS);
    ext_volume_finish(&vol);

    /* On the model's levels: larger cells, each row the run of levels its height holds. */
    const char *tall[] = {"scene.size=[44,37,40]"};
    test_config_from(&cfg, tall, 1);
    assert_true(scene_build_volume(&cfg, &vol));
    test_stretch_levels(&vol);
    assert_true(renderer_set_volume(renderer, &vol));
    clear = check_cells(renderer_cells(renderer), &vol, NULL);
    print_message("storm 44x37x40, stretched: %.0f %% of the cells empty\n", 100.0 * clear);
    assert_true(clear > 0.1 && clear < 0.95);
    assert_int_equal(renderer_cells(renderer)->cell_voxels, RENDER_CELL_VOXELS_STRETCHED);
    ext_volume_finish(&vol);

    const char *one[] = {"scene.kind=voxel", "scene.size=[17,17,17]", "scene.extent=[17,17,17]"};
    test_config_from(&cfg, one, 3);
    assert_true(scene_build_volume(&cfg, &vol));
    assert_true(renderer_set_volume(renderer, &vol));
    /* Voxel (8, 8, 8) is the first of cell k = 8 / b along each axis: trilinear samples in
     * cell k - 1 within a voxel of it read it, so cell k - 1 must hold it too, and cell k + 1
     * must not. */
    const struct render_cells *c = renderer_cells(renderer);
    check_cells(c, &vol, NULL);
    float *got = render_cells_read(c);
    const int *d = c->dims[0], k = 8 / c->cell_voxels;
    assert_int_equal(8 % c->cell_voxels, 0);
    for (int i = k - 1; i <= k + 1; i++)
        assert_true((got[i + d[0] * (i + d[1] * i)] > 0.0f) == (i <= k));
    free(got);
    ext_volume_finish(&vol);

    /* One voxel in a box wider than the clear distances reach: the GPU's distances are the
     * CPU's (above) from 1 next to the voxel's cells to the cap. */
    const char *wide[] = {"scene.kind=voxel", "scene.size=[160,136,72]",
                          "scene.extent=[160,136,72]"};
    test_config_from(&cfg, wide, 3);
    assert_true(scene_build_volume(&cfg, &vol));
    assert_true(renderer_set_volume(renderer, &vol));
    c = renderer_cells(renderer);
    check_cells(c, &vol, NULL);
    got = render_cells_read(c);
    float lowest = 0.0f, highest_clear = -1e30f;
    for (int i = 0; i < c->dims[0][0] * c->dims[0][1] * c->dims[0][2]; i++) {
        lowest = got[i] < lowest ? got[i] : lowest;
        if (got[i] <= 0.0f && got[i] > highest_clear)
            highest_clear = got[i];
    }
    assert_true(lowest == -(float)(RENDER_CELL_DISTANCE_MAX + 1));
    assert_true(highest_clear == -1.0f);
    free(got);
    ext_volume_finish(&vol);

    /* A few voxels scattered through an empty box whose sides are no multiple of a cell,
     * uniform and on the model's levels: every distance from 1 to the cap, GPU and CPU alike. */
    for (int stretched = 0; stretched < 2; stretched++) {
        const char *sparse[] = {"scene.kind=empty", "scene.size=[203,157,61]",
                                "scene.extent=[203,157,30]"};
        test_config_from(&cfg, sparse, 3);
        assert_true(scene_build_volume(&cfg, &vol));
        if (stretched)
            test_stretch_levels(&vol);
        scatter_voxels(&vol, 12, 5u);
        assert_true(renderer_set_volume(renderer, &vol));
        c = renderer_cells(renderer);
        check_cells(c, &vol, NULL);
        got = render_cells_read(c);
        bool seen[RENDER_CELL_DISTANCE_MAX + 2] = {false};
        for (int i = 0; i < c->dims[0][0] * c->dims[0][1] * c->dims[0][2]; i++)
            if (got[i] <= 0.0f)
                seen[(int)-got[i]] = true;
        for (int e = 1; e <= RENDER_CELL_DISTANCE_MAX + 1; e++)
            if (!seen[e] && (!stretched || e <= c->dims[0][2] / 2))
                fail_msg("%s: no clear cell %d cells from cloud",
                         stretched ? "stretched" : "uniform", e);
        free(got);
        ext_volume_finish(&vol);
    }
}

/* The cells of the volume shown built with PROGRAMS over several of cells_build.comp's work
 * groups (partly outside the volume at its far faces): whole, over the pair (the volume with
 * itself), and in pieces of 4 layers and 8 rows, each the CPU's cells. */
static void check_cells_ways(const struct render_cells_programs *p, const struct ext_volume *vol)
{
    const struct gpu_texture *beta = renderer_volume_texture(renderer);
    const struct grid3 *grid = renderer_grid(renderer);
    struct render_cells c = {0};
    assert_true(render_cells_build(&c, p, beta, NULL, grid));
    check_cells(&c, vol, NULL);
    assert_true(render_cells_build(&c, p, beta, beta, grid));
    check_cells(&c, vol, vol);
    assert_true(render_cells_build_begin(&c, beta, grid));
    int calls = 0;
    for (bool done = false; !done; calls++) {
        assert_true(render_cells_build_piece(&c, p, beta, NULL, grid, 4, 8, &done));
        assert_true(calls < 1000);
    }
    assert_true(calls > 2);
    check_cells(&c, vol, NULL);
    render_cells_finish(&c);
    /* The halo counts on this storm: cells without it would differ. */
    struct render_cells layout;
    float *with = cpu_cells_halo(vol, NULL, 1, &layout),
          *without = cpu_cells_halo(vol, NULL, 0, &layout);
    size_t differ = 0;
    for (size_t i = 0; i < layout.count; i++)
        differ += with[i] != without[i];
    assert_true(differ > 0);
    free(with);
    free(without);
}

/* The cells on storms of several work groups of cells a side, uniform and on the model's
 * levels, the same as the CPU's in every way of building them. */
static void test_cells_work_groups(void **state)
{
    struct render_cells_programs p;
    assert_true(render_cells_programs_init(&p));
    struct config cfg;
    const char *sets[] = {"scene.size=[70,45,30]"};
    test_config_from(&cfg, sets, 1);
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    assert_true(renderer_set_volume(renderer, &vol));
    check_cells_ways(&p, &vol);
    ext_volume_finish(&vol);
    const char *tall[] = {"scene.size=[140,75,40]"};
    test_config_from(&cfg, tall, 1);
    assert_true(scene_build_volume(&cfg, &vol));
    test_stretch_levels(&vol);
    assert_true(renderer_set_volume(renderer, &vol));
    assert_int_equal(renderer_cells(renderer)->cell_voxels, RENDER_CELL_VOXELS_STRETCHED);
    check_cells_ways(&p, &vol);
    ext_volume_finish(&vol);
    render_cells_programs_finish(&p);
}

/* The config's scene drawn with its own light map, with empty-space skipping and without;
 * *WITH and *WITHOUT what the rays did.  Returns the largest relative difference of any
 * channel. */
/* Voxels that skip_against_plain_on scatters through the scene's volume (0: none). */
static int scatter_count;

static double skip_against_plain_on(const char **sets, int n, bool stretched,
                                    struct render_counts *with, struct render_counts *without)
{
    struct config cfg;
    test_config_from(&cfg, sets, n);
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    if (stretched)
        test_stretch_levels(&vol);
    if (scatter_count)
        scatter_voxels(&vol, scatter_count, 17u + (unsigned)scatter_count);
    assert_true(renderer_set_volume(renderer, &vol));
    if (scatter_count)
        check_cells(renderer_cells(renderer), &vol, NULL);
    assert_true(renderer_set_optics(renderer, &cfg.optics.params));
    struct lightmaps light;
    struct effects e;
    test_scene_light(renderer, &cfg, &vol, &light, &e);
    struct render_view view;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &view);
    struct render_settings s;
    scene_render_settings(&cfg, &s);
    effects_apply_render(&e, &s);
    /* Skipping with the rays listed by ballot (where the driver offers it), skipping with
     * them listed through the work group's shared count, and the plain pass. */
    bool ballot = gpu_has_extension("GL_ARB_shader_ballot") &&
                  gpu_has_extension("GL_ARB_gpu_shader_int64");
    struct image img[3] = {{0}};
    struct render_counts shared;
    for (int k = 0; k < 3; k++) {
        s.no_skip = k == 2;
        assert_true(renderer_set_ballot(renderer, k == 0) == (k == 0 && ballot));
        struct gpu_texture out = {0};
        assert_true(renderer_set_counting(renderer, true));
        assert_true(renderer_draw(renderer, &s, &view, &out));
        assert_true(renderer_counts(renderer, k == 0 ? with : k == 1 ? &shared : without));
        assert_true(renderer_set_counting(renderer, false));
        assert_true(renderer_read(&out, &img[k]));
        gpu_texture_finish(&out);
    }
    renderer_set_ballot(renderer, true);
    /* The two ways of listing give the same rays the same work, bit for bit. */
    assert_memory_equal(img[0].rgba, img[1].rgba,
                        (size_t)img[0].width * img[0].height * 4 * sizeof(float));
    assert_memory_equal(with, &shared, sizeof(shared));
    double worst = 0.0;
    size_t values = (size_t)img[0].width * img[0].height * 4;
    for (size_t i = 0; i < values; i++) {
        double a = img[0].rgba[i], b = img[2].rgba[i];
        assert_true(isfinite(a));
        double scale = fmax(fabs(a), fabs(b));
        double rel = scale > 0.0 ? fabs(a - b) / scale : 0.0;
        worst = fmax(worst, rel);
    }
    for (int k = 0; k < 3; k++)
        image_finish(&img[k]);
    lightmaps_finish(&light);
    ext_volume_finish(&vol);
    /* Every ray counted once, with skipping or without; the plain pass marches them all. */
    assert_int_equal(with->rays, (uint64_t)cfg.render.width * cfg.render.height);
    assert_int_equal(without->rays, with->rays);
    assert_int_equal(without->rays_marched, without->rays);
    assert_int_equal(without->steps_leapt, 0);
    return worst;
}

static double skip_against_plain(const char **sets, int n, struct render_counts *with,
                                 struct render_counts *without)
{
    return skip_against_plain_on(sets, n, false, with, without);
}

/* Pictures within 1e-4 relative of the plain eye pass (on llvmpipe: bit for bit), on scenes
 * that take each path of the march: the storm (equal steps), a wide flat storm under a low sun
 * (its sheared light map makes the thick steps go in parts), a camera inside the storm, the
 * single voxel, a compressed light map, the storm and the flat storm on the model's uneven
 * levels (larger cells, read by height), and fewer samples every time. */
static void test_skipping_keeps_pictures(void **state)
{
    static const char *storm[] = {"scene.size=[48,48,24]", "render.width=96", "render.height=72"};
    static const char *flat[] = {"scene.size=[64,64,16]",     "scene.extent=[200,200,16]",
                                 "light.elevation=20",        "camera.position=[-20,-30,12]",
                                 "camera.target=[100,100,4]", "render.width=96",
                                 "render.height=72"};
    static const char *inside[] = {"scene.size=[48,48,24]", "camera.position=[8,10,12]",
                                   "camera.target=[30,30,6]", "render.width=80",
                                   "render.height=60"};
    static const char *voxel[] = {"scene.kind=voxel",
                                  "scene.size=[41,41,41]",
                                  "scene.extent=[9,9,9]",
                                  "camera.position=[-1,-3,9]",
                                  "camera.target=[4.5,4.5,4.5]",
                                  "camera.fov=30",
                                  "render.width=64",
                                  "render.height=64",
                                  "effects.shadows=on"};
    static const char *compressed[] = {"scene.size=[48,48,24]", "render.width=96",
                                       "render.height=72", "lightmap.mode=compressed"};
    /* Seen from inside the storm's box every ray meets an occupied cell; from outside most
     * rays are done in the first pass and most samples are leapt. */
    struct {
        const char *name;
        const char **sets;
        int n;
        bool inside, stretched;
    } cases[] = {{"storm", storm, 3, false, false},
                 {"flat storm, low sun", flat, 7, false, false},
                 {"inside", inside, 5, true, false},
                 {"one voxel", voxel, 9, false, false},
                 {"compressed", compressed, 4, false, false},
                 {"storm, stretched", storm, 3, false, true},
                 {"flat storm, stretched", flat, 7, false, true}};
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        struct render_counts with, without;
        double d = skip_against_plain_on(cases[i].sets, cases[i].n, cases[i].stretched, &with,
                                         &without);
        print_message("%-20s relative difference %.3g; beta samples %llu -> %llu, %llu steps "
                      "leapt, %llu of %llu rays marched\n",
                      cases[i].name, d, (unsigned long long)without.beta_samples,
                      (unsigned long long)with.beta_samples, (unsigned long long)with.steps_leapt,
                      (unsigned long long)with.rays_marched, (unsigned long long)with.rays);
        assert_true(d <= 1e-4);
        assert_true(with.steps_leapt > 0);
        assert_true(with.beta_samples < without.beta_samples);
        if (!cases[i].inside) {
            assert_true(with.rays_marched < with.rays);
            assert_true(with.beta_samples < without.beta_samples / 2);
        }
        /* What is marched reads the light map where the plain pass does: in cloud. */
        assert_int_equal(with.light_reads, without.light_reads);
    }
}

/* An empty box: no ray is marched, no voxel read, and the picture is the background; a ray
 * reads one macro cell, the pyramid's top (the walk alone reads a row of its top level's). */
static void test_empty_box_reads_nothing(void **state)
{
    const char *sets[] = {"scene.kind=empty", "scene.size=[32,32,16]", "render.width=64",
                          "render.height=48", "effects.shadows=on"};
    struct render_counts with, without;
    double d = skip_against_plain(sets, 5, &with, &without);
    assert_true(d == 0.0);
    assert_int_equal(with.rays_marched, 0);
    assert_int_equal(with.beta_samples, 0);
    assert_int_equal(with.light_reads, 0);
    assert_true(with.cells_read > 0);
    assert_true(with.cells_read <= with.rays);
    assert_true(without.beta_samples > 10 * without.rays); /* the plain pass marched */
}

/* A ray through clear cells leaps the cube of cells its clear distance vouches for at one
 * read: down a box 60 cells long with one voxel in its middle, the rays read a few cells each
 * (one cell at a time they would read 60 or more), and the picture is the plain one. */
static void test_clear_distance_leaps(void **state)
{
    const char *sets[] = {"scene.kind=voxel",          "scene.size=[240,64,64]",
                          "scene.extent=[240,64,64]",  "camera.position=[-60,32,32]",
                          "camera.target=[120,32,32]", "camera.fov=12",
                          "render.width=48",           "render.height=48",
                          "effects.shadows=on"};
    struct render_counts with, without;
    double d = skip_against_plain(sets, 9, &with, &without);
    print_message("relative difference %.3g; %.2f cells read a ray, %llu of %llu rays marched\n", d,
                  (double)with.cells_read / (double)with.rays,
                  (unsigned long long)with.rays_marched, (unsigned long long)with.rays);
    assert_true(d <= 1e-4);
    assert_true(with.rays_marched > 0); /* some rays meet the voxel's cells */
    assert_true(with.cells_read < 12 * with.rays);
}

/* A ray that starts in a clear cell exactly at the cap's distance from cloud: from a camera
 * inside the box at cell 13 along x, toward the voxel whose footprint reaches cell 29, the
 * first leap ends at that cell's face.  A leap one cell longer at the cap would go into it. */
static void test_clear_distance_at_the_cap(void **state)
{
    const char *sets[] = {"scene.kind=voxel",
                          "scene.size=[240,64,64]",
                          "scene.extent=[240,64,64]",
                          "camera.position=[54,32.3,32.2]",
                          "camera.target=[120,32.3,32.2]",
                          "camera.fov=6",
                          "render.width=32",
                          "render.height=32",
                          "effects.shadows=on"};
    struct render_counts with, without;
    double d = skip_against_plain(sets, 9, &with, &without);
    print_message("relative difference %.3g; %.2f cells read a ray\n", d,
                  (double)with.cells_read / (double)with.rays);
    assert_true(d <= 1e-4);
    assert_true(with.rays_marched > 0);
}

/* A few voxels scattered through empty boxes of odd sizes, uniform and on the model's levels,
 * seen from inside, from far off, grazing the floor and at the level of detail: the pictures
 * are the plain pass's. */
static void test_scattered_voxels_keep_pictures(void **state)
{
    static const char *cameras[][3] = {
        {"camera.position=[30,20,6]", "camera.target=[90,70,3]", "camera.fov=40"},
        {"camera.position=[-1500,-500,400]", "camera.target=[60,40,5]", "camera.fov=4"},
        {"camera.position=[-40,35,0.02]", "camera.target=[130,45,0.02]", "camera.fov=40"},
        {"camera.position=[-60,-80,60]", "camera.target=[60,40,5]", "camera.fov=40"}};
    for (int k = 0; k < 8; k++) {
        const char **cam = cameras[k % 4];
        const char *sets[] = {"scene.kind=empty",
                              "scene.size=[131,97,43]",
                              "scene.extent=[131,97,14]",
                              cam[0],
                              cam[1],
                              cam[2],
                              "camera.near=1",
                              "render.width=64",
                              "render.height=48",
                              "effects.shadows=on",
                              k == 3 ? "render.lod=2" : "render.skip=true"};
        scatter_count = 1 + 5 * k;
        struct render_counts with, without;
        double d = skip_against_plain_on(sets, 11, k >= 4, &with, &without);
        scatter_count = 0;
        print_message("%d voxels, %s, %s: relative difference %.3g, %llu of %llu rays marched\n",
                      1 + 5 * k, k >= 4 ? "stretched" : "uniform", cam[0], d,
                      (unsigned long long)with.rays_marched, (unsigned long long)with.rays);
        assert_true(d <= 1e-4);
    }
}

/* effects.temporal: the pair's cells hold the larger of both steps, and the blended picture
 * is the plain one. */
static void test_temporal_pair(void **state)
{
    struct config cfg;
    const char *sets[] = {"scene.size=[40,40,20]", "render.width=80", "render.height=60"};
    test_config_from(&cfg, sets, 3);
    struct ext_volume a = {0}, b = {0};
    assert_true(scene_build_volume(&cfg, &a));
    assert_true(config_set(&cfg, "scene.time=0.95"));
    assert_true(scene_build_volume(&cfg, &b));
    assert_true(renderer_set_volume(renderer, &a));
    assert_true(renderer_set_next_volume(renderer, &b));
    const struct render_cells *pair = renderer_pair_cells(renderer);
    assert_non_null(pair);
    check_cells(pair, &a, &b);
    /* The pair holds more than step k alone (the storm grew). */
    struct render_cells layout;
    float *one = cpu_cells(&a, NULL, &layout), *both = cpu_cells(&a, &b, &layout);
    size_t more = 0;
    for (size_t i = 0; i < layout.count; i++)
        more += both[i] > 0.0f && one[i] <= 0.0f;
    assert_true(more > 0);
    free(one);
    free(both);

    renderer_set_light(renderer, NULL);
    struct render_view view;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &view);
    struct render_settings s;
    scene_render_settings(&cfg, &s);
    s.temporal = true;
    s.temporal_f = 0.4f;
    struct image img[2] = {{0}};
    for (int k = 0; k < 2; k++) {
        s.no_skip = k == 1;
        struct gpu_texture out = {0};
        assert_true(renderer_draw(renderer, &s, &view, &out));
        assert_true(renderer_read(&out, &img[k]));
        gpu_texture_finish(&out);
    }
    size_t values = (size_t)img[0].width * img[0].height * 4;
    for (size_t i = 0; i < values; i++)
        assert_float_equal(img[0].rgba[i], img[1].rgba[i], 1e-4 * fabs(img[1].rgba[i]));
    image_finish(&img[0]);
    image_finish(&img[1]);
    assert_true(renderer_set_next_volume(renderer, NULL));
    assert_null(renderer_pair_cells(renderer));
    ext_volume_finish(&a);
    ext_volume_finish(&b);
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
        cmocka_unit_test(test_cells_match_cpu),
        cmocka_unit_test(test_cells_work_groups),
        cmocka_unit_test(test_skipping_keeps_pictures),
        cmocka_unit_test(test_empty_box_reads_nothing),
        cmocka_unit_test(test_clear_distance_leaps),
        cmocka_unit_test(test_clear_distance_at_the_cap),
        cmocka_unit_test(test_scattered_voxels_keep_pictures),
        cmocka_unit_test(test_temporal_pair),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
