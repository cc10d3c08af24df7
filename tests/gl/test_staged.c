/* Staged playback: a run of a series readies the next step between frames (session_prepare),
 * so that the frame of a step change uploads nothing and builds no light map; the pictures
 * after each swap are those a session that uploads the step directly draws; the same with
 * effects.temporal (the blended pair) and with a layer's field and a slice beside the
 * extinction, which travel with the swap. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "common/log.h"
#include "config/config.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "render/render.h"
#include "session/frame.h"
#include "session/scene.h"
#include "session/session.h"

static struct gpu_context *ctx;
static char series_cfg[1024], fields_cfg[1024];

static struct display *open_display(const struct config *cfg, const struct display_config *dcfg)
{
    struct display_desc dd = {.offscreen = true, .context = ctx, .height = cfg->render.height};
    scene_camera(cfg, &dd.camera);
    struct display *d = display_create(dcfg, &dd);
    assert_non_null(d);
    assert_true(display_update(d, 0.0));
    return d;
}

/* A run's session.  The reference the pictures are compared with is one too (the same effects
 * decided) that is never given the time between frames: every step it shows it uploads and
 * builds in the frame. */
static struct session *make(const struct config *cfg, const struct display_config *dcfg,
                            bool interactive)
{
    int rc;
    struct session *s = session_create(cfg,
                                       &(struct session_desc){
                                           .command = interactive ? "run" : "render",
                                           .display = dcfg,
                                           .views_move = true,
                                           .interactive = interactive,
                                           .playback = true,
                                           .probe = true, /* as anvil run has it */
                                       },
                                       &rc);
    assert_non_null(s);
    return s;
}

struct counts {
    uint64_t bytes;
    unsigned builds, uploads, swaps;
};

static void counts_of(struct session *s, struct counts *c)
{
    c->bytes = renderer_stats(session_renderer(s))->upload_bytes;
    c->builds = session_stats(s)->light_builds;
    c->uploads = session_stats(s)->volume_uploads;
    c->swaps = session_stats(s)->volume_swaps;
}

/* What the macro cells of the step just swapped in show, against the GPU's build of them. */
struct cells_seen {
    float *last; /* the last step's cells */
    size_t last_count;
    int differ_step;   /* step changes whose cells differ from the step's before */
    int differ_border; /* steps whose cells without the voxels around each cell would differ */
};

/* The swapped-in step's cells on R (made by the stage's CPU or by the GPU in pieces) are the
 * GPU's whole build from the step's texture, bit for bit. */
static void check_step_cells(struct renderer *r, const struct render_cells_programs *p,
                             struct cells_seen *seen)
{
    const struct render_cells *have = renderer_cells(r);
    struct render_cells want = {0};
    assert_true(render_cells_build(&want, p, renderer_volume_texture(r), NULL, renderer_grid(r)));
    assert_int_equal(have->count, want.count);
    assert_memory_equal(have->dims, want.dims, sizeof(want.dims));
    float *got = render_cells_read(have), *gpu = render_cells_read(&want);
    assert_non_null(got);
    assert_non_null(gpu);
    size_t bytes = want.count * sizeof(float);
    if (memcmp(got, gpu, bytes) != 0)
        fail_msg("step cells: the staged step's macro cells are not the GPU's of its texture");
    if (seen->last && seen->last_count == want.count && memcmp(seen->last, gpu, bytes) != 0)
        seen->differ_step++;
    /* The step's extinction read back: its cells without the border are other cells. */
    struct ext_volume vol = {0};
    assert_true(ext_volume_init(&vol, renderer_grid(r)));
    gpu_texture_read(renderer_volume_texture(r), vol.beta,
                     2 * grid3_count(renderer_grid(r)) * sizeof(float));
    struct render_cells layout;
    float *no_border = render_cells_cpu(&vol, NULL, 0, &layout);
    assert_non_null(no_border);
    seen->differ_border += memcmp(no_border, gpu, bytes) != 0;
    free(no_border);
    ext_volume_finish(&vol);
    free(seen->last);
    seen->last = gpu;
    seen->last_count = want.count;
    free(got);
    render_cells_finish(&want);
}

/* Plays the series through on a run's session, frame by frame with the preparation between
 * frames, and checks every step change; each new step's picture is compared with the
 * reference's of the same frame state, and its macro cells with the GPU's build of them:
 * made by the stage on the CPU, or with GPU_CELLS by the GPU in pieces.  Returns the step
 * changes seen; *MOVED counts the frames whose picture changed while the step did not (the
 * blend). */
