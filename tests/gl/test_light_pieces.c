/* The light map built in pieces (light_gpu_build_begin / _step, as staged playback builds the
 * next step's between frames) against the one-piece build (light_gpu_update): the same bits,
 * for every pass that is cut (lateral rates, slices, sweep, the columns' diffuse pass, the
 * diffuse light volume's solve, the compression) and the ones that stay whole, with another
 * map's build between every two pieces (it rebinds the same units and images, as a frame
 * does); and the macro cells built in pieces against the cells built whole. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "thin_layer.h"

#include "common/log.h"
#include "gpu/gpu.h"
#include "light/light.h"
#include "light/light_gpu.h"
#include "light/light_volume.h"
#include "render/render.h"
#include "session/scene.h"

static struct gpu_context *ctx;
static struct renderer *renderer;

enum variant { BEAM, PERIPHERAL, DIFFUSE, VOLUME, HALF, COMPRESSED };

static void settings_for(const struct config *cfg, enum variant v, struct light_settings *s)
{
    light_settings_defaults(s);
    memcpy(s->resolution, cfg->lightmap.resolution, sizeof(s->resolution));
    light_settings_set_optics(s, &cfg->optics.params, cfg->lightmap.forward_angle_deg);
    s->forward = true;
    s->peripheral = v != BEAM && v != HALF; /* HALF: the sweep not cut, one dispatch */
    s->multiple = v == DIFFUSE || v == VOLUME || v == COMPRESSED || v == HALF;
    s->lateral = s->multiple;
    s->volume = v == VOLUME;
    s->epsilon = 1.0 / 255.0;
}

/* Everything the map holds, read back: the light and diffuse light (dense), or the compressed
 * columns and nodes, and the diffuse light volume.  Compared byte for byte. */
struct held {
    struct light_map dense;
    struct light_compressed compressed;
    struct light_volume volume;
};

static void read_all(const struct light_gpu *lg, enum variant v, struct held *h)
{
    memset(h, 0, sizeof(*h));
    if (v == COMPRESSED)
        assert_true(light_gpu_read_compressed(lg, &h->compressed));
    else
        assert_true(light_gpu_read(lg, &h->dense));
    if (v == VOLUME)
        assert_true(light_gpu_read_volume(lg, &h->volume));
}

static void assert_same(const struct held *a, const struct held *b, enum variant v)
{
    if (v == COMPRESSED) {
        const struct light_compressed *x = &a->compressed, *y = &b->compressed;
        size_t ncol = (size_t)x->grid.n[0] * x->grid.n[1];
        assert_int_equal(x->node_count, y->node_count);
        assert_int_equal(x->diffuse_node_count, y->diffuse_node_count);
        assert_memory_equal(x->columns, y->columns, 2 * ncol * sizeof(uint32_t));
        assert_memory_equal(x->nodes, y->nodes, 2 * x->node_count * sizeof(float));
        assert_memory_equal(x->diffuse_columns, y->diffuse_columns, 2 * ncol * sizeof(uint32_t));
        assert_memory_equal(x->diffuse_nodes, y->diffuse_nodes,
                            3 * x->diffuse_node_count * sizeof(float));
        return;
    }
    const struct light_map *x = &a->dense, *y = &b->dense;
    size_t count = (size_t)x->grid.n[0] * x->grid.n[1] * x->grid.n[2];
    assert_memory_equal(x->grid.n, y->grid.n, sizeof(x->grid.n));
    assert_memory_equal(x->light, y->light, count * sizeof(float));
    assert_true((x->diffuse == NULL) == (y->diffuse == NULL));
    if (x->diffuse)
        assert_memory_equal(x->diffuse, y->diffuse, 2 * count * sizeof(float));
    if (v == VOLUME) {
        assert_int_equal(a->volume.iterations, b->volume.iterations);
        assert_memory_equal(a->volume.field, b->volume.field,
                            grid3_count(&a->volume.grid) * 4 * sizeof(float));
    }
}

static void held_finish(struct held *h)
{
    light_map_finish(&h->dense);
    light_compressed_finish(&h->compressed);
    light_volume_finish(&h->volume);
}

/* A light map of the scene SETS in variant V built whole and in pieces of a budget of 0 ms
 * (one piece a call), another map built between every two; returns the number of calls. */