static int play_cells(const char *path, const char *const *sets, int n_sets, bool gpu_cells,
                      int *moved)
{
    struct config cfg;
    const char *base[8] = {"render.width=40", "render.height=30",
                           "lightmap.resolution=[16,16,16]", "overlay.when=\"never\""};
    int n = 4;
    for (int i = 0; i < n_sets; i++)
        base[n++] = sets[i];
    test_config_file(&cfg, path, base, n);
    struct display_config dcfg;
    display_config_defaults(&dcfg);
    dcfg.type = DISPLAY_TYPE_ORBIT;
    dcfg.window_size[0] = cfg.render.width;
    dcfg.window_size[1] = cfg.render.height;
    struct display *da = open_display(&cfg, &dcfg), *db = open_display(&cfg, &dcfg);
    struct session *a = make(&cfg, &dcfg, true), *b = make(&cfg, &dcfg, true);
    struct renderer *ra = session_renderer(a);
    renderer_set_stage_cpu_cells(ra, !gpu_cells);
    bool half = cfg.render.precision == PRECISION_HALF;
    struct render_cells_programs programs;
    assert_true(render_cells_programs_init(&programs));
    struct cells_seen seen = {0};
    unsigned cpu_cells = renderer_stats(ra)->cpu_cells;
    session_set_playing(a, true);
    struct counts before, after, start;
    counts_of(a, &start);
    int changes = 0, shown = session_step_shown(a);
    struct image prev = {0};
    *moved = 0;
    for (int frame = 0; frame < 400 && shown < session_step_count(a) - 1; frame++) {
        struct frame_state f;
        bool redraw;
        assert_true(session_update(a, NULL, 0.1, 0.1 * frame, &f, &redraw));
        counts_of(a, &before);
        assert_true(session_apply(a, &f, NULL) && session_light(a) &&
                    display_sample_head(da, f.time_s, &f.head) && session_draw(a, da, &f));
        counts_of(a, &after);
        if (frame > 0) {
            /* No frame uploads or builds (the sun stands still): all of it is between
             * frames. */
            assert_int_equal(after.bytes, before.bytes);
            assert_int_equal(after.builds, before.builds);
        }
        struct image now;
        assert_true(renderer_read(&display_view(da, 0)->target, &now));
        size_t image_bytes = sizeof(float) * 4 * (size_t)now.width * (size_t)now.height;
        if (prev.rgba && session_step_shown(a) == shown &&
            memcmp(prev.rgba, now.rgba, image_bytes) != 0)
            (*moved)++;
        image_finish(&prev);
        prev = now;
        if (frame == 0 || session_step_shown(a) != shown) {
            /* The frame of the step change: a swap of what was readied between frames. */
            if (frame > 0) {
            shown = session_step_shown(a);
            changes++;
            assert_int_equal(after.bytes, before.bytes);
            assert_int_equal(after.builds, before.builds);
            assert_int_equal(after.uploads, before.uploads);
            assert_int_equal(after.swaps, before.swaps + 1);
            /* Its cells were made between frames: by the CPU unless asked otherwise. */
            unsigned made = renderer_stats(ra)->cpu_cells;
            assert_true(gpu_cells || half ? made == cpu_cells : made > cpu_cells);
            cpu_cells = made;
            }
            check_step_cells(ra, &programs, &seen);
            /* The same picture as a session that uploads and builds that step itself. */
            struct frame_state g = f;
            for (int k = 0; k < 500 && session_step_shown(b) != session_step_shown(a); k++) {
                assert_true(session_apply(b, &g, NULL));
                usleep(2000);
            }
            assert_true(session_apply(b, &g, NULL) && session_light(b) &&
                        session_draw(b, db, &g));
            assert_int_equal(session_step_shown(b), shown);
            struct image ia, ib;
            assert_true(renderer_read(&display_view(da, 0)->target, &ia));
            assert_true(renderer_read(&display_view(db, 0)->target, &ib));
            size_t bytes = sizeof(float) * 4 * (size_t)ia.width * (size_t)ia.height;
            if (memcmp(ia.rgba, ib.rgba, bytes) != 0)
                fail_msg("step %d: the swapped-in step draws another picture", shown);
            image_finish(&ia);
            image_finish(&ib);
        }
        /* Between frames: until nothing is in flight (the copy runs on its own thread), so
         * that the next frame finds the step readied however loaded the machine is: the
         * blend then shows between step changes. */
        for (int k = 0; k < 5000; k++) {
            bool more = false;
            assert_true(session_prepare(a, &more));
            if (!more)
                break;
            usleep(2000);
        }
    }
    assert_int_equal(shown, session_step_count(a) - 1); /* played to the end */
    image_finish(&prev);
    /* The cells' check would see cells of the step before, or without their border. */
    assert_true(seen.differ_step > 0);
    assert_true(seen.differ_border > 0);
    free(seen.last);
    render_cells_programs_finish(&programs);
    /* The uploads and builds did happen, between frames. */
    counts_of(a, &after);
    assert_true(after.bytes > start.bytes);
    assert_true(after.builds > start.builds);
    session_destroy(a);
    session_destroy(b);
    display_destroy(da);
    display_destroy(db);
    return changes;
}

static int play(const char *path, const char *const *sets, int n_sets, int *moved)
{
    return play_cells(path, sets, n_sets, false, moved);
}

static void test_plain(void **state)
{
    (void)state;
    int moved;
    const char *sets[] = {"effects.temporal=\"off\""};
    assert_int_equal(play(series_cfg, sets, 1, &moved), 3);
    assert_int_equal(moved, 0); /* one picture per step */
}

/* The same played with the staged cells built by the GPU, and in half floats (where the
 * GPU builds them from the rounded values). */
static void test_plain_gpu_cells(void **state)
{
    (void)state;
    int moved;
    const char *sets[] = {"effects.temporal=\"off\""};
    assert_int_equal(play_cells(series_cfg, sets, 1, true, &moved), 3);
    assert_int_equal(moved, 0);
}

static void test_half(void **state)
{
    (void)state;
    int moved;
    const char *sets[] = {"effects.temporal=\"on\"", "render.precision=\"half\""};
    assert_int_equal(play(series_cfg, sets, 2, &moved), 3);
    assert_true(moved > 0);
}

static void test_temporal(void **state)
{
    (void)state;
    const char *sets[] = {"effects.temporal=\"on\""};
    int moved;
    assert_int_equal(play(series_cfg, sets, 1, &moved), 3);
    assert_true(moved > 0); /* the staged next step is blended in between step changes */
}

static void test_fields(void **state)
{
    (void)state;
    int moved;
    const char *sets[] = {"effects.temporal=\"off\""};
    assert_int_equal(play(fields_cfg, sets, 1, &moved), 3);
    assert_int_equal(moved, 0);
}

/* The renderer's stage alone: a volume copied on the stage's thread, uploaded in slabs of a
 * budget (several calls), swapped in: the texture holds the volume exactly (in half floats,
 * clamped to their largest value), and the call that finishes the upload is the first to say
 * ready. */
static void stage_in_slabs(bool half, bool paced)
{
    struct renderer *r = renderer_create();
    assert_non_null(r);
    renderer_set_half(r, half);
    renderer_set_stage_paced(r, paced);
    struct grid3 g = {.n = {12, 10, 9}, .spacing = {1.0, 1.0, 1.0}};
    struct ext_volume first = {0}, vol = {0};
    assert_true(ext_volume_init(&first, &g) && ext_volume_init(&vol, &g));
    size_t n = grid3_count(&g);
    for (size_t i = 0; i < 2 * n; i++)
        vol.beta[i] = 1e-4f * (float)(i % 977) + (i == 5 ? 1e6f : 0.0f);
    vol.tint = malloc(4 * n);
    assert_non_null(vol.tint);
    memset(vol.tint, 200, 4 * n);
    assert_true(renderer_set_volume(r, &first));
    bool started = false, ready = false;
    float *also = malloc(2 * n * sizeof(float));
    assert_non_null(also);
    assert_true(renderer_stage_next(r, &vol, also, &started));
    assert_true(started);
    assert_false(renderer_has_next(r));
    const size_t layer = (size_t)12 * 10 * 8; /* one z layer of RG32F */
    int calls = 0, slices = 0;
    for (int k = 0; k < 10000 && !ready; k++) {
        bool copying = renderer_stage_copying(r);
        assert_true(renderer_stage_step(r, 2 * layer, &ready));
        if (!ready && renderer_stage_busy(r))
            calls++;
        slices += copying && paced;
        usleep(paced ? 0 : 200);
    }
    assert_true(ready);
    assert_true(calls >= 9 / 2); /* the extinction alone takes five calls of two layers */
    /* Paced: the copy itself went in slices of about the budget (20 bytes a voxel with the
     * tint and the CPU copy: 96 voxels a slice, 12 slices, then the call that moves on). */
    if (paced)
        assert_int_equal(slices, 13);
    assert_true(renderer_swap_next(r));
    assert_false(renderer_swap_next(r)); /* nothing staged any more */
    float *back = malloc(2 * n * sizeof(float));
    assert_non_null(back);
    gpu_texture_read(renderer_volume_texture(r), back, 2 * n * sizeof(float));
    for (size_t i = 0; i < 2 * n; i++) {
        float want = vol.beta[i] > RENDER_HALF_MAX && half ? RENDER_HALF_MAX : vol.beta[i];
        if (half)
            assert_float_equal(back[i], want, 1e-3f * want + 1e-7f);
        else
            assert_true(back[i] == want);
    }
    assert_memory_equal(also, vol.beta, 2 * n * sizeof(float)); /* the CPU copy, unclamped */
    free(also);
    free(back);
    ext_volume_finish(&first);
    ext_volume_finish(&vol);
    renderer_destroy(r);
}