static int compare(const char **sets, int n, enum variant v)
{
    struct config cfg;
    struct ext_volume vol = {0};
    test_config_from(&cfg, sets, n);
    test_upload_scene(renderer, &cfg, &vol);
    struct light_settings s;
    settings_for(&cfg, v, &s);
    enum light_gpu_mode mode = v == COMPRESSED ? LIGHT_GPU_COMPRESSED : LIGHT_GPU_DENSE;
    double sun[3], other_sun[3];
    light_sun_direction(cfg.light.azimuth_deg, cfg.light.elevation_deg, sun);
    light_sun_direction(cfg.light.azimuth_deg + 90.0, 25.0, other_sun);
    struct light_gpu_source src = {renderer_volume_texture(renderer), renderer_grid(renderer), 1,
                                   1, renderer_cells(renderer)};
    struct light_gpu *whole = light_gpu_create(), *pieces = light_gpu_create(),
                     *other = light_gpu_create();
    assert_non_null(whole);
    assert_non_null(pieces);
    assert_non_null(other);
    light_gpu_set_half(whole, v == HALF);
    light_gpu_set_half(pieces, v == HALF);
    bool built = false;
    assert_true(light_gpu_update(whole, &src, sun, &s, mode, &built));
    assert_true(built);

    bool needed = false, done = false;
    assert_true(light_gpu_build_begin(pieces, &src, sun, &s, mode, &needed));
    assert_true(needed);
    int calls = 0;
    struct light_settings os = s;
    os.volume = false;
    while (!done) {
        /* Begun again for the same key: resumed, not restarted. */
        assert_true(light_gpu_build_begin(pieces, &src, sun, &s, mode, &needed));
        assert_true(needed && light_gpu_building(pieces));
        assert_true(light_gpu_build_step(pieces, 0.0, &done));
        calls++;
        /* Something else on the GPU between two pieces. */
        other_sun[0] = -other_sun[0];
        assert_true(light_gpu_update(other, &src, other_sun, &os, LIGHT_GPU_DENSE, NULL));
        assert_true(calls < 10000);
    }
    assert_false(light_gpu_building(pieces));
    assert_int_equal(light_gpu_builds(pieces), 1);
    /* Built: nothing to do for the same key. */
    assert_true(light_gpu_build_begin(pieces, &src, sun, &s, mode, &needed));
    assert_false(needed);
    assert_true(light_gpu_update(pieces, &src, sun, &s, mode, &built));
    assert_false(built);

    struct held a, b;
    read_all(whole, v, &a);
    read_all(pieces, v, &b);
    assert_same(&a, &b, v);
    held_finish(&a);
    held_finish(&b);
    light_gpu_destroy(whole);
    light_gpu_destroy(pieces);
    light_gpu_destroy(other);
    ext_volume_finish(&vol);
    return calls;
}

/* The macro cells of the scene uploaded last built whole and 4 layers of cells a piece, ROWS
 * rows of them (0: all; another volume's cells built between every two pieces, with the same
 * programs); returns the pieces. */
static int compare_cells(int rows)
{
    const struct gpu_texture *beta = renderer_volume_texture(renderer);
    const struct grid3 *grid = renderer_grid(renderer);
    struct render_cells_programs p;
    assert_true(render_cells_programs_init(&p));
    struct render_cells whole = {0}, pieces = {0}, other = {0};
    assert_true(render_cells_build(&whole, &p, beta, NULL, grid));
    assert_true(render_cells_build_begin(&pieces, beta, grid));
    int calls = 0;
    for (bool done = false; !done; calls++) {
        /* 4 layers a piece (a multiple of cells_build.comp's local size); between two, the
         * same program run whole over the same volume, and the one over two volumes. */
        assert_true(render_cells_build_piece(&pieces, &p, beta, NULL, grid, 4, rows, &done));
        assert_true(render_cells_build(&other, &p, beta, NULL, grid));
        assert_true(render_cells_build(&other, &p, beta, beta, grid));
        assert_true(calls < 1000);
    }
    assert_int_equal(whole.count, pieces.count);
    assert_int_equal(whole.levels, pieces.levels);
    float *a = render_cells_read(&whole), *b = render_cells_read(&pieces);
    assert_non_null(a);
    assert_non_null(b);
    assert_memory_equal(a, b, whole.count * sizeof(float));
    /* Not all zero: the comparison saw the scene. */
    float top = 0.0f;
    for (size_t i = 0; i < whole.count; i++)
        top = a[i] > top ? a[i] : top;
    assert_true(top > 0.0f);
    free(a);
    free(b);
    render_cells_finish(&whole);
    render_cells_finish(&pieces);
    render_cells_finish(&other);
    render_cells_programs_finish(&p);
    return calls;
}

static const char *storm[] = {"scene.size=[48,48,24]", "lightmap.resolution=[32,32,40]"};

static void test_pieces_match_whole(void **state)
{
    (void)state;
    const char *names[] = {"beam", "peripheral", "diffuse", "volume", "half", "compressed"};
    int calls[COMPRESSED + 1];
    for (int v = BEAM; v <= COMPRESSED; v++) {
        calls[v] = compare(storm, 2, (enum variant)v);
        print_message("%s: %d pieces\n", names[v], calls[v]);
        /* Cut, not one piece: the slices alone are 20 pieces of 2 at 40 planes. */
        assert_true(calls[v] > 20);
    }
    /* The columns' diffuse pass cut too: more pieces than the lateral rates add to the
     * peripheral build (2 axes x 24 levels, 8 a piece: 6) and one. */
    assert_true(calls[DIFFUSE] - calls[PERIPHERAL] > 6 + 1);
    /* The compression cut: its four sweeps (the light's and the diffuse light's counts, then
     * their nodes) in more than a piece each. */
    assert_true(calls[COMPRESSED] - calls[DIFFUSE] > 4);
    /* The diffuse light volume's solve cut: more pieces than its source and system and one. */
    assert_true(calls[VOLUME] - calls[PERIPHERAL] > 2);
}

/* The macro cells in pieces of 4 layers, and of 4 layers and 4 rows (the storm 72 voxels high:
 * 9 layers of cells): the same cells as built whole, on even levels and on the model's own. */
static void test_cells_pieces_match_whole(void **state)
{
    (void)state;
    struct config cfg;
    struct ext_volume vol = {0};
    const char *tall[] = {"scene.size=[48,48,72]"};
    test_config_from(&cfg, tall, 1);
    test_upload_scene(renderer, &cfg, &vol);
    int calls = compare_cells(0);
    print_message("cells: %d pieces\n", calls);
    assert_true(calls > 2); /* 9 layers: 3 pieces of level 0, then the coarser levels */
    /* 4 rows of cells a piece too (12 rows: 3 pieces for each of the 5 pieces above but the
     * last, the coarser levels'). */
    assert_int_equal(compare_cells(4), 3 * (calls - 1) + 1);
    ext_volume_finish(&vol);
}

/* On the model's own levels (the slices sample through the height table). */
static void test_pieces_match_whole_native_levels(void **state)
{
    (void)state;
    char path[512], files[600];
    snprintf(path, sizeof(path), "%s", test_tmp_path("thin_pieces.nc"));
    assert_true(thin_layer_write(path));
    snprintf(files, sizeof(files), "data.files=[\"%s\"]", path);
    const char *levels[] = {"scene.kind=data", files, "data.vertical=native",
                            "lightmap.resolution=[16,16,64]", "light.elevation=30"};
    assert_true(compare(levels, 5, DIFFUSE) > 20);
    assert_true(compare_cells(0) >= 2);
    assert_true(compare_cells(4) >= 2);
    remove(path);
}

/* A budget holds several pieces; a one-piece build drops a build under way. */
static void test_budget_and_drop(void **state)
{
    (void)state;
    struct config cfg;
    struct ext_volume vol = {0};
    test_config_from(&cfg, storm, 2);
    test_upload_scene(renderer, &cfg, &vol);
    struct light_settings s;
    settings_for(&cfg, DIFFUSE, &s);
    double sun[3];
    light_sun_direction(cfg.light.azimuth_deg, cfg.light.elevation_deg, sun);
    struct light_gpu_source src = {renderer_volume_texture(renderer), renderer_grid(renderer), 1,
                                   1, renderer_cells(renderer)};
    struct light_gpu *lg = light_gpu_create();
    assert_non_null(lg);
    bool needed, done = false;
    assert_true(light_gpu_build_begin(lg, &src, sun, &s, LIGHT_GPU_DENSE, &needed));
    assert_true(light_gpu_build_step(lg, 0.0, &done));
    assert_false(done);
    /* The map held before is gone from the start: nothing to sample. */
    float beam, diffuse[2];
    bool have = false;
    const double p[3] = {0.0, 0.0, 1000.0};
    assert_false(light_gpu_sample(lg, p, &beam, diffuse, &have));
    bool built = false;
    assert_true(light_gpu_update(lg, &src, sun, &s, LIGHT_GPU_DENSE, &built));
    assert_true(built);
    assert_false(light_gpu_building(lg));
    /* A generous budget: all of it in one call. */
    src.volume_id = 2;
    assert_true(light_gpu_build_begin(lg, &src, sun, &s, LIGHT_GPU_DENSE, &needed));
    assert_true(needed);
    assert_true(light_gpu_build_step(lg, 1e9, &done));
    assert_true(done);
    assert_int_equal(light_gpu_builds(lg), 2);
    light_gpu_destroy(lg);
    ext_volume_finish(&vol);
}

int main(void)
{
    log_set_level(LOG_WARN);
    ctx = test_gl_context_or_skip();
    renderer = renderer_create();
    if (!renderer)
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pieces_match_whole),
        cmocka_unit_test(test_pieces_match_whole_native_levels),
        cmocka_unit_test(test_cells_pieces_match_whole),
        cmocka_unit_test(test_budget_and_drop),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return rc;
}