static void test_stage_floats(void **state)
{
    (void)state;
    stage_in_slabs(false, false);
}

static void test_stage_half(void **state)
{
    (void)state;
    stage_in_slabs(true, false);
}

/* The copy in slices between frames (as on a software driver): the same volume. */
static void test_stage_paced_floats(void **state)
{
    (void)state;
    stage_in_slabs(false, true);
}

static void test_stage_paced_half(void **state)
{
    (void)state;
    stage_in_slabs(true, true);
}

/* The pair's cells (effects.temporal) in pieces of 4 layers, as session_prepare makes them:
 * the same cells as made whole, and more than one piece. */
static void test_pair_cells_pieces(void **state)
{
    (void)state;
    struct renderer *r = renderer_create();
    assert_non_null(r);
    struct grid3 g = {.n = {20, 12, 40}, .spacing = {1.0, 1.0, 1.0}};
    struct ext_volume a = {0}, b = {0};
    assert_true(ext_volume_init(&a, &g) && ext_volume_init(&b, &g));
    size_t n = grid3_count(&g);
    for (size_t i = 0; i < n; i++) { /* cells empty in one, the other or neither */
        a.beta[2 * i] = (i / 97) % 3 == 0 ? 0.0f : 1e-3f * (float)(i % 89);
        b.beta[2 * i + 1] = (i / 53) % 4 == 0 ? 0.0f : 2e-3f * (float)(i % 71);
    }
    assert_true(renderer_set_volume(r, &a));
    assert_true(renderer_set_next_volume(r, &b));
    assert_false(renderer_pair_cells_ready(r));
    bool done = false;
    int pieces = 0;
    while (!done && pieces < 100) {
        assert_true(renderer_pair_cells_step(r, 4, &done));
        pieces++;
    }
    assert_true(done);
    assert_true(renderer_pair_cells_ready(r));
    assert_int_equal(pieces, 4); /* 10 layers of cells: 4, 4, 2, then the coarser levels */
    const struct render_cells *c = renderer_pair_cells(r); /* made: not made again */
    assert_non_null(c);
    size_t count = c->count;
    float *in_pieces = render_cells_read(c);
    assert_non_null(in_pieces);
    assert_true(renderer_set_next_volume(r, &b)); /* stale again: made whole */
    assert_false(renderer_pair_cells_ready(r));
    c = renderer_pair_cells(r);
    assert_non_null(c);
    assert_int_equal(c->count, count);
    float *whole = render_cells_read(c);
    assert_non_null(whole);
    assert_memory_equal(in_pieces, whole, count * sizeof(float));
    bool nonzero = false;
    for (size_t i = 0; i < count; i++)
        nonzero |= whole[i] > 0.0f;
    assert_true(nonzero);
    free(in_pieces);
    free(whole);
    ext_volume_finish(&a);
    ext_volume_finish(&b);
    renderer_destroy(r);
}

/* With a staged next volume (its own cells made) on the grid shown: the pair's cells in one
 * piece from the two volumes' cells, the same as made whole from the volumes. */
static void test_pair_cells_from_cells(void **state)
{
    (void)state;
    struct renderer *r = renderer_create();
    assert_non_null(r);
    struct grid3 g = {.n = {20, 12, 40}, .spacing = {1.0, 1.0, 1.0}};
    struct ext_volume a = {0}, b = {0};
    assert_true(ext_volume_init(&a, &g) && ext_volume_init(&b, &g));
    size_t n = grid3_count(&g);
    for (size_t i = 0; i < n; i++) {
        a.beta[2 * i] = (i / 97) % 3 == 0 ? 0.0f : 1e-3f * (float)(i % 89);
        b.beta[2 * i + 1] = (i / 53) % 4 == 0 ? 0.0f : 2e-3f * (float)(i % 71);
    }
    assert_true(renderer_set_volume(r, &a));
    bool started = false, ready = false;
    assert_true(renderer_stage_next(r, &b, NULL, &started));
    assert_true(started);
    for (int k = 0; k < 10000 && !ready; k++) {
        assert_true(renderer_stage_step(r, 0, &ready));
        usleep(200);
    }
    assert_true(ready);
    bool done = false;
    assert_true(renderer_pair_cells_step(r, 4, &done));
    assert_true(done); /* one piece */
    const struct render_cells *c = renderer_pair_cells(r);
    assert_non_null(c);
    float *from_cells = render_cells_read(c);
    assert_non_null(from_cells);
    struct render_cells_programs p;
    assert_true(render_cells_programs_init(&p));
    struct render_cells whole = {0};
    assert_true(render_cells_build(&whole, &p, renderer_volume_texture(r), renderer_next_texture(r),
                                   renderer_grid(r)));
    assert_int_equal(whole.count, c->count);
    float *want = render_cells_read(&whole);
    assert_non_null(want);
    assert_memory_equal(from_cells, want, whole.count * sizeof(float));
    free(from_cells);
    free(want);
    render_cells_finish(&whole);
    render_cells_programs_finish(&p);
    ext_volume_finish(&a);
    ext_volume_finish(&b);
    renderer_destroy(r);
}

/* The upload slab session_prepare asks for: what fits into the time left at the last slab's
 * rate, within 4 and 64 MiB. */
static void test_slab_bytes(void **state)
{
    (void)state;
    const size_t mib = (size_t)1 << 20;
    assert_int_equal(session_slab_bytes(0.0, 100.0), 4 * mib);     /* no rate yet */
    assert_int_equal(session_slab_bytes(1e6, 0.0), 4 * mib);       /* no time left */
    assert_int_equal(session_slab_bytes(1e6, 20.0), (size_t)20e6); /* 1 MB a ms, 20 ms */
    assert_int_equal(session_slab_bytes(1e6, 1.0), 4 * mib);       /* at least 4 MiB */
    assert_int_equal(session_slab_bytes(1e7, 1000.0), 64 * mib);   /* at most 64 MiB */
}

static int setup(void **state)
{
    (void)state;
    ctx = test_gl_context_or_skip();
    const char *bin = getenv("ANVIL_BIN");
    char cmd[2048];
    snprintf(cmd, sizeof(cmd),
             "'%s' --quiet synth -o '%s' --steps 4 --size 16x16x8 --extent 16x16x8", bin,
             test_tmp_path("series.nc"));
    if (system(cmd) != 0)
        return -1;
    static const char text[] =
        "scene = { kind = \"data\"; };\n"
        "data = { format = \"wrf\"; files = [\"series.nc\"]; };\n"
        "playback = { speed = 5.0; loop = false; };\n"
        "camera = { position = [-6.0, -10.0, 6.0]; target = [8.0, 8.0, 3.0]; };\n";
    snprintf(series_cfg, sizeof(series_cfg), "%s", test_write_file("series.cfg", text));
    char fields[2048];
    snprintf(fields, sizeof(fields),
             "%slook = {\n"
             "    layers = ( { field = \"temperature\"; mode = \"tint\"; opacity = 1.0; } );\n"
             "    slices = ( { field = \"wind\"; axis = \"z\"; position = 3.0; "
             "opacity = 1.0; } );\n"
             "};\n",
             text);
    snprintf(fields_cfg, sizeof(fields_cfg), "%s", test_write_file("fields.cfg", fields));
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    gpu_context_destroy(ctx);
    return 0;
}

int main(void)
{
    log_set_level(LOG_WARN);
    if (!getenv("ANVIL_BIN")) {
        fprintf(stderr, "ANVIL_BIN is not set: the synthetic series cannot be written\n");
        return TEST_SKIP;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stage_floats),       cmocka_unit_test(test_stage_half),
        cmocka_unit_test(test_stage_paced_floats), cmocka_unit_test(test_stage_paced_half),
        cmocka_unit_test(test_pair_cells_pieces),  cmocka_unit_test(test_pair_cells_from_cells),
        cmocka_unit_test(test_slab_bytes),         cmocka_unit_test(test_plain),
        cmocka_unit_test(test_plain_gpu_cells),    cmocka_unit_test(test_half),
        cmocka_unit_test(test_temporal),           cmocka_unit_test(test_fields),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
